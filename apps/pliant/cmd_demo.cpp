// pliant demo [--out DIR] [--cloth-frames N] [--deform-frames N]
//             [--nerf-minutes M | --nerf-iterations N] [--nerf-resolution R] [--nerf-views N]
//
// Everything pliant does today, end to end, on generated data (no input files):
//   1. the drape scene's sheet (2 m × 2 m, 134 × 134 quads, 35,912 triangles) folded like an
//      accordion (layers 1.5 edge lengths apart; the BVH benchmark's workload, bvh_workload.hpp,
//      at drape size), written to DIR/folded_sheet.ply; the self-collision broad phase on it,
//      static, inflation a quarter edge: pair counts and stage timings;
//   2. the same, swept from the folded sheet to a moved copy (a travelling sine wave of 0.1 edge
//      lengths, DIR/folded_sheet_t1.ply), with the continuous narrow phase (conservative CCD) on
//      every pair: hits and the earliest time of impact;
//   3. the paper's BVH table (bench/peers/bvh_table.hpp) at 2,244, 27,030 and 35,992 triangles,
//      3 repetitions, beside Embree and brute force;
//   4. the built-in cloth scenes (scenes/drape.json, twist.json, pile.json, flag.json, built into
//      the binary) through `pliant cloth`: DIR/<scene>/frames/frame_NNNN.obj, preview.mp4 and
//      stats.json;
//   4b. untangling: the drape without self-collision and with dihedral bending, 16 frames
//      (DIR/untangle/fall/scene.json; it falls through itself, DIR/untangle/fall/); its last frame
//      is the cloth of DIR/untangle/scene.json (a new cloth whose rest shape is that frame), which
//      `pliant cloth` untangles before frame 0 and simulates with self-collision for 24 frames
//      (at most --cloth-frames): DIR/untangle/preview.mp4, frames, stats.json (its untangle
//      report); and two sheets crossing like an X, untangled by a region move and dropped on
//      the ground: DIR/untangle/crossing/ (scene.json, preview.mp4, frames, stats.json);
//   5. a volume through the ray caster (the Colin27 brain from mricron-data, else the head CT from
//      invesalius-examples, else a generated phantom): DIR/volume/volume.png, turntable.mp4;
//   6. the same volume twisted by the XPBD soft body on a tet grid, resampled and ray-cast every
//      frame (deform_run.hpp): DIR/deform/twist.mp4, twist.png, twisted.nrrd;
//   7. the paper's pipeline from images (nerf_run.hpp): a posed-image dataset rendered from the
//      volume, a radiance field trained on it (--nerf-minutes, default 2), exported as an RGBA
//      volume, scored on held-out views, cleaned (threshold 5, the paper's mildest, alpha
//      normalization) and twisted like step 6: DIR/nerf/dataset/, reconstructed.nrrd, compare.png,
//      cleaned.nrrd, twist.mp4;
//   8. DIR/summary.json with every number (schema in docs/formats.md).
// Steps 1 and 2 run on the files' own numbers (double), so `pliant collide` on the written files
// with the printed inflation reproduces their counts exactly.
//
// Human output on stdout (progress on stderr when it is a terminal); with --json, stdout is
// summary.json's object. Throws IoError when DIR cannot be created or written, InternalError when
// the BVH table's pair counts disagree between pliant, Embree and brute force (after writing the
// summary). Takes about four minutes on 2 vCPUs (two of them training the radiance field).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "broad_phase_report.hpp"
#include "cloth_run.hpp"
#include "commands.hpp"
#include "deform_run.hpp"
#include "nerf_run.hpp"
#include "output_directory.hpp"
#include "peers/bvh_table.hpp"
#include "peers/bvh_workload.hpp"
#include "pliant/built_in_scenes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/cloth_scene.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/nerf_dataset.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

constexpr std::int64_t DRAPE_TRIANGLES = 35912;  // 134 × 134 quads, DESIGN.md's drape scene
constexpr float DRAPE_SIZE = 2.0f;               // m
constexpr int COLLIDE_REPEATS = 5;
constexpr int TABLE_REPEATS = 3;

struct DemoOptions {
    std::string out = "out/demo";
    int cloth_frames = -1;             // -1: each cloth scene's own
    int deform_frames = 48;            // frames of the twist animations (steps 6 and 7)
    double nerf_minutes = 2.0;         // the radiance field's training budget
    std::int64_t nerf_iterations = 0;  // > 0: a fixed iteration count instead (reproducible)
    int nerf_resolution = 128;  // the radiance field's final grid (voxels on the longest side)
    int nerf_views = 100;       // views of the posed-image dataset (every 10th held out)
};

// One broad-phase configuration, measured like `pliant collide --repeat N` after one untimed
// warm-up update.
// With swept, the continuous narrow phase runs on the pairs too (`collide --ccd`).
nlohmann::ordered_json measure(const geometry::TriangleMeshD& mesh,
                               std::span<const Vec3d> positions_t1, double inflation, bool swept) {
    return to_json(measure_broad_phase(mesh, positions_t1, inflation, COLLIDE_REPEATS, swept,
                                       /*warm_up=*/true, /*narrow=*/swept));
}

