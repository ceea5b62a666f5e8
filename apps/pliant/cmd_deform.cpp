// pliant deform VOLUME [--series UID] --driver wave|twist|bubble|rotate [driver options]
//               [--cells B] [--full-box] [--mesh FILE.node] [--stiffness K] [--substeps N]
//               [--damping D] [--frames N] [--fps F] -o OUT [--render OUT.mp4] [--tf …]
//               [--size WxH] [--camera AZ,EL,DIST] [--step S] [--max-memory MIB]
//               [--mesh-out MESH.vtu] [--checkpoint-every N] [--resume] [--json]
//               [--shading] [--resample exact|map] [--no-pipeline]
//
// The deformable-volume pipeline of Park & Kye 2022 on a volume file: a tet grid over it
// (pbd::build_tet_grid: cells of B³ voxels, 5 tets each, only cells near visible voxels unless
// --full-box; or a TetGen mesh with --mesh), deformed by the XPBD soft body (pbd::SoftBody) under
// one driver for N frames of 1/fps seconds, then resampled back into a grid like the source
// (volume::Resampler) and written to OUT (any writable volume format, io/volume_io.hpp). With
// --render, every frame is ray-cast into an MP4 at --fps through its inverse map
// (render::MappedRayCaster: no resample per frame), or with --resample exact resampled and
// ray-cast (render::RayCaster); OUT is the exact resample either way. --shading shades the frames.
// With
// --render the next frame is stepped while the current one renders (pipeline/frame_pipeline.hpp;
// the same bytes); --no-pipeline runs the stages one after the other.
// VOLUME may be a DICOM folder (--series UID picks a series, default the largest); an oblique
// volume is resampled to an axis-aligned grid first (one info line on stderr).
//
// Drivers (pbd/drivers.hpp; lengths in box units, fractions of the volume's largest side):
//   rotate  --axis x|y|z --angle DEG        rigid rotation about the volume's centre (testing)
//   twist   --axis x|y|z --angle DEG --grip G   the slab of the body within G of the box's max
//           face turned against the slab at its min face (G = 0.1: the ends of a rounded body,
//           a head, are held, not just its extreme points)
//   wave    --axis x|y|z (propagation) --displacement-axis x|y|z --amplitude A --wavelength W
//           --speed S (box units per second)
//   bubble  --center X,Y,Z (box coordinates) --radius R --inflation F
//   --ramp S  seconds over which the driver reaches full strength; default: the whole run for
//           rotate and twist (the last frame shows the full angle), the driver's own otherwise.
// An option of another driver is a usage error (exit 2).
//
// stdout: a summary, or with --json deform_run.hpp's object (docs/formats.md): output, render,
// still, mesh_output, driver, frames, substeps, stiffness, vertices, tets, active_cells,
// ms_per_substep, step_ms, resample_ms, render_ms, ms_per_frame (means over frames), volume_ratio
// and inverted_tets (last frame), min_volume_ratio, max_volume_ratio, max_inverted_tets (over
// frames), tets_skipped, voxels_written (last resampling).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "option_values.hpp"
#include "pliant/io/transfer_function_json.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pbd/drivers.hpp"
#include "pliant/pipeline/deform_run.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "progress_bar.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct DeformCommandOptions {
    std::string volume;
    std::string series;
    std::string driver;
    std::string axis;  // empty: z, for wave x
    std::string displacement_axis = "z";
    double angle = 90.0;
    double grip = 0.1;
    double amplitude = pbd::WaveDriver{}.amplitude;
    double wavelength = pbd::WaveDriver{}.wavelength;
    double speed = pbd::WaveDriver{}.speed;
    std::array<double, 3> center{0.5, 0.5, 0.5};
    double radius = pbd::BubbleDriver{}.radius;
    double inflation = pbd::BubbleDriver{}.inflation;
    double ramp = -1.0;  // < 0: the default of the driver
    int cells = 4;
    bool full_box = false;
    std::string mesh;
    double stiffness = 1.0;
    int substeps = pbd::SoftBodyOptions{}.substeps;
    double damping = pbd::SoftBodyOptions{}.damping;
    int frames = 48;
    double fps = 24.0;
    std::string out;
    std::string render;
    std::string mesh_out;
    std::string grid;
    std::string tf = "grayscale";
    std::string size = "512x512";
    double step = 0.0;
    std::array<double, 3> camera{30.0, 20.0, 0.0};
    double max_memory_mib = 0.0;  // 0: the memory available
    int checkpoint_every = pipeline::DeformRunOptions{}.checkpoint_every;
    bool resume = false;
    bool shading = false;
    std::string resample = "map";
    int thin_levels = pipeline::DeformRunOptions{}.thin_levels;
    bool no_pipeline = false;

    // The driver-specific options the user gave, for the usage check.
    std::vector<std::pair<const CLI::Option*, std::vector<std::string>>> driver_only;
};

