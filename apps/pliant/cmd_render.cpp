// pliant render VOLUME [--series UID] [--tf FILE|PRESET] [--view AXIS | --camera AZ,EL,DIST]
// [--size WxH]
//               [--axis-aligned] [--step S] [--opacity-unit U] [--background R,G,B] [--mip]
//               [--shading]
//               [--clip PX,PY,PZ,NX,NY,NZ]
//               -o OUT.png | --orbit N -o OUT.mp4   [--max-memory MIB] [--json]
//
// Ray-casts a volume file (io/volume_io.hpp: NRRD, NIfTI, MetaImage, raw + JSON, .inv3, a DICOM
// folder or file) with render::RayCaster (render/raycast.hpp) and writes a PNG, or with --orbit N
// an MP4 turntable of N frames around +z (azimuth advancing 360°/N per frame, 24 frames per
// second) through ffmpeg. An oblique volume (a grid turned in the world, a tilted scan) is
// rendered as it lies, in world space (render/raycast.hpp, "Oriented volumes"); cameras frame its
// world box (Volume::world_bounds).
//   --axis-aligned  resample an oblique volume onto an axis-aligned grid first instead
//                 (io::Orientation::axis_aligned: trilinear, one info line on stderr).
//   --series UID  the DICOM series to read when the folder holds several (default: the largest).
//   --tf          a preset name (ct-bone, ct-skin, mri-brain, grayscale) or a transfer function
//                 JSON file (docs/formats.md); default grayscale. Ignored for RGBA volumes.
//   --view AXIS   orthographic, looking along ±x/±y/±z, the volume's world box filling the image
//                 (render::view_camera); without --size the longer side is 512 pixels and the
//                 other follows the box's aspect.
//   --camera      perspective from azimuth, elevation (degrees, render::frame_box's convention)
//                 and distance from the box's centre (world units; 0 = frame the box). Default
//                 30,20,0.
//   --step        sampling step in world units (default: half the smallest spacing).
//   --opacity-unit  world units RGBA opacities and unit-less transfer functions are per
//                 (default: the smallest spacing).
//   --clip PX,PY,PZ,NX,NY,NZ  a clipping plane through the point with the normal (world units):
//                 only the normal's side is rendered (render::ClipPlane).
//   --max-memory  MiB the volume, the ray caster's tables and the image may take (default: the
//                 memory available); more is refused before allocating
//                 (pipeline/memory_budget.hpp).
// stdout: a one-line summary, or with --json one object: output, width, height, frames, step,
// opacity_unit, prepare_ms, ms_per_frame (mean time of RayCaster::render), samples (per frame,
// mean over frames).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "option_values.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/transfer_function_json.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct RenderCommandOptions {
    std::string volume;
    std::string series;
    std::string tf = "grayscale";
    std::string view;
    std::array<double, 3> camera{30.0, 20.0, 0.0};
    std::string size;
    double step = 0.0;
    double opacity_unit = 0.0;
    std::array<float, 3> background{0.0f, 0.0f, 0.0f};
    bool mip = false;
    bool shading = false;
    std::array<double, 6> clip{};
    bool has_clip = false;
    std::string out;
    int orbit = 0;
    bool axis_aligned = false;
    double max_memory_mib = 0.0;  // 0: the memory available
};