std::string format_broad_phase(const std::string& title, const nlohmann::ordered_json& r) {
    std::string text = title + "\n";
    text += fmt::format("  {:<16}{:>10}   {:<16}{:>10}   {:<16}{:>10}\n", "triangle pairs",
                        thousands(r["triangle_pairs"].get<std::int64_t>()), "VF pairs",
                        thousands(r["vf_pairs"].get<std::int64_t>()), "EE pairs",
                        thousands(r["ee_pairs"].get<std::int64_t>()));
    text += fmt::format("  {:<16}{:>7.3f} ms   {:<16}{:>7.3f} ms   {:<16}{:>7.3f} ms\n", "build",
                        r["build_ms"].get<double>(), "refit", r["refit_ms"].get<double>(),
                        "traverse", r["traverse_ms"].get<double>());
    text += fmt::format(
        "  {:<16}{:>7.3f} ms   {:<16}{:>7.3f} ms   (medians of {}; total = one "
        "refit-based update)\n",
        "features", r["features_ms"].get<double>(), "total", r["total_ms"].get<double>(),
        COLLIDE_REPEATS);
    if (r.contains("narrow_ms")) {
        text += fmt::format("  {:<16}{:>7.3f} ms   {:<16}{:>10}   {:<16}{:>10}   earliest toi {}\n",
                            "narrow (CCD)", r["narrow_ms"].get<double>(), "VF hits",
                            thousands(r["vf_hits"].get<std::int64_t>()), "EE hits",
                            thousands(r["ee_hits"].get<std::int64_t>()),
                            r["earliest_toi"].get<double>());
    }
    return text;
}

std::vector<Vec3d> to_double(std::span<const Vec3f> positions) {
    std::vector<Vec3d> out;
    out.reserve(positions.size());
    for (const Vec3f& p : positions) {
        out.push_back(vec3_cast<double>(p));
    }
    return out;
}

void say(bool quiet, const std::string& text) {
    if (!quiet) {
        std::fputs(text.c_str(), stdout);
        std::fflush(stdout);
    }
}

// The demo's volume: the first installed of the Colin27 MRI brain and the InVesalius head CT,
// else a generated phantom, with the transfer-function preset that suits it.
struct DemoVolume {
    volume::Volume volume;
    std::string source = "generated: 3D Shepp-Logan phantom, 128^3";
    std::string preset = "grayscale";
};

DemoVolume load_demo_volume() {
    struct Candidate {
        const char* path;
        const char* what;
        const char* preset;
    };
    const Candidate candidates[] = {
        {"/usr/share/mricron/templates/ch2.nii.gz", "the Colin27 brain (MRI, mricron-data)",
         "mri-brain"},
        {"/usr/share/doc/invesalius-examples/examples/Cranium.inv3",
         "the InVesalius head CT (invesalius-examples)", "ct-bone"},
    };
    DemoVolume demo;
    for (const Candidate& c : candidates) {
        if (std::filesystem::exists(c.path)) {
            demo.volume = io::read_volume(c.path);
            demo.source = fmt::format("{} ({})", c.what, c.path);
            demo.preset = c.preset;
            return demo;
        }
    }
    demo.volume = volume::shepp_logan_3d({128, 128, 128});
    return demo;
}

// The demo volume rendered to DIR/volume/volume.png (512²) and a 36-frame turntable
// DIR/volume/turntable.mp4 (384²).
nlohmann::ordered_json render_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo,
                                          bool quiet) {
    const volume::Volume& v = demo.volume;
    const std::string& source = demo.source;
    const std::string& preset = demo.preset;
    const volume::TransferFunction tf = volume::preset(preset, v);
    render::RayCastOptions options;
    options.shading = true;
    const render::RayCaster caster(v, &tf, options);
    const std::filesystem::path out = dir / "volume";
    make_output_directory(out);
    render::Image image;
    const render::Camera camera = render::frame_box(v.bounds(), 60.0, 20.0, 512, 512);
    const render::RayCastStats still = caster.render(camera, image);
    io::write_png(out / "volume.png", image);
    constexpr int TURNTABLE_FRAMES = 36;
    double turntable_ms = 0.0;
    std::unique_ptr<io::VideoWriter> video;
    if (io::ffmpeg_available()) {
        video = std::make_unique<io::VideoWriter>(out / "turntable.mp4", 384, 384, 12.0);
    }
    for (int f = 0; f < TURNTABLE_FRAMES; ++f) {
        const render::Camera orbit =
            render::frame_box(v.bounds(), 60.0 + 360.0 * f / TURNTABLE_FRAMES, 20.0, 384, 384);
        turntable_ms += caster.render(orbit, image).ms;
        if (video) {
            video->write(image);
        } else {
            io::write_png(out / fmt::format("turntable_{:04d}.png", f), image);
        }
    }
    if (video) {
        video->finish();
    }
    const std::string turntable =
        video ? (out / "turntable.mp4").string() : (out / "turntable_NNNN.png").string();
    say(quiet, fmt::format("a volume through the ray caster: {}, {} x {} x {} voxels, transfer "
                           "function {}:\n  {} ({:.1f} ms at 512 x 512), turntable {} ({:.1f} ms "
                           "per 384 x 384 frame)\n\n",
                           source, v.dims()[0], v.dims()[1], v.dims()[2], preset,
                           (out / "volume.png").string(), still.ms, turntable,
                           turntable_ms / TURNTABLE_FRAMES));
    return {{"source", source},
            {"dims", {v.dims()[0], v.dims()[1], v.dims()[2]}},
            {"transfer_function", preset},
            {"png", (out / "volume.png").string()},
            {"png_ms", still.ms},
            {"turntable", turntable},
            {"turntable_ms_per_frame", turntable_ms / TURNTABLE_FRAMES}};
}