pbd::Axis to_axis(const std::string& name) {
    return name == "x" ? pbd::Axis::x : (name == "y" ? pbd::Axis::y : pbd::Axis::z);
}

pbd::Driver make_driver(const DeformCommandOptions& o, double duration,
                        const Vec3d& volume_centre) {
    const pbd::Axis axis =
        o.axis.empty() ? (o.driver == "wave" ? pbd::Axis::x : pbd::Axis::z) : to_axis(o.axis);
    if (o.driver == "rotate") {
        return pbd::RotateDriver{.axis = axis,
                                 .angle = o.angle,
                                 .ramp_time = o.ramp >= 0.0 ? o.ramp : duration,
                                 .centre = volume_centre};
    }
    if (o.driver == "twist") {
        return pbd::TwistDriver{.axis = axis,
                                .angle = o.angle,
                                .ramp_time = o.ramp >= 0.0 ? o.ramp : duration,
                                .grip = o.grip};
    }
    if (o.driver == "wave") {
        pbd::WaveDriver wave{.direction = axis,
                             .displacement = to_axis(o.displacement_axis),
                             .amplitude = o.amplitude,
                             .wavelength = o.wavelength,
                             .speed = o.speed};
        if (o.ramp >= 0.0) {
            wave.ramp_time = o.ramp;
        }
        return wave;
    }
    pbd::BubbleDriver bubble{.centre = {o.center[0], o.center[1], o.center[2]},
                             .radius = o.radius,
                             .inflation = o.inflation};
    if (o.ramp >= 0.0) {
        bubble.ramp_time = o.ramp;
    }
    return bubble;
}

void run_deform_command(const DeformCommandOptions& options, const GlobalOptions& global) {
    // Usage checks across options (exit 2).
    for (const auto& [option, drivers] : options.driver_only) {
        if (option->count() > 0 &&
            std::find(drivers.begin(), drivers.end(), options.driver) == drivers.end()) {
            throw CLI::ValidationError(option->get_name(),
                                       fmt::format("applies to --driver {}, not {}",
                                                   fmt::join(drivers, "|"), options.driver));
        }
    }
    if (!options.mesh_out.empty() && !has_extension(options.mesh_out, ".vtu")) {
        throw CLI::ValidationError("--mesh-out",
                                   "expected a .vtu file name, got '" + options.mesh_out + "'");
    }
    if (!options.render.empty() && !has_extension(options.render, ".mp4")) {
        throw CLI::ValidationError("--render",
                                   "expected an .mp4 file name, got '" + options.render + "'");
    }
    pipeline::DeformRunOptions run;
    run.size = parse_size(options.size);

    io::ReadVolumeOptions read;
    run.max_memory_bytes = pipeline::memory_limit_bytes(options.max_memory_mib);
    if (run.max_memory_bytes > 0) {
        read.max_bytes = static_cast<std::size_t>(run.max_memory_bytes);
    }
    read.series_uid = options.series;
    read.grid = options.grid;
    const volume::Volume source = io::read_volume(options.volume, read);
    std::optional<volume::TransferFunction> tf;
    if (volume::channels(source.type()) != 4) {
        tf = io::load_transfer_function(options.tf, source);
        tf->validate();
    }

    run.driver_name = options.driver;
    run.driver = make_driver(options, options.frames / options.fps, source.bounds().center());
    run.grid.cell_voxels = options.cells;
    run.grid.full_box = options.full_box;
    run.mesh = options.mesh;
    run.body.stiffness = options.stiffness;
    run.body.substeps = options.substeps;
    run.body.damping = options.damping;
    run.frames = options.frames;
    run.fps = options.fps;
    run.out = options.out;
    run.video = options.render;
    run.mesh_out = options.mesh_out;
    run.camera = options.camera;
    run.step = options.step;
    run.shading = options.shading;
    run.resample = pipeline::parse_resample_mode(options.resample);
    run.thin_levels = options.thin_levels;
    run.progress = frame_progress(stderr_is_terminal() && !global.json);
    run.checkpoint_every = options.checkpoint_every;
    run.resume = options.resume;
    run.pipelined = !options.no_pipeline;
    const nlohmann::ordered_json result = pipeline::run_deform(source, tf ? &*tf : nullptr, run);

    if (global.json) {
        std::fputs((result.dump(2) + "\n").c_str(), stdout);
    } else {
        std::printf(
            "%s: %s, %d frames of %lld tets (%lld vertices): %.2f ms per substep, %.1f ms per "
            "resampling, volume ratio %.4f, %lld inverted tets%s%s\n",
            options.out.c_str(), options.driver.c_str(), options.frames,
            result["tets"].get<long long>(), result["vertices"].get<long long>(),
            result["ms_per_substep"].get<double>(), result["resample_ms"].get<double>(),
            result["volume_ratio"].get<double>(), result["inverted_tets"].get<long long>(),
            options.render.empty() ? "" : "; video ", options.render.c_str());
    }
}

}  // namespace

