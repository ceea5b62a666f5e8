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
// summary). The steps are library calls (pipeline/demo.hpp); this file parses, calls and prints.
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

#include "commands.hpp"
#include "peers/bvh_table.hpp"
#include "peers/bvh_workload.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/pipeline/broad_phase_report.hpp"
#include "pliant/pipeline/built_in_scenes.hpp"
#include "pliant/pipeline/cloth_run.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/deform_run.hpp"
#include "pliant/pipeline/demo.hpp"
#include "pliant/pipeline/garment_scene.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"
#include "pliant/pipeline/nerf_run.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "progress_bar.hpp"
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
    return pipeline::to_json(pipeline::measure_broad_phase(mesh, positions_t1, inflation,
                                                           COLLIDE_REPEATS, swept,
                                                           /*warm_up=*/true, /*narrow=*/swept));
}

std::string format_broad_phase(const std::string& title, const nlohmann::ordered_json& r) {
    std::string text = title + "\n";
    text += fmt::format("  {:<16}{:>10}   {:<16}{:>10}   {:<16}{:>10}\n", "triangle pairs",
                        pipeline::thousands(r["triangle_pairs"].get<std::int64_t>()), "VF pairs",
                        pipeline::thousands(r["vf_pairs"].get<std::int64_t>()), "EE pairs",
                        pipeline::thousands(r["ee_pairs"].get<std::int64_t>()));
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
                            pipeline::thousands(r["vf_hits"].get<std::int64_t>()), "EE hits",
                            pipeline::thousands(r["ee_hits"].get<std::int64_t>()),
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

// A preview's path as printed: "none" when none was made (null).
std::string shown(const nlohmann::ordered_json& preview) {
    return preview.is_null() ? "none" : preview.get<std::string>();
}

// What each step prints, from its JSON (pipeline/demo.hpp).
void print_volume(const nlohmann::ordered_json& r, bool quiet) {
    const std::filesystem::path png = r["png"].get<std::string>();
    say(quiet, fmt::format("a volume through the ray caster: {}, {} x {} x {} voxels, transfer "
                           "function {}:\n  {} ({:.1f} ms at 512 x 512), turntable {} ({:.1f} ms "
                           "per 384 x 384 frame)\n\n",
                           r["source"].get<std::string>(), r["dims"][0].get<int>(),
                           r["dims"][1].get<int>(), r["dims"][2].get<int>(),
                           r["transfer_function"].get<std::string>(), png.string(),
                           r["png_ms"].get<double>(), r["turntable"].get<std::string>(),
                           r["turntable_ms_per_frame"].get<double>()));
}

void print_deform(const pipeline::DemoStep& step, bool quiet) {
    const nlohmann::ordered_json& result = step.json;
    const std::string& watch = step.watch;
    say(quiet,
        fmt::format("the volume twisted (tet grid + XPBD + resampling + ray casting): {} tets, "
                    "{:.1f} ms per substep, {:.1f} ms per resampling, {:.1f} ms per frame; "
                    "volume ratio {:.4f}, {} inverted tets:\n  {}\n\n",
                    result["tets"].get<long long>(), result["ms_per_substep"].get<double>(),
                    result["resample_ms"].get<double>(), result["ms_per_frame"].get<double>(),
                    result["volume_ratio"].get<double>(), result["inverted_tets"].get<long long>(),
                    watch));
}

void print_reconstruction(const pipeline::DemoStep& step, bool quiet) {
    const nlohmann::ordered_json& j = step.json;
    const nlohmann::ordered_json& dataset_json = j["dataset"];
    const nlohmann::ordered_json& train = j["train"];
    const nlohmann::ordered_json& deform = j["deform"];
    say(quiet,
        fmt::format(
            "the paper's pipeline from images: {} views of {} x {} rendered from the volume "
            "({}), a radiance field trained for {:.0f} s ({} iterations, grid {}), exported at "
            "{} x {} x {} RGBA:\n  held-out views: PSNR {:.2f} dB, SSIM {:.4f}; peak memory "
            "{:.0f} MiB; compare.png shows a held-out view, its reconstruction, the cleaned "
            "one\n  cleaned (threshold 5, alpha normalization; held-out PSNR {:.2f} dB), twisted: "
            "{:.1f} ms per frame, volume ratio {:.4f}, {} inverted tets:\n  {}\n\n",
            dataset_json["views"].get<int>(), dataset_json["width"].get<int>(),
            dataset_json["height"].get<int>(), dataset_json["output"].get<std::string>(),
            train["seconds"].get<double>(), train["iterations"].get<long long>(),
            train["resolution"].get<int>(), train["volume_dims"][0].get<int>(),
            train["volume_dims"][1].get<int>(), train["volume_dims"][2].get<int>(),
            j["held_out_psnr"].get<double>(), j["held_out_ssim"].get<double>(),
            train["peak_rss_bytes"].get<double>() / 1048576.0,
            j["cleaned_held_out_psnr"].get<double>(), deform["ms_per_frame"].get<double>(),
            deform["volume_ratio"].get<double>(), deform["inverted_tets"].get<long long>(),
            step.watch));
}

void print_untangle(const nlohmann::ordered_json& r, bool quiet) {
    const nlohmann::ordered_json& untangled = r["untangle"];
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
                    r["fall_intersecting_pairs"].get<std::int64_t>(), r["fall_frames"].get<int>(),
                    shown(r["fall_preview"]), r["fall_scene"].get<std::string>(),
                    r["fall_dir"].get<std::string>(), what, r["frames"].get<int>(),
                    r["max_intersecting_pairs"].get<std::int64_t>(),
                    r["mean_ms_per_frame"].get<double>(), shown(r["preview"]),
                    r["scene"].get<std::string>(), r["dir"].get<std::string>()));
    const nlohmann::ordered_json& crossing = r["crossing"];
    const nlohmann::ordered_json& crossing_untangled = crossing["untangle"];
    say(quiet,
        fmt::format(
            "untangling: two sheets crossing like an X ({} intersecting triangle pairs), {}; then "
            "{} frames: {} intersecting pairs in the worst frame; preview {}\n  reproduce: pliant "
            "cloth {} --out {}\n\n",
            crossing["initial_intersecting_pairs"].get<std::int64_t>(),
            crossing_untangled.is_null()
                ? std::string("not untangled")
                : fmt::format("untangled in {} iterations with {} region move{}, {} pairs left",
                              crossing_untangled["iterations"].get<int>(),
                              crossing_untangled["region_moves"].get<int>(),
                              crossing_untangled["region_moves"].get<int>() == 1 ? "" : "s",
                              crossing_untangled["pairs_left"].get<std::int64_t>()),
            r["frames"].get<int>(), crossing["max_intersecting_pairs"].get<std::int64_t>(),
            shown(crossing["preview"]), crossing["scene"].get<std::string>(),
            crossing["dir"].get<std::string>()));
}