// The deformable-volume pipeline (tet grid, XPBD soft body, resampling, ray casting) on `source`
// with the twist driver, the slab at +y (the face, for the Colin27 brain) turned 90 degrees
// against the slab at -y over 2 s: OUT/twist.mp4 (none without ffmpeg), twist.png (the last
// frame) and twisted.nrrd. tf: for a scalar source, nullptr for RGBA. Returns run_deform's JSON
// and the file to watch.
std::pair<nlohmann::ordered_json, std::string> twist_volume(const volume::Volume& source,
                                                            const volume::TransferFunction* tf,
                                                            const std::filesystem::path& out,
                                                            int frames, bool progress) {
    DeformRunOptions run;
    run.driver_name = "twist";
    run.driver =
        pbd::TwistDriver{.axis = pbd::Axis::y, .angle = 90.0, .ramp_time = 2.0, .grip = 0.1};
    run.frames = frames;
    run.fps = 24.0;
    run.out = out / "twisted.nrrd";
    if (io::ffmpeg_available()) {
        run.video = out / "twist.mp4";
    }
    run.still = out / "twist.png";
    run.size = {384, 384};
    run.camera = {60.0, 20.0, 0.0};
    run.shading = true;
    run.progress = progress;
    return {run_deform(source, tf, run),
            run.video.empty() ? run.still.string() : run.video.string()};
}

// Step 6: the demo volume twisted (twist_volume) into DIR/deform.
nlohmann::ordered_json deform_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo,
                                          const DemoOptions& options, bool quiet) {
    const std::filesystem::path out = dir / "deform";
    make_output_directory(out);
    const volume::TransferFunction tf = volume::preset(demo.preset, demo.volume);
    const auto [result, watch] = twist_volume(demo.volume, &tf, out, options.deform_frames,
                                              !quiet && ::isatty(::fileno(stderr)) != 0);
    say(quiet,
        fmt::format("the volume twisted (tet grid + XPBD + resampling + ray casting): {} tets, "
                    "{:.1f} ms per substep, {:.1f} ms per resampling, {:.1f} ms per frame; "
                    "volume ratio {:.4f}, {} inverted tets:\n  {}\n\n",
                    result["tets"].get<long long>(), result["ms_per_substep"].get<double>(),
                    result["resample_ms"].get<double>(), result["ms_per_frame"].get<double>(),
                    result["volume_ratio"].get<double>(), result["inverted_tets"].get<long long>(),
                    watch));
    return result;
}

