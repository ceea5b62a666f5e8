// pliant cloth SCENE.json --out DIR [--frames N] [--no-preview] [--preview-size WxH]
//              [--max-memory MIB] [--checkpoint-every N] [--resume] [--json]
//
// Simulates a cloth scene (format in docs/formats.md) with pipeline::run_cloth_scene and writes:
//   DIR/frames/frame_0000.obj … frame_NNNN.obj (or .ply with "output": {"format": "ply"}): the
//     initial state, then one file per simulated frame, each replaced atomically;
//   DIR/preview.mp4: a shaded preview through ffmpeg (DIR/preview/frame_NNNN.png when ffmpeg is
//     not installed; --no-preview: none; --preview-size WxH, default 640x480);
//   DIR/stats.json: the scene's sizes and, per frame, `frame`, `ms` (the simulation step),
//     the step's stages (`step_ms`, `refit_ms`, `traverse_ms`, `narrow_ms`, `response_ms`),
//     `contacts`, `ccd_hits`, `intersecting_pairs` and `obstacle_intersections` (exact counts on
//     the frame as written); and
//     `mean_ms_per_frame` (schema in docs/formats.md). Written last, atomically.
// Ctrl-C (SIGINT) stops the run after the frame in progress: frames, preview and stats.json so
// far are complete, stderr says where, exit code 130. DIR/checkpoint.bin (every
// --checkpoint-every frames) lets --resume continue a run that was stopped or killed. A progress
// bar goes to stderr when it is a terminal. With --json, stdout is stats.json's object; otherwise a
// short summary.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "commands.hpp"
#include "interrupt.hpp"
#include "option_values.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/pipeline/cloth_run.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "progress_bar.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct ClothCommandOptions {
    std::string scene;
    std::string out;
    int frames = -1;  // -1: the scene's
    bool no_preview = false;
    std::string preview_size = "640x480";
    double max_memory_mib = 0.0;  // 0: the memory available
    int checkpoint_every = pipeline::ClothRunOptions{}.checkpoint_every;
    bool resume = false;
};

void run_cloth(const ClothCommandOptions& options, const GlobalOptions& global) {
    const cloth::ClothScene scene = pipeline::read_cloth_scene(options.scene);
    const int frames = options.frames >= 0 ? options.frames : scene.frames;
    const std::filesystem::path out(options.out);
    pipeline::ClothRunOptions run;
    run.frames = frames;
    run.progress = frame_progress(stderr_is_terminal() && !global.json);
    run.keep_going = InterruptGuard::keep_going;
    run.preview = !options.no_preview;
    const std::array<int, 2> preview_size = parse_size(options.preview_size, "--preview-size");
    if (std::min(preview_size[0], preview_size[1]) < 16 ||
        std::max(preview_size[0], preview_size[1]) > 8192) {
        throw CLI::ValidationError("--preview-size", "expected WxH with 16 <= W, H <= 8192, got '" +
                                                         options.preview_size + "'");
    }
    run.preview_width = preview_size[0];
    run.preview_height = preview_size[1];
    run.max_memory_bytes = static_cast<std::uint64_t>(options.max_memory_mib * 1024.0 * 1024.0);
    run.checkpoint_every = options.checkpoint_every;
    run.resume = options.resume;
    const InterruptGuard interrupt_guard;
    const nlohmann::ordered_json stats = pipeline::run_cloth_scene(scene, options.scene, out, run);
    if (global.json) {
        std::fputs((stats.dump(2) + "\n").c_str(), stdout);
    } else {
        std::printf(
            "%d frames of %zu triangles, %.1f ms per frame (%d substeps), at most %lld "
            "intersecting triangle pairs and %lld obstacle intersections in a frame; frames in "
            "%s, stats in %s%s\n",
            frames, stats["triangles"].get<std::size_t>(), stats["mean_ms_per_frame"].get<double>(),
            scene.substeps,
            static_cast<long long>(stats["max_intersecting_pairs"].get<std::int64_t>()),
            static_cast<long long>(stats["max_obstacle_intersections"].get<std::int64_t>()),
            (out / "frames").string().c_str(), (out / "stats.json").string().c_str(),
            stats.contains("preview") ? (", preview " + stats["preview"].get<std::string>()).c_str()
                                      : "");
    }
}

}  // namespace

void register_cloth(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<ClothCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "cloth", "XPBD cloth simulation of a scene file: mesh frames and per-frame statistics");
    cmd->add_option("SCENE", options->scene, "Scene file (JSON, see docs/formats.md)")->required();
    cmd->add_option("--out", options->out, "Output directory (created if missing)")
        ->required()
        ->check(non_empty_path());
    cmd->add_option("--frames", options->frames, "Frames to simulate (default: the scene's)")
        ->check(CLI::Range(0, 1'000'000));
    cmd->add_flag("--no-preview", options->no_preview,
                  "Do not render DIR/preview.mp4 (PNG frames in DIR/preview/ without ffmpeg)");
    cmd->add_option("--preview-size", options->preview_size,
                    "Preview size in pixels, WxH like --size elsewhere (default 640x480)")
        ->type_name("WxH");
    cmd->add_option("--max-memory", options->max_memory_mib,
                    "Refuse a cloth whose triangles need more memory than this, MiB (default: the "
                    "memory available: physical, or the control group's limit)")
        ->check(finite_in_range(1.0, 1e12));
    cmd->add_option("--checkpoint-every", options->checkpoint_every,
                    "Save DIR/checkpoint.bin every N frames, at the last frame and on Ctrl-C "
                    "(0: never; default " +
                        std::to_string(options->checkpoint_every) + ")")
        ->check(CLI::Range(0, 1'000'000));
    cmd->add_flag("--resume", options->resume,
                  "Continue from DIR/checkpoint.bin (frames identical to an uninterrupted run); "
                  "without one, start from frame 0");
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_cloth(*options, global); });
}

}  // namespace pliant::cli
