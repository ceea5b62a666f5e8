// pliant nerf train DATASET -o VOLUME [--minutes M | --iterations N] [--resolution R]
//                   [--stages S] [--batch B] [--export-resolution E] [--type rgba8|rgba32f]
//                   [--threshold T] [--normalize none|max|range] [--background R,G,B] [--seed S]
//                   [--max-memory MIB] [--downscale N] [--images DIR] [--alpha-mask]
//                   [--checkpoint-every N] [--resume]
// pliant nerf eval DATASET VOLUME [--background R,G,B] [--images DIR] [--max-memory MIB]
//                  [--downscale N] [--photos DIR] [--alpha-mask] [--json]
//
// DATASET: a transforms.json (NeRF-synthetic, instant-ngp, nerfstudio), a directory holding one,
// or a COLMAP sparse model directory (cameras, images, points3D; its photos from train's
// --images / eval's --photos DIR, default <model>/../../images); --downscale N box-filters the
// photos by N and scales the intrinsics (pipeline/nerf_dataset_file.hpp); --alpha-mask ignores
// pixels of alpha 0.
//
// train: reconstructs a voxel radiance field (nerf/trainer.hpp) from a posed-image dataset
// (io/nerf_dataset.hpp) and writes it as an RGBA volume (nerf/export.hpp: E voxels along the
// box's longest side, default 256), optionally cleaned (volume/clean.hpp: --threshold T on the
// 0–255 alpha scale, then --normalize; default none, which keeps what the training views show).
// A progress bar (iteration, grid resolution, batch loss and PSNR) goes to stderr when it is a
// terminal. Ctrl-C (SIGINT) stops after the iteration in progress: the volume so far is exported
// and written, stderr says where, exit code 130. VOLUME.checkpoint.bin (every --checkpoint-every
// iterations and on Ctrl-C) lets --resume continue a stopped or killed run.
// stdout: a summary, or with --json: output, iterations, seconds, train_psnr (last batch),
// resolution, grid_dims, occupied_cells, volume_dims, volume_spacing, peak_rss_bytes,
// interrupted.
//
// eval: renders the RGBA VOLUME with the ray caster (render::RayCaster, its defaults: step half
// the smallest spacing, opacity per smallest spacing, early termination at 0.99) from every view
// of the dataset (through render::Camera when the view is a centred square-pixel pinhole, else
// through its per-pixel rays: any principal point and lens) over the dataset's background, and
// compares with the dataset's images: PSNR and SSIM (nerf/metrics.hpp) per view and their means.
// --images DIR writes the renders as DIR/<i>.png. stdout: a table, or with --json: psnr, ssim
// (means), views [{file_path, psnr, ssim}].
//
// pliant nerf poses PHOTOS_DIR -o DIR [--test-every 8] [--matcher auto|exhaustive|sequential]
//                   [--centred-principal-point] [--json]
// poses: camera poses and one shared OPENCV lens for a folder of photos, by COLMAP
// (pipeline/photo_poses.hpp), written as DIR/transforms_train.json, DIR/transforms_test.json
// (nerfstudio's convention), DIR/points.ply and DIR/poses.json; COLMAP's files in DIR/colmap/.
// Ctrl-C kills COLMAP and exits 130 without writing the dataset.
// stdout: a summary, or with --json: photos, registered, unregistered, mean_reprojection_error_px,
// points, train, test, matcher, seconds per stage, total_seconds, camera, dataset_from_colmap.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "interrupt.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"
#include "pliant/pipeline/nerf_run.hpp"
#include "pliant/pipeline/photo_poses.hpp"
#include "progress_bar.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct TrainCommandOptions {
    std::string transforms;
    std::string out;
    double minutes = 0.0;
    std::int64_t iterations = 0;
    int resolution = 128;
    int stages = 3;
    int batch = 4096;
    int export_resolution = 256;
    std::string type = "rgba8";
    double threshold = 0.0;
    std::string normalize = "none";
    std::array<float, 3> background{0.0f, 0.0f, 0.0f};
    std::uint64_t seed = 1;
    float tv_density = nerf::TrainOptions{}.tv_density;
    float tv_color = nerf::TrainOptions{}.tv_color;
    float lr = nerf::TrainOptions{}.lr_density;
    double max_memory_mib = 0.0;  // 0: the memory available
    int downscale = 1;
    std::string photos;
    bool alpha_mask = false;
    std::int64_t checkpoint_every = 500;
    bool resume = false;
    int environment = 0;
    float sparsity = 0.0f;
    float distortion = 0.0f;
    bool exposure = false;
    bool refine_poses = false;
    bool refine_focal = false;
    std::string refined_poses;
    std::string test;
    std::string compare;
    std::string crop;
};