// The paper's whole pipeline from images: a posed-image dataset rendered from the demo volume
// (DIR/nerf/dataset, 200 × 200, every 10th view held out), a radiance field trained on the
// training views for options.nerf_minutes and exported as an RGBA volume
// (DIR/nerf/reconstructed.nrrd), scored on the held-out views (PSNR, SSIM; DIR/nerf/compare.png:
// held-out view 0, its reconstruction, the cleaned reconstruction), cleaned as in the paper
// (threshold 5 on the 0-255 alpha scale, then alpha normalization: DIR/nerf/cleaned.nrrd), then
// twisted like step 6: DIR/nerf/twist.mp4, twist.png, twisted.nrrd.
nlohmann::ordered_json reconstruct_demo_volume(const std::filesystem::path& dir,
                                               const DemoVolume& demo, const DemoOptions& options,
                                               bool quiet) {
    const std::filesystem::path out = dir / "nerf";
    make_output_directory(out);
    const bool progress = !quiet && ::isatty(::fileno(stderr)) != 0;
    const volume::TransferFunction tf = volume::preset(demo.preset, demo.volume);

    DatasetRunOptions dataset_run;
    dataset_run.views = options.nerf_views;
    const nlohmann::ordered_json dataset_json =
        render_dataset(demo.volume, &tf, dataset_run, out / "dataset");
    const nerf::Dataset train_set =
        io::read_nerf_dataset(out / "dataset" / "transforms_train.json");
    const nerf::Dataset test_set = io::read_nerf_dataset(out / "dataset" / "transforms_test.json");

    TrainRunOptions train_run;
    if (options.nerf_iterations > 0) {
        train_run.train.iterations = options.nerf_iterations;
    } else {
        train_run.train.seconds = 60.0 * options.nerf_minutes;
    }
    train_run.train.resolution = options.nerf_resolution;
    train_run.exported.resolution = 256;
    train_run.progress = progress;
    const TrainRunResult trained = train_volume(train_set, train_run, [] { return true; });
    io::write_volume(out / "reconstructed.nrrd", trained.volume);
    const nlohmann::ordered_json eval = evaluate_volume(test_set, trained.volume, {0, 0, 0});

    // The paper's mildest threshold: this volume is semi-transparent tissue whose per-voxel
    // opacities (0.85 mm voxels) the stronger ones, 20 and 35, cut holes into; the paper's
    // objects were opaque.
    volume::Volume cleaned = trained.volume;
    const volume::CleanOptions clean_options{.threshold_255 = 5.0,
                                             .normalization = volume::AlphaNormalization::max};
    volume::clean(cleaned, clean_options);
    io::write_volume(out / "cleaned.nrrd", cleaned);
    const nlohmann::ordered_json eval_cleaned = evaluate_volume(test_set, cleaned, {0, 0, 0});

    // Held-out view 0: the ground truth, the reconstruction, the cleaned reconstruction.
    const nerf::View& view = test_set.views.front();
    const render::Camera camera = nerf::camera_from_view(test_set.intrinsics, view.camera_to_world);
    std::vector<render::Image> row = {nerf::to_image(test_set.intrinsics, view)};
    const std::array<const volume::Volume*, 2> reconstructions = {&trained.volume, &cleaned};
    for (const volume::Volume* v : reconstructions) {
        const render::RayCaster caster(*v, nullptr, render::RayCastOptions{});
        caster.render(camera, row.emplace_back());
    }
    io::write_png(out / "compare.png", render::side_by_side(row, 4, {255, 255, 255}));

    const auto [deform, watch] =
        twist_volume(cleaned, nullptr, out, options.deform_frames, progress);

    say(quiet,
        fmt::format(
            "the paper's pipeline from images: {} views of {} x {} rendered from the volume "
            "({}), a radiance field trained for {:.0f} s ({} iterations, grid {}), exported at "
            "{} x {} x {} RGBA:\n  held-out views: PSNR {:.2f} dB, SSIM {:.4f}; peak memory "
            "{:.0f} MiB; compare.png shows a held-out view, its reconstruction, the cleaned "
            "one\n  cleaned (threshold 5, alpha normalization; held-out PSNR {:.2f} dB), twisted: "
            "{:.1f} ms per frame, volume ratio {:.4f}, {} inverted tets:\n  {}\n\n",
            dataset_json["views"].get<int>(), dataset_json["width"].get<int>(),
            dataset_json["height"].get<int>(), (out / "dataset").string(),
            trained.json["seconds"].get<double>(), trained.json["iterations"].get<long long>(),
            trained.json["resolution"].get<int>(), trained.volume.dims()[0],
            trained.volume.dims()[1], trained.volume.dims()[2], eval["psnr"].get<double>(),
            eval["ssim"].get<double>(), trained.json["peak_rss_bytes"].get<double>() / 1048576.0,
            eval_cleaned["psnr"].get<double>(), deform["ms_per_frame"].get<double>(),
            deform["volume_ratio"].get<double>(), deform["inverted_tets"].get<long long>(), watch));
    nlohmann::ordered_json j;
    j["dataset"] = dataset_json;
    j["train"] = trained.json;
    j["train"]["output"] = (out / "reconstructed.nrrd").string();
    j["held_out_psnr"] = eval["psnr"];
    j["held_out_ssim"] = eval["ssim"];
    j["cleaned_held_out_psnr"] = eval_cleaned["psnr"];
    j["compare_png"] = (out / "compare.png").string();
    j["cleaned"] = (out / "cleaned.nrrd").string();
    j["deform"] = deform;
    return j;
}

// A `pliant cloth` run's preview (its stats.json object): the path, or null when none was made.
nlohmann::ordered_json preview_of(const nlohmann::ordered_json& stats) {
    return stats.contains("preview") ? stats["preview"] : nlohmann::ordered_json();
}

// The same for printing: "none" when none was made.
std::string shown_preview(const nlohmann::ordered_json& stats) {
    return stats.contains("preview") ? stats["preview"].get<std::string>() : "none";
}

