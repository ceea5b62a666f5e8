#include "pliant/pipeline/demo.hpp"

#include <fmt/format.h>

#include <array>
#include <memory>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/pipeline/cloth_run.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/deform_run.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"
#include "pliant/pipeline/nerf_run.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/clean.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::pipeline {

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

nlohmann::ordered_json render_demo_volume(const std::filesystem::path& dir,
                                          const DemoVolume& demo) {
    const volume::Volume& v = demo.volume;
    const std::string& source = demo.source;
    const std::string& preset = demo.preset;
    const volume::TransferFunction tf = volume::preset(preset, v);
    render::RayCastOptions options;
    options.shading = true;
    const render::RayCaster caster(v, &tf, options);
    const std::filesystem::path out = dir / "volume";
    io::make_output_directory(out);
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
    return {{"source", source},
            {"dims", {v.dims()[0], v.dims()[1], v.dims()[2]}},
            {"transfer_function", preset},
            {"png", (out / "volume.png").string()},
            {"png_ms", still.ms},
            {"turntable", turntable},
            {"turntable_ms_per_frame", turntable_ms / TURNTABLE_FRAMES}};
}

DemoStep twist_volume(const volume::Volume& source, const volume::TransferFunction* tf,
                      const std::filesystem::path& out, int frames, const ProgressFn& progress) {
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

DemoStep deform_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo, int frames,
                            const ProgressFn& progress) {
    const std::filesystem::path out = dir / "deform";
    io::make_output_directory(out);
    const volume::TransferFunction tf = volume::preset(demo.preset, demo.volume);
    return twist_volume(demo.volume, &tf, out, frames, progress);
}

DemoStep reconstruct_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo,
                                 const ReconstructOptions& options) {
    const std::filesystem::path out = dir / "nerf";
    io::make_output_directory(out);
    const volume::TransferFunction tf = volume::preset(demo.preset, demo.volume);

    DatasetRunOptions dataset_run;
    dataset_run.views = options.views;
    const nlohmann::ordered_json dataset_json =
        render_dataset(demo.volume, &tf, dataset_run, out / "dataset");
    const nerf::Dataset train_set =
        pipeline::read_nerf_dataset(out / "dataset" / "transforms_train.json");
    const nerf::Dataset test_set =
        pipeline::read_nerf_dataset(out / "dataset" / "transforms_test.json");

    TrainRunOptions train_run;
    if (options.iterations > 0) {
        train_run.train.iterations = options.iterations;
    } else {
        train_run.train.seconds = 60.0 * options.minutes;
    }
    train_run.train.resolution = options.resolution;
    train_run.exported.resolution = 256;
    train_run.on_progress = options.on_train_progress;
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
        twist_volume(cleaned, nullptr, out, options.deform_frames, options.progress);

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
    return {j, watch};
}

nlohmann::ordered_json untangle_demo(const std::filesystem::path& dir, const char* drape_json,
                                     int frames, const ProgressFn& progress) {
    // At frame 16 the sheet has fallen through itself where its skirt folds (hundreds of pairs).
    const std::filesystem::path out = dir / "untangle";
    const std::filesystem::path fall_dir = out / "fall";

    // Each scene is written to SCENE_DIR/scene.json and read back from there, so the printed
    // command reproduces its run into SCENE_DIR.
    const auto run_written = [&progress](const std::filesystem::path& scene_dir,
                                         const nlohmann::ordered_json& json) {
        io::make_output_directory(scene_dir);
        const std::filesystem::path path = scene_dir / "scene.json";
        io::write_file_atomically(path, [&](std::ostream& o) { o << json.dump(2) << '\n'; });
        std::pair<cloth::ClothScene, nlohmann::ordered_json> result{
            pipeline::read_cloth_scene(path), nullptr};
        ClothRunOptions run;
        run.frames = json["frames"].get<int>();
        run.progress = progress;
        run.checkpoint_every = 0;  // a demo's short runs are not resumed
        result.second = run_cloth_scene(result.first, path.string(), scene_dir, run);
        return result;
    };
    nlohmann::ordered_json fall_json = nlohmann::ordered_json::parse(drape_json);
    fall_json["self_collision"] = false;
    fall_json["frames"] = UNTANGLE_FALL_FRAMES;
    // Dihedral bending and single-edge stretch: with the isometric bending and stretch chains of
    // scenes/drape.json the skirt falls deeper through itself than the untangler's 400
    // iterations clear (docs/journal/2026-11-25-isometric-bending.md,
    // docs/journal/2026-11-28-stretch-chains.md).
    fall_json["material"]["bending"] = "dihedral";
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

nlohmann::ordered_json preview_of(const nlohmann::ordered_json& stats) {
    return stats.contains("preview") ? stats["preview"] : nlohmann::ordered_json();
}

}  // namespace pliant::pipeline
