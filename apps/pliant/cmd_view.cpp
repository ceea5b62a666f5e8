// pliant view cloth SCENE.json  [view options] [--substeps-per-frame S] [--check-every N]
// pliant view volume VOLUME      [view options] [--tf PRESET|FILE] [--opacity-scale S]
//                                [--threshold T] [--clip PX,PY,PZ,NX,NY,NZ] [--shading] [--step S]
//                                [--axis-aligned]
//                                [--preview-divisor D] [--deform [--driver none|wave|twist|bubble]
//                                [--stiffness K] [--cells B] [--substeps N] [--fps F]
//                                [--drag-radius R] [--resample exact|map] [--thin-levels N]]
//                                [--max-memory MIB]
// view options: [--size WxH] [--camera AZ,EL,DIST] [--frames N [--screenshot FILE.png]]
//               [--no-ui] [--paused] [--sync] [--msaa N]
//
// The interactive viewer (apps/viewer, GLFW + OpenGL 3.3 + Dear ImGui). `cloth` simulates a scene
// live as `pliant cloth` does (the same scene loading and solver) and draws the cloth and its
// obstacles shaded like the preview; the left button grabs a cloth vertex and drags it. `volume`
// shows the library's ray caster live, with transfer function presets, opacity scale, the
// cleaning threshold and a clipping plane; --deform adds the tet grid + XPBD soft body +
// rendering of `pliant deform`, drivers and mouse drag (each frame ray-cast through its inverse
// map, or with --resample exact resampled, as `pliant deform --resample`). An oblique
// volume is shown as it lies (as `pliant render`); --axis-aligned, and --deform (as `pliant
// deform`), resample it onto an axis-aligned grid first.
//   --camera AZ,EL,DIST  azimuth, elevation (degrees, render::frame_box's convention) and distance
//                 from the target (world units; 0 frames the scene), the camera of `pliant render
//                 --camera` (volume default 30,20,0; cloth default -60,25,0 as the cloth preview).
//   --frames N    stop after N frames (headless runs and measurements; vsync off); with
//                 --screenshot FILE.png the last frame is saved without the overlay (works under
//                 xvfb-run with Mesa).
// Errors: no display or no OpenGL 3.3 (exit 1, the message names the reason); a build without
// the viewer says so (exit 1).
// Frames are simulated a frame ahead in the background (the view shows the latest one and stays
// smooth however slow a step is); --sync locks each displayed frame to one simulated frame. stdout:
// a summary line, or with --json the run's object (docs/formats.md): frames, mean_frame_ms, fps,
// stage means, camera, gl_renderer.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "option_values.hpp"
#include "pliant/core/error.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "validators.hpp"
#include "view_options.hpp"
#ifdef PLIANT_HAS_VIEWER
#include "viewer.hpp"
#endif