// Step 4b: the drape scene (drape_json) without self-collision for UNTANGLE_FALL_FRAMES frames,
// DIR/untangle/fall/scene.json run into DIR/untangle/fall (the sheet falls through itself); a
// scene whose cloth is that run's last frame, DIR/untangle/scene.json (the drape's other keys,
// `frames` frames; the frame is the new cloth's rest shape: its masses, edge lengths and fold
// angles), run through `pliant cloth` into DIR/untangle: untangled before frame 0, then simulated
// with self-collision.
nlohmann::ordered_json untangle_demo(const std::filesystem::path& dir, const char* drape_json,
                                     int frames, bool quiet) {
    // At frame 16 the sheet has fallen through itself where its skirt folds (hundreds of pairs).
    constexpr int UNTANGLE_FALL_FRAMES = 16;
    const std::filesystem::path out = dir / "untangle";
    const std::filesystem::path fall_dir = out / "fall";
    const bool progress = !quiet && ::isatty(::fileno(stderr)) != 0;

    // Each scene is written to SCENE_DIR/scene.json and read back from there, so the printed
    // command reproduces its run into SCENE_DIR.
    const auto run_written = [progress](const std::filesystem::path& scene_dir,
                                        const nlohmann::ordered_json& json) {
        make_output_directory(scene_dir);
        const std::filesystem::path path = scene_dir / "scene.json";
        io::write_file_atomically(path, [&](std::ostream& o) { o << json.dump(2) << '\n'; });
        std::pair<cloth::ClothScene, nlohmann::ordered_json> result{io::read_cloth_scene(path),
                                                                    nullptr};
        ClothRunOptions run;
        run.frames = json["frames"].get<int>();
        run.progress = progress;
        result.second = run_cloth_scene(result.first, path.string(), scene_dir, run);
        return result;
    };
    nlohmann::ordered_json fall_json = nlohmann::ordered_json::parse(drape_json);
    fall_json["self_collision"] = false;
    fall_json["frames"] = UNTANGLE_FALL_FRAMES;
    // The dihedral bending model: with the isometric one that scenes/drape.json chooses, the
    // skirt, softer in sharp folds, falls deeper through itself (1,157 pairs at frame 16
    // against 693), more than the untangler clears in its 400 iterations (491 left;
    // docs/performance.md, "isometric bending").
    fall_json["material"]["bending"] = "dihedral";
    // And single-edge stretch: with the stretch chains of scenes/drape.json the skirt, which then
    // keeps its length, swings through itself deeper still (2,410 pairs at frame 16), and 400
    // iterations leave 666 of them (this fall scene with "stretch_solver": "chains", then the
    // untangle scene on its frame 16, `--frames 0`).
    fall_json["material"]["stretch_solver"] = "edges";
    const auto [fall, fall_stats] = run_written(fall_dir, fall_json);
    const std::int64_t fall_pairs = fall_stats["frames"].back()["intersecting_pairs"];

    nlohmann::ordered_json scene_json = nlohmann::ordered_json::parse(drape_json);
    scene_json["cloth"] = {{"mesh", fmt::format("fall/frames/frame_{:04d}.{}", UNTANGLE_FALL_FRAMES,
                                                fall.frame_format)}};
    scene_json["frames"] = frames;
    const nlohmann::ordered_json stats = run_written(out, scene_json).second;
    const std::filesystem::path fall_path = fall_dir / "scene.json";
    const std::filesystem::path scene_path = out / "scene.json";
    const nlohmann::ordered_json& untangled = stats["untangle"];
    std::string what = "not run (the cloth did not intersect itself)";
    if (!untangled.is_null()) {
        what = fmt::format(
            "{} iterations, {:.0f} ms, {} pairs left, no vertex moved more than "
            "{:.1f} mm",
            untangled["iterations"].get<int>(), untangled["ms"].get<double>(),
            untangled["pairs_left"].get<std::int64_t>(),
            untangled["max_displacement_m"].get<double>() * 1e3);
    }
    say(quiet,
        fmt::format("untangling: the drape without self-collision falls through itself ({} "
                    "intersecting triangle pairs at frame {}; preview {});\n  reproduce: pliant "
                    "cloth {} --out {}\n  that frame as a new cloth (its rest shape), untangled "
                    "({}), then {} frames with self-collision: {} intersecting pairs in the worst "
                    "frame, {:.1f} ms per frame; preview {}\n  reproduce: pliant cloth {} --out "
                    "{}\n",
                    fall_pairs, UNTANGLE_FALL_FRAMES, shown_preview(fall_stats), fall_path.string(),
                    fall_dir.string(), what, frames,
                    stats["max_intersecting_pairs"].get<std::int64_t>(),
                    stats["mean_ms_per_frame"].get<double>(), shown_preview(stats),
                    scene_path.string(), out.string()));
    // Two sheets crossing like an X (the second tilted by 20 degrees through the first, the
    // intersection running from edge to edge): contour minimization alone stalls; a region move
    // takes one sheet out of the other; then they fall onto the ground, apart.
    const std::filesystem::path crossing_dir = out / "crossing";
    const nlohmann::ordered_json crossing_json = {
        {"cloth",
         {{"grid", {{"size", {1.0, 1.0}}, {"quads", {30, 30}}}},
          {"instances",
           {{{"translate", {0.0, 0.0, 0.6}}},
            {{"rotate_degrees", {20.0, 0.0, 0.0}}, {"translate", {0.0123, 0.0171, 0.6}}}}}}},
        {"obstacles", {{{"plane", {{"point", {0.0, 0.0, 0.0}}, {"normal", {0.0, 0.0, 1.0}}}}}}},
        {"frames", frames},
        {"substeps", 40}};
    const nlohmann::ordered_json crossing_stats = run_written(crossing_dir, crossing_json).second;
    const nlohmann::ordered_json& crossing_untangled = crossing_stats["untangle"];
    const std::filesystem::path crossing_path = crossing_dir / "scene.json";
    say(quiet,
        fmt::format(
            "untangling: two sheets crossing like an X ({} intersecting triangle pairs), {}; then "
            "{} frames: {} intersecting pairs in the worst frame; preview {}\n  reproduce: pliant "
            "cloth {} --out {}\n\n",
            crossing_stats["initial_intersecting_pairs"].get<std::int64_t>(),
            crossing_untangled.is_null()
                ? std::string("not untangled")
                : fmt::format("untangled in {} iterations with {} region move{}, {} pairs left",
                              crossing_untangled["iterations"].get<int>(),
                              crossing_untangled["region_moves"].get<int>(),
                              crossing_untangled["region_moves"].get<int>() == 1 ? "" : "s",
                              crossing_untangled["pairs_left"].get<std::int64_t>()),
            frames, crossing_stats["max_intersecting_pairs"].get<std::int64_t>(),
            shown_preview(crossing_stats), crossing_path.string(), crossing_dir.string()));

    return {{"fall_scene", fall_path.string()},
            {"fall_dir", fall_dir.string()},
            {"fall_frames", UNTANGLE_FALL_FRAMES},
            {"fall_intersecting_pairs", fall_pairs},
            {"fall_preview", preview_of(fall_stats)},
            {"scene", scene_path.string()},
            {"dir", out.string()},
            {"frames", frames},
            {"initial_intersecting_pairs", stats["initial_intersecting_pairs"]},
            {"untangle", untangled},
            {"max_intersecting_pairs", stats["max_intersecting_pairs"]},
            {"mean_ms_per_frame", stats["mean_ms_per_frame"]},
            {"preview", preview_of(stats)},
            {"crossing",
             {{"scene", crossing_path.string()},
              {"dir", crossing_dir.string()},
              {"initial_intersecting_pairs", crossing_stats["initial_intersecting_pairs"]},
              {"untangle", crossing_untangled},
              {"max_intersecting_pairs", crossing_stats["max_intersecting_pairs"]},
              {"preview", preview_of(crossing_stats)}}}};
}

