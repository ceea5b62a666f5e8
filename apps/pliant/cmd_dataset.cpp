// pliant dataset VOLUME [--series UID] --views N [--size WxH] [--tf FILE|PRESET] [--fov DEG]
// [--test-every K]
//                [--background R,G,B] [--step S] [--max-memory MIB] -o DIR   [--json]
//
// Renders a posed-image dataset from a volume with the ray caster (render/raycast.hpp), so that
// every radiance-field reconstruction has a ground truth:
//   - N perspective views on a Fibonacci sphere around the volume's box (view i at height
//     z_i = 1 − (2 i + 1) / N, azimuth i · 137.508°), each looking at the box's centre from the
//     distance at which the box's bounding sphere fits the field of view (render::frame_box,
//     margin 1.1, vertical field of view --fov, default 40°);
//   - view i goes to the test split when i % K == 0 (K = --test-every, default 10), else to train;
//   - DIR/train/r_<i>.png, DIR/test/r_<i>.png (RGB, the background composited),
//     DIR/transforms_train.json, DIR/transforms_test.json (io/nerf_dataset.hpp: camera_angle_x,
//     fl_x …, the volume's box as `aabb`, OpenGL camera-to-world matrices).
// --series, --tf, --step, --background as for `pliant render` (an oblique volume is rendered as
// it lies, in world space; `aabb` is its world box, Volume::world_bounds). --max-memory MiB: the
// volume, the ray caster's tables and one image (views are written one at a time) may take at most
// this (default: the memory available); more is refused before allocating and before anything is
// written. stdout: a summary, or with --json: output, views, train, test, width, height, ms.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "option_values.hpp"
#include "pliant/io/transfer_function_json.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "pliant/pipeline/nerf_run.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct DatasetCommandOptions {
    std::string volume;
    std::string series;
    int views = 100;
    std::string size = "200x200";
    std::string tf = "grayscale";
    double fov = 40.0;
    int test_every = 10;
    std::array<float, 3> background{0.0f, 0.0f, 0.0f};
    double step = 0.0;
    std::string out;
    double max_memory_mib = 0.0;  // 0: the memory available
};

void run_dataset(const DatasetCommandOptions& options, const GlobalOptions& global) {
    const std::array<int, 2> size = parse_size(options.size);
    const std::uint64_t memory_limit = pipeline::memory_limit_bytes(options.max_memory_mib);
    pipeline::require_memory(fmt::format("dataset: a {}x{} view", size[0], size[1]),
                             pipeline::image_bytes(size[0], size[1]), memory_limit);
    io::ReadVolumeOptions read;
    read.series_uid = options.series;
    read.orientation = io::Orientation::keep;  // the ray caster renders it in world space
    if (memory_limit > 0) {
        read.max_bytes = static_cast<std::size_t>(memory_limit);
    }
    const volume::Volume vol = io::read_volume(options.volume, read);
    pipeline::require_memory("dataset: " + pipeline::ray_cast_what(vol, size[0], size[1]),
                             pipeline::ray_cast_need_bytes(vol, size[0], size[1]), memory_limit);
    const bool is_rgba = volume::channels(vol.type()) == 4;
    volume::TransferFunction tf;
    if (!is_rgba) {
        tf = io::load_transfer_function(options.tf, vol);
    }
    pipeline::DatasetRunOptions run;
    run.views = options.views;
    run.size = size;
    run.fov = options.fov;
    run.test_every = options.test_every;
    run.background = options.background;
    run.step = options.step;
    const nlohmann::ordered_json j =
        pipeline::render_dataset(vol, is_rgba ? nullptr : &tf, run, options.out);
    if (global.json) {
        std::fputs((j.dump(2) + "\n").c_str(), stdout);
    } else {
        std::printf("%s: %d views of %dx%d (%zu train, %zu test) in %.0f ms\n", options.out.c_str(),
                    options.views, run.size[0], run.size[1], j["train"].get<std::size_t>(),
                    j["test"].get<std::size_t>(), j["ms"].get<double>());
    }
}

}  // namespace

void register_dataset(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<DatasetCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "dataset",
        "Render a posed-image dataset (transforms_train/test.json + PNGs) from a volume");
    cmd->add_option("VOLUME", options->volume, "Volume file, or a folder of DICOM files")
        ->required();
    cmd->add_option("--series", options->series,
                    "DICOM: the SeriesInstanceUID to read from a folder holding several (default: "
                    "the largest)")
        ->type_name("UID");
    cmd->add_option("--views", options->views, "Number of views (train + test)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--size", options->size, "Image size")->type_name("WxH");
    cmd->add_option("--tf", options->tf,
                    "Transfer function: a preset (ct-bone, ct-skin, mri-brain, grayscale) or a "
                    "JSON file; ignored for RGBA volumes");
    cmd->add_option("--fov", options->fov, "Vertical field of view, degrees")
        ->check(finite_in_range(1.0, 170.0));
    cmd->add_option("--test-every", options->test_every,
                    "View i goes to the test split when i % K == 0")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--background", options->background, "Background colour, each in [0, 1]")
        ->type_name("R,G,B")
        ->delimiter(',')
        ->check(finite_in_range(0.0, 1.0));
    cmd->add_option("--step", options->step,
                    "Ray-casting step, world units (default 0: half the smallest spacing)")
        ->check(finite_in_range(0.0, 1e30));
    add_max_memory_option(*cmd, options->max_memory_mib, "a volume and views that need");
    cmd->add_option("-o,--output", options->out, "Output directory")
        ->required()
        ->check(non_empty_path());
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_dataset(*options, global); });
}

}  // namespace pliant::cli