void run_render(const RenderCommandOptions& options, const GlobalOptions& global) {
    // Usage checks that need several options (exit 2).
    if (options.orbit > 0 && !has_extension(options.out, ".mp4")) {
        throw CLI::ValidationError(
            "-o", "--orbit writes an MP4: the output must end in .mp4, got '" + options.out + "'");
    }
    if (options.orbit == 0 && !has_extension(options.out, ".png")) {
        throw CLI::ValidationError(
            "-o", "the output must end in .png (or .mp4 with --orbit), got '" + options.out + "'");
    }
    std::array<int, 2> size{512, 512};
    const bool has_size = !options.size.empty();
    if (has_size) {
        size = parse_size(options.size);
    }

    // Memory: the image before the volume is read, then everything before the caster allocates.
    // Without --size, --view's image is at most 512 pixels on a side.
    const std::uint64_t memory_limit = pipeline::memory_limit_bytes(options.max_memory_mib);
    pipeline::require_memory(fmt::format("render: a {}x{} image", size[0], size[1]),
                             pipeline::image_bytes(size[0], size[1]), memory_limit);
    io::ReadVolumeOptions read;
    read.series_uid = options.series;
    read.orientation = options.axis_aligned ? io::Orientation::axis_aligned : io::Orientation::keep;
    if (memory_limit > 0) {
        read.max_bytes = static_cast<std::size_t>(memory_limit);
    }
    const volume::Volume vol = io::read_volume(options.volume, read);
    pipeline::require_memory("render: " + pipeline::ray_cast_what(vol, size[0], size[1]),
                             pipeline::ray_cast_need_bytes(vol, size[0], size[1]), memory_limit);
    volume::TransferFunction tf;
    const bool is_rgba = volume::channels(vol.type()) == 4;
    if (!is_rgba) {
        tf = io::load_transfer_function(options.tf, vol);
    }
    render::RayCastOptions ro;
    ro.step = options.step;
    ro.opacity_unit = options.opacity_unit;
    ro.mode = options.mip ? render::RayCastMode::mip : render::RayCastMode::composite;
    ro.shading = options.shading;
    ro.background = {options.background[0], options.background[1], options.background[2]};
    if (options.has_clip) {
        const auto& c = options.clip;
        ro.clip = render::ClipPlane{{c[0], c[1], c[2]}, {c[3], c[4], c[5]}};
    }
    const render::RayCaster caster(vol, is_rgba ? nullptr : &tf, ro);

    const AABBd box = vol.world_bounds();
    const auto camera_for = [&](double azimuth) {
        if (!options.view.empty()) {
            return render::view_camera(box, render::parse_view_axis(options.view.c_str()), size[0],
                                       size[1]);
        }
        return render::orbit_camera(box, azimuth, options.camera[1], options.camera[2], size[0],
                                    size[1]);
    };
    if (!options.view.empty() && !has_size) {
        // Longer side 512 pixels, the other from the box's aspect as seen along the axis.
        const render::Camera probe = camera_for(0.0);
        const Vec3d e = box.extent();
        const auto along = [&](Vec3d v) {
            return std::fabs(v.x) * e.x + std::fabs(v.y) * e.y + std::fabs(v.z) * e.z;
        };
        const double aspect = along(probe.right()) / along(probe.up());
        size =
            aspect >= 1.0
                ? std::array<int, 2>{512, std::max(1, static_cast<int>(std::lround(512 / aspect)))}
                : std::array<int, 2>{std::max(1, static_cast<int>(std::lround(512 * aspect))), 512};
    }

    const int frames = options.orbit > 0 ? options.orbit : 1;
    double total_ms = 0.0;
    double total_samples = 0.0;
    render::Image image;
    if (options.orbit > 0) {
        io::VideoWriter video(options.out, size[0], size[1], 24.0);
        for (int f = 0; f < frames; ++f) {
            const render::RayCastStats stats =
                caster.render(camera_for(options.camera[0] + 360.0 * f / frames), image);
            total_ms += stats.ms;
            total_samples += static_cast<double>(stats.samples);
            video.write(image);
        }
        video.finish();
    } else {
        const render::RayCastStats stats = caster.render(camera_for(options.camera[0]), image);
        total_ms = stats.ms;
        total_samples = static_cast<double>(stats.samples);
        io::write_png(options.out, image);
    }

    const double ms_per_frame = total_ms / frames;
    const auto samples = static_cast<std::int64_t>(std::llround(total_samples / frames));
    if (global.json) {
        nlohmann::ordered_json j;
        j["output"] = options.out;
        j["width"] = size[0];
        j["height"] = size[1];
        j["frames"] = frames;
        j["step"] = caster.step();
        j["opacity_unit"] = caster.opacity_unit();
        j["prepare_ms"] = caster.prepare_ms();
        j["ms_per_frame"] = ms_per_frame;
        j["samples"] = samples;
        std::fputs((j.dump(2) + "\n").c_str(), stdout);
    } else {
        std::printf("%s: %d frame%s of %dx%d, %.1f ms per frame, %lld samples per frame\n",
                    options.out.c_str(), frames, frames == 1 ? "" : "s", size[0], size[1],
                    ms_per_frame, static_cast<long long>(samples));
    }
}

}  // namespace