// --crop: "auto" or six numbers x0,y0,z0,x1,y1,z1 with min < max (UsageError otherwise).
void parse_crop(const std::string& text, pipeline::TrainRunOptions& run) {
    if (text.empty()) {
        return;
    }
    if (text == "auto") {
        run.auto_crop = true;
        return;
    }
    std::vector<double> v;
    std::size_t begin = 0;
    while (begin <= text.size()) {
        const std::size_t end = std::min(text.find(',', begin), text.size());
        const std::string item = text.substr(begin, end - begin);
        char* stop = nullptr;
        const double x = std::strtod(item.c_str(), &stop);
        if (item.empty() || stop != item.c_str() + item.size() || !std::isfinite(x)) {
            throw CLI::ValidationError(
                "--crop",
                fmt::format("--crop: '{}' is not a number; expected auto or x0,y0,z0,x1,y1,z1",
                            item));
        }
        v.push_back(x);
        begin = end + 1;
    }
    if (v.size() != 6 || !(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) {
        throw CLI::ValidationError(
            "--crop",
            fmt::format(
                "--crop: '{}', expected auto or x0,y0,z0,x1,y1,z1 with x0 < x1, y0 < y1, z0 < z1",
                text));
    }
    run.crop = AABBd{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
}

// --max-memory in bytes (0: the memory available; unknown: no limit).
std::size_t to_bytes(double mib) {
    const std::uint64_t limit = pipeline::memory_limit_bytes(mib);
    return limit > 0 ? static_cast<std::size_t>(limit) : volume::Volume::MAX_BYTES;
}

void run_train(const TrainCommandOptions& options, const GlobalOptions& global) {
    const volume::VoxelType type =
        options.type == "rgba32f" ? volume::VoxelType::rgba32f : volume::VoxelType::rgba8;
    io::check_volume_writable(options.out, type);  // fail before a long run
    io::require_writable_file(options.out);
    pipeline::ReadNerfDatasetOptions ro;
    ro.background = {options.background[0], options.background[1], options.background[2]};
    ro.max_bytes = to_bytes(options.max_memory_mib);
    ro.downscale = options.downscale;
    ro.images_dir = options.photos;
    ro.alpha_mask = options.alpha_mask;
    const nerf::Dataset dataset = pipeline::read_nerf_dataset(options.transforms, ro);
    std::optional<nerf::Dataset> test;
    if (!options.test.empty()) {
        test = pipeline::read_nerf_dataset(options.test, ro);
    }

    pipeline::TrainRunOptions run;
    parse_crop(options.crop, run);
    run.test = test ? &*test : nullptr;
    run.compare = options.compare;
    nerf::TrainOptions& to = run.train;
    to.max_bytes = to_bytes(options.max_memory_mib);
    run.exported.max_bytes = to.max_bytes;
    to.resolution = options.resolution;
    to.stages = options.stages;
    to.batch_rays = options.batch;
    to.seed = options.seed;
    to.tv_density = options.tv_density;
    to.tv_color = options.tv_color;
    to.lr_density = to.lr_color = to.lr_environment = options.lr;
    to.environment_width = options.environment;
    to.sparsity = options.sparsity;
    to.distortion = options.distortion;
    to.exposure = options.exposure;
    to.refine_poses = options.refine_poses;
    to.refine_focal = options.refine_focal;
    run.refined_poses = options.refined_poses;
    if (options.iterations > 0) {
        to.iterations = options.iterations;
    } else {
        to.seconds = 60.0 * (options.minutes > 0.0 ? options.minutes : 2.0);
    }
    run.exported.resolution = options.export_resolution;
    run.exported.type = type;
    if (options.threshold > 0.0 || options.normalize != "none") {
        volume::CleanOptions co;
        co.threshold_255 = options.threshold;
        co.normalization = options.normalize == "max" ? volume::AlphaNormalization::max
                           : options.normalize == "range"
                               ? volume::AlphaNormalization::threshold_range
                               : volume::AlphaNormalization::none;
        run.clean = co;
    }
    run.on_progress = train_progress(stderr_is_terminal());
    if (options.checkpoint_every > 0 || options.resume) {
        run.checkpoint = options.out + ".checkpoint.bin";
        run.checkpoint_every = options.checkpoint_every;
        run.resume = options.resume;
    }

    pipeline::TrainRunResult result;
    {
        const InterruptGuard guard;
        result = pipeline::train_volume(dataset, run, [] { return InterruptGuard::keep_going(); });
        end_progress();
    }
    io::write_volume(options.out, result.volume);

    if (global.json) {
        nlohmann::ordered_json j;
        j["output"] = options.out;
        j.update(result.json);
        std::fputs((j.dump(2) + "\n").c_str(), stdout);
    } else {
        const nlohmann::ordered_json& r = result.json;
        const auto& vd = result.volume.dims();
        std::printf(
            "%s: %lld iterations in %.1f s, grid %dx%dx%d, last batch PSNR %.2f dB, volume "
            "%lldx%lldx%lld, peak memory %.0f MiB\n",
            options.out.c_str(), r["iterations"].get<long long>(), r["seconds"].get<double>(),
            r["grid_dims"][0].get<int>(), r["grid_dims"][1].get<int>(),
            r["grid_dims"][2].get<int>(), r["train_psnr"].get<double>(),
            static_cast<long long>(vd[0]), static_cast<long long>(vd[1]),
            static_cast<long long>(vd[2]), pipeline::peak_rss_bytes() / 1048576.0);
    }
    if (result.stopped) {
        throw Interrupted(
            fmt::format("training stopped after {} iterations; the volume so far "
                        "is in {}",
                        result.json["iterations"].get<long long>(), options.out));
    }
}

struct EvalCommandOptions {
    std::string transforms;
    std::string volume;
    std::array<float, 3> background{0.0f, 0.0f, 0.0f};
    std::string images;
    double max_memory_mib = 0.0;  // 0: the memory available
    int downscale = 1;
    std::string photos;
    bool alpha_mask = false;
};

void run_eval(const EvalCommandOptions& options, const GlobalOptions& global) {
    pipeline::ReadNerfDatasetOptions ro;
    ro.background = {options.background[0], options.background[1], options.background[2]};
    ro.max_bytes = to_bytes(options.max_memory_mib);
    ro.downscale = options.downscale;
    ro.images_dir = options.photos;
    ro.alpha_mask = options.alpha_mask;
    const nerf::Dataset dataset = pipeline::read_nerf_dataset(options.transforms, ro);
    io::ReadVolumeOptions rv;
    rv.max_bytes = ro.max_bytes;
    rv.orientation = io::Orientation::keep;  // rendered at the views' poses in world space
    const volume::Volume vol = io::read_volume(options.volume, rv);
    if (volume::channels(vol.type()) != 4) {
        throw InvalidInput(fmt::format("{}: a {} volume; nerf eval needs an RGBA volume",
                                       options.volume, volume::name(vol.type())));
    }
    if (!dataset.views.empty()) {
        // The views are in memory already (read against the same limit); the caster and one
        // render come on top.
        std::uint64_t view_bytes = 0;
        for (const nerf::View& v : dataset.views) {
            view_bytes = pipeline::saturating_sum(view_bytes, v.rgb.size() * sizeof(float));
        }
        const int width = dataset.intrinsics.width;
        const int height = dataset.intrinsics.height;
        pipeline::require_memory(
            "nerf eval: " + pipeline::ray_cast_what(vol, width, height),
            pipeline::saturating_sum(view_bytes, pipeline::ray_cast_need_bytes(vol, width, height)),
            ro.max_bytes);
    }
    const nlohmann::ordered_json j =
        pipeline::evaluate_volume(dataset, vol, options.background, options.images);
    if (global.json) {
        std::fputs((j.dump(2) + "\n").c_str(), stdout);
    } else {
        for (const auto& e : j["views"]) {
            std::printf("%-28s PSNR %6.2f dB  SSIM %.4f\n",
                        e["file_path"].get<std::string>().c_str(), e["psnr"].get<double>(),
                        e["ssim"].get<double>());
        }
        std::printf("mean over %zu views: PSNR %.2f dB, SSIM %.4f\n", dataset.views.size(),
                    j["psnr"].get<double>(), j["ssim"].get<double>());
    }
}

struct PosesCommandOptions {
    std::string photos;
    std::string out;
    int test_every = 8;
    std::string matcher = "auto";
    bool centred_principal_point = false;
};

// "\rpliant nerf poses: [2/5] features  37%" on stderr while COLMAP runs (terminals only).
pipeline::PhotoPosesStageFn poses_progress(bool enabled) {
    if (!enabled) {
        return {};
    }
    return [](const std::string& stage, int index, int count, double fraction) {
        if (fraction >= 0.0) {
            std::fprintf(stderr, "\rnerf poses: [%d/%d] %-9s %3.0f%%", index + 1, count,
                         stage.c_str(), 100.0 * fraction);
        } else {
            std::fprintf(stderr, "\rnerf poses: [%d/%d] %-9s     ", index + 1, count,
                         stage.c_str());
        }
        std::fflush(stderr);
    };
}

void run_poses(const PosesCommandOptions& options, const GlobalOptions& global) {
    pipeline::PhotoPosesOptions po;
    po.test_every = options.test_every;
    po.matcher = options.matcher;
    po.refine_principal_point = !options.centred_principal_point;
    po.threads = global.threads;
    pipeline::PhotoPosesResult result;
    {
        const InterruptGuard guard;
        const bool bar = stderr_is_terminal();
        try {
            result =
                pipeline::recover_photo_poses(options.photos, options.out, po, poses_progress(bar),
                                              [] { return InterruptGuard::keep_going(); });
        } catch (...) {
            if (bar) {
                std::fputs("\n", stderr);
            }
            throw;
        }
        if (bar) {
            std::fputs("\n", stderr);
        }
    }
    if (global.json) {
        std::fputs((result.json.dump(2) + "\n").c_str(), stdout);
        return;
    }
    const nlohmann::ordered_json& j = result.json;
    std::printf("%s: registered %d/%d photos, mean reprojection error %.3f px, %lld points\n",
                options.out.c_str(), result.num_registered, result.num_photos,
                result.mean_reprojection_error_px, static_cast<long long>(result.num_points));
    std::printf("camera OPENCV %dx%d: fl %.2f %.2f, c %.2f %.2f, k1 %.4f k2 %.4f p1 %.5f p2 %.5f\n",
                result.intrinsics.width, result.intrinsics.height, result.intrinsics.fx,
                result.intrinsics.fy, result.intrinsics.cx, result.intrinsics.cy,
                result.intrinsics.lens.k1, result.intrinsics.lens.k2, result.intrinsics.lens.p1,
                result.intrinsics.lens.p2);
    std::string times;
    for (const auto& [name, seconds] : j["seconds"].items()) {
        times += fmt::format("{} {:.1f} s, ", name, seconds.get<double>());
    }
    std::printf("seconds: %stotal %.1f s\n", times.c_str(), j["total_seconds"].get<double>());
    std::printf(
        "wrote transforms_train.json (%zu), transforms_test.json (%zu), points.ply, "
        "poses.json\n",
        result.train.size(), result.test.size());
    if (!result.unregistered.empty()) {
        std::string names;
        for (const std::string& n : result.unregistered) {
            names += (names.empty() ? "" : ", ") + n;
        }
        std::printf("not registered: %s\n", names.c_str());
    }
}
}  // namespace

void register_nerf(CLI::App& app, const GlobalOptions& global) {
    CLI::App* nerf = app.add_subcommand(
        "nerf", "Radiance fields: reconstruct an RGBA volume from posed images, evaluate it");
    nerf->require_subcommand(1);

    auto t = std::make_shared<TrainCommandOptions>();
    CLI::App* train = nerf->add_subcommand(
        "train", "Train a voxel radiance field on transforms.json and export an RGBA volume");
    train
        ->add_option("TRANSFORMS", t->transforms,
                     "transforms_train.json, or a COLMAP sparse model directory")
        ->required();
    train->add_option("-o,--output", t->out, "Output volume (.nrrd, .nii, .nii.gz, .json)")
        ->required()
        ->check(non_empty_path());
    CLI::Option* minutes =
        train->add_option("--minutes", t->minutes, "Wall-clock budget in minutes (default 2)")
            ->check(finite_in_range(0.0, 1e6));
    train
        ->add_option("--iterations", t->iterations,
                     "A fixed number of iterations instead of a time budget (reproducible)")
        ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
        ->excludes(minutes);
    train
        ->add_option("--resolution", t->resolution,
                     "Final grid: voxels along the scene box's longest side")
        ->check(CLI::Range(4, 1024));
    train->add_option("--stages", t->stages, "Coarse-to-fine stages (each halves the grid)")
        ->check(CLI::Range(1, 6));
    train->add_option("--batch", t->batch, "Rays per iteration")->check(CLI::Range(1, 1 << 22));
    train
        ->add_option("--export-resolution", t->export_resolution,
                     "Exported volume: voxels along the longest side")
        ->check(CLI::Range(1, 2048));
    train->add_option("--type", t->type, "Exported voxel type")
        ->check(CLI::IsMember({"rgba8", "rgba32f"}));
    train
        ->add_option("--threshold", t->threshold,
                     "volume::clean threshold on the 0-255 alpha scale (the paper: 5, 20, 35)")
        ->check(finite_in_range(0.0, 255.0));
    train->add_option("--normalize", t->normalize, "Alpha normalization after the threshold")
        ->check(CLI::IsMember({"none", "max", "range"}));
    train
        ->add_option("--background", t->background,
                     "Colour transparent image pixels are composited over, each in [0, 1]")
        ->type_name("R,G,B")
        ->delimiter(',')
        ->check(finite_in_range(0.0, 1.0));
    train->add_option("--seed", t->seed, "Seed of the ray batches");
    train
        ->add_option("--checkpoint-every", t->checkpoint_every,
                     "Save OUT.checkpoint.bin every N iterations and on Ctrl-C (0: never; "
                     "default 500); removed once training completes")
        ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 40));
    train->add_flag("--resume", t->resume,
                    "Continue from OUT.checkpoint.bin (with --iterations: the same volume as an "
                    "uninterrupted run); without one, start from iteration 0");
    train->add_option("--tv-density", t->tv_density, "Total-variation weight on density")
        ->check(finite_in_range(0.0, 1e9));
    train->add_option("--tv-color", t->tv_color, "Total-variation weight on colour")
        ->check(finite_in_range(0.0, 1e9));
    train->add_option("--lr", t->lr, "Adam learning rate (raw density and colour)")
        ->check(finite_in_range(0.0, 100.0));
    train
        ->add_option("--max-memory", t->max_memory_mib,
                     "Refuse datasets and grids that would need more than this (MiB; default: "
                     "the memory available), before allocating")
        ->type_name("MIB")
        ->check(finite_in_range(1e-6, 1e9));
    train
        ->add_option("--downscale", t->downscale,
                     "Box-filter the photos by N x N pixels (intrinsics scaled to match)")
        ->check(CLI::Range(1, 64));
    train->add_option("--images,--photos", t->photos,
                      "A COLMAP model's photos (default: <model>/../../images)");
    train->add_flag("--alpha-mask", t->alpha_mask, "Ignore pixels of alpha 0 (besides masks)");
    train
        ->add_option("--environment", t->environment,
                     "Learn the background of rays leaving the box as an environment map W "
                     "texels around (photos of a room; 0: the constant --background)")
        ->check(CLI::Range(0, 4096));
    train
        ->add_option("--sparsity", t->sparsity,
                     "Weight of a sparsity prior on density (empties the air of photo captures; "
                     "0: off)")
        ->check(finite_in_range(0.0, 1e9));
    train
        ->add_option("--distortion", t->distortion,
                     "Weight of Mip-NeRF 360's distortion loss (against floaters; 0: off)")
        ->check(finite_in_range(0.0, 1e9));
    train->add_flag("--exposure", t->exposure,
                    "Learn a gain and bias per photo and channel (exposure, white balance)");
    train->add_flag("--refine-poses", t->refine_poses,
                    "Refine each training photo's pose (rotation, position) while training");
    train->add_flag("--refine-focal", t->refine_focal,
                    "Refine the focal length (one scale for all photos) while training");
    train->add_option("--refined-poses", t->refined_poses,
                      "With --refine-poses/--refine-focal: write the refined training cameras "
                      "as a transforms.json");
    train->add_option("--test", t->test,
                      "Held-out views (transforms_test.json): score the trained field on them "
                      "(test_psnr, test_ssim)");
    train->add_option("--compare", t->compare,
                      "With --test: write a PNG of held-out photos above their renders");
    train
        ->add_option("--crop", t->crop,
                     "Export only this box of the dataset's frame, or 'auto': the object above "
                     "the table (nerf/crop.hpp)")
        ->type_name("auto|X0,Y0,Z0,X1,Y1,Z1");
    train->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    train->callback([t, &global] { run_train(*t, global); });

    auto e = std::make_shared<EvalCommandOptions>();
    CLI::App* eval = nerf->add_subcommand(
        "eval", "PSNR and SSIM of an RGBA volume's ray-cast renders against a dataset's views");
    eval->add_option("TRANSFORMS", e->transforms,
                     "transforms_test.json, or a COLMAP sparse model directory")
        ->required();
    eval->add_option("VOLUME", e->volume, "RGBA volume (from nerf train)")->required();
    eval->add_option("--background", e->background, "Background colour, each in [0, 1]")
        ->type_name("R,G,B")
        ->delimiter(',')
        ->check(finite_in_range(0.0, 1.0));
    eval->add_option("--images", e->images, "Write the renders to this directory");
    eval->add_option("--max-memory", e->max_memory_mib,
                     "Refuse datasets and volumes that would need more than this (MiB; default: "
                     "the memory available), before allocating")
        ->type_name("MIB")
        ->check(finite_in_range(1e-6, 1e9));
    eval->add_option("--downscale", e->downscale,
                     "Box-filter the photos by N x N pixels (intrinsics scaled to match)")
        ->check(CLI::Range(1, 64));
    eval->add_option("--photos", e->photos,
                     "A COLMAP model's photos (default: <model>/../../images)");
    eval->add_flag("--alpha-mask", e->alpha_mask, "Ignore pixels of alpha 0 (besides masks)");
    eval->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    eval->callback([e, &global] { run_eval(*e, global); });

    auto po = std::make_shared<PosesCommandOptions>();
    CLI::App* poses = nerf->add_subcommand(
        "poses", "Recover camera poses and the lens from a folder of photos with COLMAP");
    poses->add_option("PHOTOS_DIR", po->photos, "Folder of photos (.jpg, .jpeg, .png) of one size")
        ->required();
    poses
        ->add_option("-o,--output", po->out,
                     "Output folder: transforms_train.json, transforms_test.json, points.ply, "
                     "poses.json, colmap/")
        ->required()
        ->check(non_empty_path());
    poses
        ->add_option("--test-every", po->test_every,
                     "Hold out every N-th registered photo for transforms_test.json (0: none)")
        ->check(CLI::Range(0, 1000000));
    poses
        ->add_option("--matcher", po->matcher,
                     "COLMAP matching: exhaustive, sequential (photos in walking order), or auto "
                     "(sequential above 150 photos)")
        ->check(CLI::IsMember({"auto", "exhaustive", "sequential"}));
    poses->footer(
        "Needs COLMAP (apt-get install colmap). Global options --threads N and --json "
        "apply here too.");
    poses->callback([po, &global] { run_poses(*po, global); });
}

}  // namespace pliant::cli