void run_demo(const DemoOptions& options, const GlobalOptions& global) {
    const bool quiet = global.json;  // --json: stdout carries only the summary object
    const std::filesystem::path dir(options.out);
    make_output_directory(dir);
    const std::filesystem::path sheet_path = dir / "folded_sheet.ply";
    const std::filesystem::path sheet_t1_path = dir / "folded_sheet_t1.ply";
    const std::filesystem::path summary_path = dir / "summary.json";
    Stopwatch demo_watch;

    // Step 1: the folded drape-size sheet, static.
    bench::BvhWorkloadOptions workload_options;
    workload_options.sheet_size = DRAPE_SIZE;
    workload_options.wavelength *= DRAPE_SIZE;  // the benchmark's shape, scaled to 2 m
    const bench::BvhWorkload workload = bench::BvhWorkload::make(DRAPE_TRIANGLES, workload_options);
    const geometry::TriangleMesh& sheet = workload.mesh;
    io::write_mesh(sheet_path, sheet);
    const float edge = workload.edge_length;
    const auto inflation = static_cast<double>(workload.inflation);
    say(quiet,
        fmt::format("pliant demo: self-collision broad phase (LBVH + R-triangles + orphan sets)\n\n"
                    "sheet: {} m x {} m, {} x {} quads, {} triangles, {} vertices, edge {:.6f} m\n"
                    "folded like an accordion: panels {} m, layers {:.6f} m (1.5 edges) apart\n"
                    "written to {}\n\n",
                    DRAPE_SIZE, DRAPE_SIZE, workload.quads_per_side, workload.quads_per_side,
                    thousands(static_cast<std::int64_t>(sheet.num_triangles())),
                    thousands(static_cast<std::int64_t>(sheet.num_vertices())), edge,
                    workload_options.panel_fraction * DRAPE_SIZE, workload_options.gap_edges * edge,
                    sheet_path.string()));

    geometry::TriangleMeshD sheet_d;
    sheet_d.positions = to_double(sheet.positions);
    sheet_d.triangles = sheet.triangles;
    const nlohmann::ordered_json static_result =
        measure(sheet_d, sheet_d.positions, inflation, false);
    say(quiet,
        format_broad_phase(fmt::format("static, inflation {} m (a quarter edge):", inflation),
                           static_result));
    say(quiet, fmt::format("  reproduce: pliant collide {} --inflate {} --repeat {}\n\n",
                           sheet_path.string(), inflation, COLLIDE_REPEATS));

    // Step 2: swept to a moved copy.
    const std::vector<Vec3f> moved = workload.positions(1);
    geometry::TriangleMesh sheet_t1{moved, sheet.triangles};
    io::write_mesh(sheet_t1_path, sheet_t1);
    const std::vector<Vec3d> moved_d = to_double(moved);
    const nlohmann::ordered_json swept_result = measure(sheet_d, moved_d, inflation, true);
    say(quiet,
        format_broad_phase(
            fmt::format("swept to a moved copy (sine wave, amplitude {:.6f} m), inflation {} m:",
                        workload.amplitude, inflation),
            swept_result));
    say(quiet,
        fmt::format("  reproduce: pliant collide {} --to {} --inflate {} --repeat {} --ccd\n\n",
                    sheet_path.string(), sheet_t1_path.string(), inflation, COLLIDE_REPEATS));

    // Step 3: the paper's BVH table.
    bench::BvhTableOptions table_options;
    table_options.sizes = {2244, 27030, 35992};
    table_options.repeats = TABLE_REPEATS;
    table_options.threads = global.threads;
    if (::isatty(::fileno(stderr)) != 0) {
        table_options.progress = [](const std::string& message) {
            std::fprintf(stderr, "%s\n", message.c_str());
        };
    }
    say(quiet, "the paper's BVH table (Tables 1-3), measured now:\n");
    const bench::BvhTableResult table = bench::run_bvh_table(table_options);
    say(quiet, bench::format_bvh_table(table) + "\n");

    // Step 4: the built-in cloth scenes (scenes/*.json, built in).
    nlohmann::ordered_json cloth_summary = nlohmann::ordered_json::object();
    for (const BuiltInScene& built_in : BUILT_IN_SCENES) {
        const std::string file = fmt::format("scenes/{}.json", built_in.name);
        const cloth::ClothScene scene =
            io::parse_cloth_scene(built_in.json, file + " (built in)", ".");
        const int frames = options.cloth_frames >= 0 ? options.cloth_frames : scene.frames;
        const std::filesystem::path scene_dir = dir / built_in.name;
        say(quiet, fmt::format("{} ({}): {} frames of XPBD cloth, {} substeps per frame:\n",
                               built_in.what, file, frames, scene.substeps));
        ClothRunOptions run;
        run.frames = frames;
        run.progress = !quiet && ::isatty(::fileno(stderr)) != 0;
        const nlohmann::ordered_json stats = run_cloth_scene(scene, file, scene_dir, run);

        say(quiet, fmt::format("  {} triangles, {:.1f} ms per frame, {} intersecting triangle "
                               "pairs in the worst frame; preview {}\n  reproduce: pliant cloth "
                               "{} --out {}\n\n",
                               thousands(stats["triangles"].get<std::int64_t>()),
                               stats["mean_ms_per_frame"].get<double>(),
                               stats["max_intersecting_pairs"].get<std::int64_t>(),
                               shown_preview(stats), file, scene_dir.string()));
        cloth_summary[built_in.name] = {{"dir", scene_dir.string()},
                                        {"frames", frames},
                                        {"triangles", stats["triangles"]},
                                        {"mean_ms_per_frame", stats["mean_ms_per_frame"]},
                                        {"max_intersecting_pairs", stats["max_intersecting_pairs"]},
                                        {"preview", preview_of(stats)}};
    }

    // Step 4b: untangling the drape after it fell through itself without self-collision.
    const char* drape_json = nullptr;
    for (const BuiltInScene& built_in : BUILT_IN_SCENES) {
        if (std::string_view(built_in.name) == "drape") {
            drape_json = built_in.json;
        }
    }
    if (drape_json == nullptr) {
        throw InternalError("demo: the built-in scenes have no drape scene");
    }
    constexpr int UNTANGLE_FRAMES = 24;
    const nlohmann::ordered_json untangle_summary =
        untangle_demo(dir, drape_json,
                      options.cloth_frames >= 0 ? std::min(options.cloth_frames, UNTANGLE_FRAMES)
                                                : UNTANGLE_FRAMES,
                      quiet);

    // Step 5: a volume rendered by the ray caster: the Colin27 brain (Debian mricron-data) or the
    // head CT (invesalius-examples), else the generated Shepp-Logan phantom; a PNG and a
    // turntable MP4 (PNG frames without ffmpeg).
    const DemoVolume demo_volume = load_demo_volume();
    const nlohmann::ordered_json volume_summary = render_demo_volume(dir, demo_volume, quiet);

    // Step 6: the same volume deformed: twisted by the XPBD soft body, resampled every frame and
    // ray-cast into a video.
    const nlohmann::ordered_json deform_summary =
        deform_demo_volume(dir, demo_volume, options, quiet);

    // Step 7: the paper's pipeline from images: dataset, radiance field, export, cleaning,
    // deformation.
    const nlohmann::ordered_json nerf_summary =
        reconstruct_demo_volume(dir, demo_volume, options, quiet);

    // Step 8: the summary.
    const nlohmann::ordered_json summary = {
        {"sheet",
         {{"size_m", DRAPE_SIZE},
          {"quads_per_side", workload.quads_per_side},
          {"triangles", sheet.num_triangles()},
          {"vertices", sheet.num_vertices()},
          {"edge_length_m", edge},
          {"panel_m", workload_options.panel_fraction * DRAPE_SIZE},
          {"layer_gap_m", workload_options.gap_edges * edge},
          {"wave_amplitude_m", workload.amplitude},
          {"file", sheet_path.string()},
          {"file_t1", sheet_t1_path.string()}}},
        {"static", static_result},
        {"swept", swept_result},
        {"bvh_table", bench::bvh_table_json(table)},
        {"drape", cloth_summary["drape"]},
        {"cloth", cloth_summary},
        {"untangle", untangle_summary},
        {"volume", volume_summary},
        {"deform", deform_summary},
        {"nerf", nerf_summary},
        {"threads", num_threads()},
        {"seconds", demo_watch.elapsed_ms() / 1000.0},
    };
    io::write_file_atomically(summary_path,
                              [&](std::ostream& out) { out << summary.dump(2) << '\n'; });

    if (global.json) {
        std::fputs((summary.dump(2) + "\n").c_str(), stdout);
    } else {
        say(quiet,
            fmt::format(
                "outputs in {}/:\n  {:<27}the folded sheet (binary PLY)\n  {:<27}its "
                "moved copy\n  {:<27}each cloth scene: preview.mp4 (watch these), frames (OBJ), "
                "stats.json\n  {:<27}the drape untangled after falling through itself: preview.mp4 "
                "(watch it), fall/preview.mp4 (the fall), scene.json, stats.json; crossing/ "
                "(two sheets crossing like an X, untangled): preview.mp4\n  {:<27}the "
                "ray-cast volume: volume.png, turntable.mp4\n  {:<27}the "
                "twisted volume: twist.mp4 (watch it), twist.png, twisted.nrrd\n  {:<27}from "
                "images: dataset/, reconstructed.nrrd, compare.png (look at it), cleaned.nrrd, "
                "twist.mp4 (watch it)\n  {:<27}every number above\n",
                dir.string(), sheet_path.filename().string(), sheet_t1_path.filename().string(),
                "drape/ twist/ pile/ flag/", "untangle/", "volume/", "deform/", "nerf/",
                summary_path.filename().string()));
    }
    if (!table.ok()) {
        std::string errors;
        for (const std::string& e : table.errors()) {
            errors += "\n  " + e;
        }
        throw InternalError("demo: the BVH table's pair counts disagree:" + errors);
    }
}

}  // namespace