void register_render(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<RenderCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Ray-cast a volume (NRRD, NIfTI, MetaImage, raw+JSON, .inv3, DICOM) to a PNG, or an MP4 "
        "turntable");
    cmd->add_option("VOLUME", options->volume, "Volume file, or a folder of DICOM files")
        ->required();
    cmd->add_option("--series", options->series,
                    "DICOM: the SeriesInstanceUID to read from a folder holding several (default: "
                    "the largest; pliant volume series DIR lists them)")
        ->type_name("UID");
    cmd->add_option("--tf", options->tf,
                    "Transfer function: a preset (ct-bone, ct-skin, mri-brain, grayscale) or a "
                    "JSON file; ignored for RGBA volumes");
    CLI::Option* view =
        cmd->add_option("--view", options->view,
                        "Orthographic view along an axis, the volume's box filling the image")
            ->check(CLI::IsMember({"+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"}));
    cmd->add_option("--camera", options->camera,
                    "Perspective camera: azimuth, elevation (degrees), distance from the centre "
                    "(world units, 0 = frame the box)")
        ->type_name("AZ,EL,DIST")
        ->delimiter(',')
        ->excludes(view)
        ->check(finite_in_range(-1e6, 1e6));
    cmd->add_option("--size", options->size, "Image size (default 512x512)")->type_name("WxH");
    cmd->add_option("--step", options->step,
                    "Sampling step, world units (default 0: half the smallest spacing)")
        ->check(finite_in_range(0.0, 1e30));
    cmd->add_option("--opacity-unit", options->opacity_unit,
                    "World units opacities are per (default 0: the smallest spacing)")
        ->check(finite_in_range(0.0, 1e30));
    cmd->add_option("--background", options->background, "Background colour, each in [0, 1]")
        ->type_name("R,G,B")
        ->delimiter(',')
        ->check(finite_in_range(0.0, 1.0));
    cmd->add_flag("--mip", options->mip, "Maximum intensity projection instead of compositing");
    cmd->add_flag("--shading", options->shading, "Gradient (headlight) shading");
    cmd->add_option("--clip", options->clip,
                    "Clipping plane through (PX,PY,PZ) with normal (NX,NY,NZ), world units: the "
                    "normal's side is rendered")
        ->type_name("PX,PY,PZ,NX,NY,NZ")
        ->delimiter(',')
        ->check(finite_in_range(-1e12, 1e12))
        ->each([options](const std::string&) { options->has_clip = true; });
    cmd->add_option("-o,--output", options->out, "Output PNG (or MP4 with --orbit)")
        ->required()
        ->check(non_empty_path());
    cmd->add_option("--orbit", options->orbit, "Turntable of N frames around +z (MP4)")
        ->check(CLI::Range(1, 100000))
        ->excludes(view);
    cmd->add_flag("--axis-aligned", options->axis_aligned,
                  "Resample an oblique volume onto an axis-aligned grid first (trilinear) instead "
                  "of rendering its grid as it lies");
    add_max_memory_option(*cmd, options->max_memory_mib, "a volume and image that need");
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_render(*options, global); });
}

}  // namespace pliant::cli