namespace pliant::cli {
namespace {

struct ViewCommandOptions {
    std::string input;
    std::string size;
    std::array<double, 3> camera{0.0, 0.0, 0.0};
    bool has_camera = false;
    std::string screenshot;
    std::array<double, 6> clip{};
    std::string driver = "none";
    std::string resample = "map";
    bool no_ui = false;
};

// A view's window size and camera when the options are not given (shown in its --help).
struct ViewDefaults {
    std::array<double, 3> camera;  // azimuth, elevation (degrees), distance (0: frame the scene)
    std::array<int, 2> size;       // pixels
};
constexpr ViewDefaults CLOTH_VIEW_DEFAULTS{{-60.0, 25.0, 0.0}, {1280, 720}};
constexpr ViewDefaults VOLUME_VIEW_DEFAULTS{{30.0, 20.0, 0.0}, {512, 512}};

// The options both views take; fills run (size, camera, frames, screenshot, overlay, msaa).
void add_view_options(CLI::App* cmd, ViewCommandOptions& o, viewer::ViewRunOptions& run,
                      const ViewDefaults& defaults) {
    o.camera = defaults.camera;
    cmd->add_option("--size", o.size, "Window size in pixels")
        ->type_name("WxH")
        ->default_str(std::to_string(defaults.size[0]) + "x" + std::to_string(defaults.size[1]));
    cmd->add_option("--camera", o.camera,
                    "Camera: azimuth, elevation (degrees), distance from the target (0 = frame "
                    "the scene)")
        ->type_name("AZ,EL,DIST")
        ->delimiter(',')
        ->check(finite_in_range(-1e6, 1e6));
    CLI::Option* frames =
        cmd->add_option("--frames", run.frames, "Stop after N frames (headless runs, timing)")
            ->check(CLI::Range(1, 100'000'000));
    cmd->add_option("--screenshot", o.screenshot,
                    "Save the last frame (without the overlay) as a PNG; needs --frames")
        ->needs(frames);
    cmd->add_flag("--no-ui", o.no_ui, "Hide the overlay (stats and controls)");
    cmd->add_flag("--paused", run.paused, "Start with the simulation paused");
    cmd->add_flag("--sync", run.sync,
                  "Lock step: every displayed frame waits for one simulated frame (default: the "
                  "simulation runs a frame ahead in the background, the view shows its latest "
                  "frame)");
    cmd->add_option("--msaa", run.window.msaa_samples,
                    "Multisample anti-aliasing samples (0: off; -1: 4 on hardware OpenGL, off "
                    "on software renderers such as Mesa llvmpipe; cloth default -1, volume 0)")
        ->check(CLI::Range(-1, 16));
}

// After parsing: the size, camera, overlay and vsync into run; usage errors exit with 2.
void finish_view_options(const ViewCommandOptions& o, const ViewDefaults& defaults,
                         viewer::ViewRunOptions& run) {
    const std::array<int, 2> size = o.size.empty() ? defaults.size : parse_size(o.size);
    run.window.width = size[0];
    run.window.height = size[1];
    run.azimuth = o.camera[0];
    run.elevation = o.camera[1];
    run.distance = o.camera[2];
    if (!o.screenshot.empty() && !has_extension(o.screenshot, ".png")) {
        throw CLI::ValidationError("--screenshot",
                                   "expected a .png file name, got '" + o.screenshot + "'");
    }
    run.screenshot = o.screenshot;
    run.window.show_ui = !o.no_ui;
    run.window.vsync = run.frames <= 0;  // measurements and headless runs as fast as they go
}

#ifdef PLIANT_HAS_VIEWER
void print_summary(const nlohmann::ordered_json& result, const GlobalOptions& global) {
    if (global.json) {
        std::fputs((result.dump(2) + "\n").c_str(), stdout);
        return;
    }
    std::printf(
        "pliant view %s: %lld frames, %.1f fps (%.1f ms per frame)%s%s\n",
        result["view"].get<std::string>().c_str(),
        static_cast<long long>(result["frames"].get<std::int64_t>()), result["fps"].get<double>(),
        result["mean_frame_ms"].get<double>(),
        result["screenshot"].is_null() ? "" : ", screenshot ",
        result["screenshot"].is_null() ? "" : result["screenshot"].get<std::string>().c_str());
}
#endif

#ifndef PLIANT_HAS_VIEWER
[[noreturn]] void no_viewer() {
    throw Unsupported(
        "this pliant was built without the viewer: GLFW 3.3, OpenGL or Dear ImGui were not found "
        "when it was configured (install libglfw3-dev libgl-dev libimgui-dev, e.g. with "
        "scripts/install-deps, then reconfigure and rebuild)");
}
#endif

void run_view_cloth(const ViewCommandOptions& o, viewer::ClothViewOptions options,
                    const GlobalOptions& global) {
    finish_view_options(o, CLOTH_VIEW_DEFAULTS, options.run);
    const cloth::ClothScene scene = pipeline::read_cloth_scene(o.input);
#ifdef PLIANT_HAS_VIEWER
    print_summary(viewer::run_cloth_view(scene, o.input, options), global);
#else
    (void)scene;
    (void)global;
    no_viewer();
#endif
}

void run_view_volume(const ViewCommandOptions& o, viewer::VolumeViewOptions options,
                     const CLI::App* cmd, const GlobalOptions& global) {
    finish_view_options(o, VOLUME_VIEW_DEFAULTS, options.run);
    if (cmd->count("--clip") > 0) {
        options.session.clip =
            render::ClipPlane{{o.clip[0], o.clip[1], o.clip[2]}, {o.clip[3], o.clip[4], o.clip[5]}};
    }
    options.session.driver.kind = viewer::parse_driver_kind(o.driver);
    options.session.resample = pipeline::parse_resample_mode(o.resample);
    const bool deform_only = cmd->count("--driver") + cmd->count("--stiffness") +
                                 cmd->count("--cells") + cmd->count("--substeps") +
                                 cmd->count("--fps") + cmd->count("--drag-radius") +
                                 cmd->count("--resample") + cmd->count("--thin-levels") >
                             0;
    if (deform_only && !options.session.deform) {
        throw CLI::ValidationError("--deform",
                                   "--driver, --stiffness, --cells, --substeps, --fps, "
                                   "--drag-radius, --resample and --thin-levels apply with "
                                   "--deform only");
    }
#ifdef PLIANT_HAS_VIEWER
    print_summary(viewer::run_volume_view(o.input, options), global);
#else
    (void)global;
    no_viewer();
#endif
}

}  // namespace

void register_view(CLI::App& app, const GlobalOptions& global) {
    CLI::App* view = app.add_subcommand(
        "view", "Interactive viewer: cloth simulated live, volumes ray-cast live (OpenGL)");
    view->require_subcommand(1);

    // pliant view cloth
    auto cloth_o = std::make_shared<ViewCommandOptions>();
    auto cloth_options = std::make_shared<viewer::ClothViewOptions>();
    CLI::App* cloth = view->add_subcommand(
        "cloth", "Simulate a cloth scene live; grab the cloth with the left button");
    cloth->add_option("SCENE", cloth_o->input, "Scene file (JSON, see docs/formats.md)")
        ->required();
    add_view_options(cloth, *cloth_o, cloth_options->run, CLOTH_VIEW_DEFAULTS);
    cloth
        ->add_option("--substeps-per-frame", cloth_options->session.substeps_per_frame,
                     "Solver substeps per displayed frame (the speed; default 4, one "
                     "self-collision window)")
        ->check(CLI::Range(1, 1000));
    cloth
        ->add_option("--check-every", cloth_options->session.check_every,
                     "Frames between exact intersecting-pair counts (default 10)")
        ->check(CLI::Range(1, 1'000'000));
    cloth->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cloth->callback(
        [cloth_o, cloth_options, &global] { run_view_cloth(*cloth_o, *cloth_options, global); });

    // pliant view volume
    auto volume_o = std::make_shared<ViewCommandOptions>();
    auto volume_options = std::make_shared<viewer::VolumeViewOptions>();
    volume_options->run.window.msaa_samples = 0;  // an image on a quad: nothing to anti-alias
    CLI::App* vol = view->add_subcommand(
        "volume", "Ray-cast a volume live; --deform: deform it (drivers, mouse drag)");
    vol->add_option("VOLUME", volume_o->input,
                    "Volume file (NRRD, NIfTI, MetaImage, raw+JSON, .inv3) or a DICOM folder (its "
                    "largest series)")
        ->required();
    add_view_options(vol, *volume_o, volume_options->run, VOLUME_VIEW_DEFAULTS);
    viewer::VolumeSessionOptions& s = volume_options->session;
    vol->add_option("--tf", s.tf,
                    "Transfer function: a preset (ct-bone, ct-skin, mri-brain, grayscale) or a "
                    "JSON file; ignored for RGBA volumes");
    vol->add_option("--opacity-scale", s.opacity_scale,
                    "Opacity scale: opacities per opacity unit / S (default 1)")
        ->check(finite_in_range(1e-6, 1e6));
    vol->add_option("--threshold", s.threshold,
                    "Cleaning threshold on the 0-255 alpha scale (volume/clean.hpp; default 0)")
        ->check(finite_in_range(0.0, 255.0));
    vol->add_option("--clip", volume_o->clip,
                    "Clipping plane through (PX,PY,PZ) with normal (NX,NY,NZ), world units: the "
                    "normal's side is shown")
        ->type_name("PX,PY,PZ,NX,NY,NZ")
        ->delimiter(',')
        ->check(finite_in_range(-1e12, 1e12));
    vol->add_flag("--shading", s.shading, "Gradient (headlight) shading");
    vol->add_option("--step", s.step,
                    "Ray-casting step, world units (default 0: half the smallest spacing)")
        ->check(finite_non_negative());
    vol->add_option("--preview-divisor", volume_options->preview_divisor,
                    "While interacting, ray-cast at 1/D of the resolution per axis (default 2; 1: "
                    "always full)")
        ->check(CLI::Range(1, 64));
    vol->add_flag("--axis-aligned", volume_options->axis_aligned,
                  "Resample an oblique volume onto an axis-aligned grid first (trilinear) instead "
                  "of showing it as it lies (--deform always does)");
    vol->add_flag("--deform", s.deform,
                  "Deform the volume: tet grid, XPBD soft body, resampling every frame");
    vol->add_option("--driver", volume_o->driver, "Initial driver (with --deform)")
        ->check(CLI::IsMember({"none", "wave", "twist", "bubble"}));
    vol->add_option("--resample", volume_o->resample,
                    "Show each frame through its inverse map without resampling (map, default) "
                    "or from its exact resample (exact; with --deform)")
        ->check(CLI::IsMember({"exact", "map"}));
    vol->add_option("--thin-levels", s.thin_levels,
                    "Through the map, an rgba8 volume: faint haze sampled once per 2^N steps, N "
                    "= 0 (every step), 1 or 2 (default 2; with --deform)")
        ->check(CLI::Range(0, 2));
    vol->add_option("--stiffness", s.body.stiffness, "PBD stiffness in (0, 1] (default 1)")
        ->check(finite_in_range(1e-6, 1.0));
    vol->add_option("--cells", s.grid.cell_voxels, "Voxels per tet-grid cell side (default 4)")
        ->check(CLI::Range(1, 4096));
    vol->add_option("--substeps", s.body.substeps, "XPBD substeps per frame (default 10)")
        ->check(CLI::Range(1, 10000));
    vol->add_option("--fps", s.fps, "Simulated frames per second: a frame is 1/F s (default 24)")
        ->check(finite_in_range(1e-3, 1e4));
    vol->add_option("--drag-radius", s.drag_radius,
                    "Vertices within this radius of the grabbed one move with it, box units "
                    "(default 0.05)")
        ->check(finite_in_range(0.0, 10.0));
    vol->add_option("--max-memory", volume_options->max_memory_mib,
                    "Largest volume to read, MiB (default 16384)")
        ->check(finite_in_range(1.0, 1e9));
    vol->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    vol->callback([volume_o, volume_options, vol, &global] {
        run_view_volume(*volume_o, *volume_options, vol, global);
    });
}

}  // namespace pliant::cli