void run_demo(const DemoOptions& options, const GlobalOptions& global) {
    const bool quiet = global.json;  // --json: stdout carries only the summary object
    const std::filesystem::path dir(options.out);
    io::make_output_directory(dir);
    const std::filesystem::path sheet_path = dir / "folded_sheet.ply";
    const std::filesystem::path sheet_t1_path = dir / "folded_sheet_t1.ply";
    const std::filesystem::path summary_path = dir / "summary.json";
    Stopwatch demo_watch;
    const pipeline::ProgressFn progress = frame_progress(!quiet && stderr_is_terminal());

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
                    pipeline::thousands(static_cast<std::int64_t>(sheet.num_triangles())),
                    pipeline::thousands(static_cast<std::int64_t>(sheet.num_vertices())), edge,
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
    if (stderr_is_terminal()) {
        table_options.progress = [](const std::string& message) {
            std::fprintf(stderr, "%s\n", message.c_str());
        };
    }
    say(quiet, "the paper's BVH table (Tables 1-3), measured now:\n");
    const bench::BvhTableResult table = bench::run_bvh_table(table_options);
    say(quiet, bench::format_bvh_table(table) + "\n");

    // Step 4: the built-in cloth scenes (scenes/*.json, built in).
    nlohmann::ordered_json cloth_summary = nlohmann::ordered_json::object();
    for (const pipeline::BuiltInScene& built_in : pipeline::BUILT_IN_SCENES) {
        const std::string file = fmt::format("scenes/{}.json", built_in.name);
        const cloth::ClothScene scene =
            pipeline::parse_cloth_scene(built_in.json, file + " (built in)", ".");
        const int frames = options.cloth_frames >= 0 ? options.cloth_frames : scene.frames;
        const std::filesystem::path scene_dir = dir / built_in.name;
        say(quiet, fmt::format("{} ({}): {} frames of XPBD cloth, {} substeps per frame:\n",
                               built_in.what, file, frames, scene.substeps));
        pipeline::ClothRunOptions run;
        run.frames = frames;
        run.progress = progress;
        run.checkpoint_every = 0;  // a demo's short runs are not resumed
        const nlohmann::ordered_json stats = pipeline::run_cloth_scene(scene, file, scene_dir, run);

        say(quiet, fmt::format("  {} triangles, {:.1f} ms per frame, {} intersecting triangle "
                               "pairs in the worst frame; preview {}\n  reproduce: pliant cloth "
                               "{} --out {}\n\n",
                               pipeline::thousands(stats["triangles"].get<std::int64_t>()),
                               stats["mean_ms_per_frame"].get<double>(),
                               stats["max_intersecting_pairs"].get<std::int64_t>(),
                               shown(pipeline::preview_of(stats)), file, scene_dir.string()));
        cloth_summary[built_in.name] = {{"dir", scene_dir.string()},
                                        {"frames", frames},
                                        {"triangles", stats["triangles"]},
                                        {"mean_ms_per_frame", stats["mean_ms_per_frame"]},
                                        {"max_intersecting_pairs", stats["max_intersecting_pairs"]},
                                        {"preview", pipeline::preview_of(stats)}};
    }

    // Step 4a: a skirt sewn from two flat panels on a walking mannequin (garment_scene.hpp).
    {
        const std::filesystem::path garment_dir = dir / "garment";
        const int frames = options.cloth_frames >= 0 ? options.cloth_frames : 96;
        say(quiet, fmt::format("a skirt of two panels sewn on a walking mannequin "
                               "({}/scene.json): {} frames:\n",
                               garment_dir.string(), frames));
        const nlohmann::ordered_json stats = pipeline::garment_demo(garment_dir, frames, progress);
        say(quiet, fmt::format("  {} triangles, {:.1f} ms per frame, {} intersecting triangle "
                               "pairs in the worst frame; preview {}\n  reproduce: pliant cloth "
                               "{}/scene.json --out DIR\n\n",
                               pipeline::thousands(stats["triangles"].get<std::int64_t>()),
                               stats["mean_ms_per_frame"].get<double>(),
                               stats["max_intersecting_pairs"].get<std::int64_t>(),
                               shown(pipeline::preview_of(stats)), garment_dir.string()));
        cloth_summary["garment"] = {{"dir", garment_dir.string()},
                                    {"frames", frames},
                                    {"triangles", stats["triangles"]},
                                    {"mean_ms_per_frame", stats["mean_ms_per_frame"]},
                                    {"max_intersecting_pairs", stats["max_intersecting_pairs"]},
                                    {"preview", pipeline::preview_of(stats)}};
    }

    // Step 4b: untangling the drape after it fell through itself without self-collision.
    const char* drape_json = nullptr;
    for (const pipeline::BuiltInScene& built_in : pipeline::BUILT_IN_SCENES) {
        if (std::string_view(built_in.name) == "drape") {
            drape_json = built_in.json;
        }
    }
    if (drape_json == nullptr) {
        throw InternalError("demo: the built-in scenes have no drape scene");
    }
    constexpr int UNTANGLE_FRAMES = 24;
    const nlohmann::ordered_json untangle_summary = pipeline::untangle_demo(
        dir, drape_json,
        options.cloth_frames >= 0 ? std::min(options.cloth_frames, UNTANGLE_FRAMES)
                                  : UNTANGLE_FRAMES,
        progress);
    print_untangle(untangle_summary, quiet);

    // Step 5: a volume rendered by the ray caster: the Colin27 brain (Debian mricron-data) or the
    // head CT (invesalius-examples), else the generated Shepp-Logan phantom; a PNG and a
    // turntable MP4 (PNG frames without ffmpeg).
    const pipeline::DemoVolume demo_volume = pipeline::load_demo_volume();
    const nlohmann::ordered_json volume_summary = pipeline::render_demo_volume(dir, demo_volume);
    print_volume(volume_summary, quiet);

    // Step 6: the same volume deformed: twisted by the XPBD soft body, resampled every frame and
    // ray-cast into a video.
    const pipeline::DemoStep deformed =
        pipeline::deform_demo_volume(dir, demo_volume, options.deform_frames, progress);
    print_deform(deformed, quiet);

    // Step 7: the paper's pipeline from images: dataset, radiance field, export, cleaning,
    // deformation.
    const pipeline::DemoStep reconstructed = pipeline::reconstruct_demo_volume(
        dir, demo_volume,
        {.views = options.nerf_views,
         .minutes = options.nerf_minutes,
         .iterations = options.nerf_iterations,
         .resolution = options.nerf_resolution,
         .deform_frames = options.deform_frames,
         .progress = progress,
         .on_train_progress = train_progress(!quiet && stderr_is_terminal())});
    print_reconstruction(reconstructed, quiet);

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
        {"deform", deformed.json},
        {"nerf", reconstructed.json},
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
                "(two sheets crossing like an X, untangled): preview.mp4\n  {:<27}a skirt of "
                "two sewn panels on a walking mannequin: preview.mp4 (watch it), frames (OBJ with "
                "the panels' quads and UVs), cloth.pc2, scene.json, stats.json\n  {:<27}the "
                "ray-cast volume: volume.png, turntable.mp4\n  {:<27}the "
                "twisted volume: twist.mp4 (watch it), twist.png, twisted.nrrd\n  {:<27}from "
                "images: dataset/, reconstructed.nrrd, compare.png (look at it), cleaned.nrrd, "
                "twist.mp4 (watch it)\n  {:<27}every number above\n",
                dir.string(), sheet_path.filename().string(), sheet_t1_path.filename().string(),
                "drape/ twist/ pile/ flag/", "untangle/", "garment/", "volume/", "deform/", "nerf/",
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