void register_demo(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "demo",
        "Everything pliant does today, end to end, on embedded and installed data: self-collision "
        "broad and narrow phase on a folded sheet, the paper's BVH table, the four cloth scenes, "
        "untangling a sheet that fell through itself, a volume ray-cast and twisted, and the "
        "paper's pipeline from images (dataset, radiance "
        "field, cleaning, deformation); writes everything under --out and summary.json");
    cmd->add_option("--out", options->out, "Output directory (created if missing)")
        ->type_name("DIR")
        ->check(non_empty_path());
    cmd->add_option(
           "--cloth-frames", options->cloth_frames,
           "Frames of each cloth scene (default: the scene's own; the untangling step runs at "
           "most 24)")
        ->check(CLI::Range(0, 100'000));
    cmd->add_option("--deform-frames", options->deform_frames,
                    "Frames of the twisted volumes' animations (default 48)")
        ->check(CLI::Range(1, 100'000));
    CLI::Option* minutes =
        cmd->add_option("--nerf-minutes", options->nerf_minutes,
                        "Training budget of the radiance field, minutes (default 2)")
            ->check(finite_in_range(0.001, 1e4));
    cmd->add_option("--nerf-iterations", options->nerf_iterations,
                    "A fixed number of training iterations instead of --nerf-minutes "
                    "(reproducible)")
        ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
        ->excludes(minutes);
    cmd->add_option("--nerf-resolution", options->nerf_resolution,
                    "The radiance field's final grid, voxels on the longest side (default 128)")
        ->check(CLI::Range(8, 1024));
    cmd->add_option("--nerf-views", options->nerf_views,
                    "Views of the radiance field's dataset (default 100; every 10th held out)")
        ->check(CLI::Range(11, 100'000));
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_demo(*options, global); });
}

}  // namespace pliant::cli