void register_deform(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<DeformCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "deform",
        "Deform a volume: tet grid, XPBD soft body under a driver, resampling (and a video)");
    cmd->add_option("VOLUME", options->volume,
                    "Volume file (NRRD, NIfTI, MetaImage, raw+JSON, .inv3) or a DICOM folder")
        ->required();
    cmd->add_option("--series", options->series,
                    "DICOM: the SeriesInstanceUID to read from a folder holding several (default: "
                    "the largest)")
        ->type_name("UID");
    cmd->add_option("--grid", options->grid,
                    "OpenVDB: the float grid to read (default: \"density\", else the only one)")
        ->type_name("NAME");
    cmd->add_option("--driver", options->driver, "Deformation driver")
        ->required()
        ->check(CLI::IsMember({"wave", "twist", "bubble", "rotate"}));
    const auto only = [&](CLI::Option* option, std::vector<std::string> drivers) {
        options->driver_only.emplace_back(option, std::move(drivers));
    };
    only(cmd->add_option("--axis", options->axis,
                         "rotate/twist: axis; wave: propagation axis (default z; wave: x)")
             ->check(CLI::IsMember({"x", "y", "z"})),
         {"rotate", "twist", "wave"});
    only(cmd->add_option("--displacement-axis", options->displacement_axis,
                         "wave: displacement axis (default z)")
             ->check(CLI::IsMember({"x", "y", "z"})),
         {"wave"});
    only(cmd->add_option("--angle", options->angle, "rotate/twist: angle in degrees (default 90)")
             ->check(finite_in_range(-1e6, 1e6)),
         {"rotate", "twist"});
    only(cmd->add_option("--grip", options->grip,
                         "twist: thickness of the two held slabs, box units (default 0.1)")
             ->check(finite_in_range(0.0, 0.49)),
         {"twist"});
    only(cmd->add_option("--amplitude", options->amplitude, "wave: amplitude, box units")
             ->check(finite_non_negative()),
         {"wave"});
    only(cmd->add_option("--wavelength", options->wavelength, "wave: wavelength, box units")
             ->check(finite_in_range(1e-6, 1e6)),
         {"wave"});
    only(cmd->add_option("--speed", options->speed, "wave: speed, box units per second")
             ->check(finite_in_range(-1e6, 1e6)),
         {"wave"});
    only(cmd->add_option("--center", options->center, "bubble: centre, box coordinates")
             ->type_name("X,Y,Z")
             ->delimiter(',')
             ->check(finite_in_range(-1e6, 1e6)),
         {"bubble"});
    only(cmd->add_option("--radius", options->radius, "bubble: radius, box units")
             ->check(finite_in_range(1e-6, 1e6)),
         {"bubble"});
    only(cmd->add_option("--inflation", options->inflation,
                         "bubble: rest-volume factor at the centre (> 1 inflates)")
             ->check(finite_in_range(1e-6, 1e6)),
         {"bubble"});
    cmd->add_option("--ramp", options->ramp,
                    "Seconds to reach full strength (default: the whole run for rotate and "
                    "twist, the driver's own otherwise)")
        ->check(finite_non_negative());
    CLI::Option* mesh =
        cmd->add_option("--mesh", options->mesh,
                        "TetGen mesh (.node/.ele) in the volume's world frame instead of a grid");
    cmd->add_option("--cells", options->cells, "Voxels per tet-grid cell side (default 4)")
        ->check(CLI::Range(1, 4096))
        ->excludes(mesh);
    cmd->add_flag("--full-box", options->full_box,
                  "Tets over the whole box, not only near visible voxels")
        ->excludes(mesh);
    cmd->add_option("--stiffness", options->stiffness, "PBD stiffness in (0, 1] (default 1)")
        ->check(finite_in_range(1e-6, 1.0));
    cmd->add_option("--substeps", options->substeps, "XPBD substeps per frame")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--damping", options->damping, "Velocity damping, 1/s")
        ->check(finite_non_negative());
    cmd->add_option("--frames", options->frames, "Frames to simulate (default 48)")
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("--fps", options->fps, "Frames per second (default 24)")
        ->check(finite_in_range(1e-3, 1e4));
    cmd->add_option("-o,--output", options->out, "Deformed volume of the last frame")
        ->required()
        ->check(non_empty_path());
    cmd->add_option("--render", options->render, "MP4 of every frame, ray-cast");
    cmd->add_option("--mesh-out", options->mesh_out,
                    "Deformed tet mesh of the last frame, VTK XML .vtu (ParaView)");
    cmd->add_option("--tf", options->tf,
                    "Transfer function (preset or JSON) for scalar volumes: rendering, and which "
                    "voxels are visible for the grid (default grayscale)");
    cmd->add_option("--size", options->size, "Video size (default 512x512)")->type_name("WxH");
    cmd->add_option("--step", options->step,
                    "Video: ray-casting step, world units (default 0: half the smallest spacing)")
        ->check(finite_non_negative());
    cmd->add_option("--camera", options->camera,
                    "Video camera: azimuth, elevation (degrees), distance (0 = frame the box)")
        ->type_name("AZ,EL,DIST")
        ->delimiter(',')
        ->check(finite_in_range(-1e6, 1e6));
    cmd->add_flag("--shading", options->shading, "Video: gradient (headlight) shading");
    cmd->add_option("--resample", options->resample,
                    "Video: render each frame through its inverse map without resampling (map, "
                    "default) or from its exact resample (exact)")
        ->check(CLI::IsMember({"exact", "map"}));
    cmd->add_option("--thin-levels", options->thin_levels,
                    "Video through the map, an rgba8 volume: faint haze sampled once per 2^N "
                    "steps, N = 0 (every step), 1 or 2 (default 2)")
        ->check(CLI::Range(0, 2));
    cmd->add_flag("--no-pipeline", options->no_pipeline,
                  "Video: step each frame after the last one rendered, not while it renders "
                  "(the same output)");
    add_max_memory_option(*cmd, options->max_memory_mib, "a volume and tet grid that need");
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->add_option("--checkpoint-every", options->checkpoint_every,
                    "Save OUT.checkpoint.bin every N frames (0: never; not with --render; "
                    "default " +
                        std::to_string(options->checkpoint_every) + ")")
        ->check(CLI::Range(0, 1'000'000));
    cmd->add_flag("--resume", options->resume,
                  "Continue from OUT.checkpoint.bin (the same output as an uninterrupted run); "
                  "without one, start from frame 0");
    cmd->callback([options, &global] { run_deform_command(*options, global); });
}

}  // namespace pliant::cli
