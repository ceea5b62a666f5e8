#include "pliant/pipeline/nerf_run.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <system_error>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::pipeline {

std::int64_t peak_rss_bytes() {
    struct rusage usage {};
    ::getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;  // Linux: kilobytes
}

nlohmann::ordered_json render_dataset(const volume::Volume& source,
                                      const volume::TransferFunction* tf,
                                      const DatasetRunOptions& options,
                                      const std::filesystem::path& dir) {
    const Stopwatch watch;
    render::RayCastOptions ro;
    ro.step = options.step;
    ro.background = {options.background[0], options.background[1], options.background[2]};
    const render::RayCaster caster(source, tf, ro);

    io::make_output_directory(dir / "train");
    io::make_output_directory(dir / "test");

    const AABBd box = source.bounds();
    render::FramingOptions framing;
    framing.fov_y_degrees = options.fov;
    std::vector<std::string> names[2];
    std::vector<nerf::Pose> poses[2];
    nerf::Intrinsics intrinsics;
    render::Image image;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));  // 137.508°
    for (int i = 0; i < options.views; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / options.views;
        const double azimuth =
            std::fmod(i * golden, 2.0 * std::numbers::pi) * 180.0 / std::numbers::pi;
        const double elevation = std::asin(z) * 180.0 / std::numbers::pi;
        const render::Camera camera =
            render::frame_box(box, azimuth, elevation, options.size[0], options.size[1], framing);
        caster.render(camera, image);
        const int split = i % options.test_every == 0 ? 1 : 0;
        const std::string name = fmt::format("{}/r_{}", split == 1 ? "test" : "train", i);
        io::write_png(dir / (name + ".png"), image);
        names[split].push_back("./" + name);
        poses[split].push_back(nerf::pose_from_camera(camera));
        intrinsics = nerf::intrinsics_from_camera(camera);
    }
    pipeline::write_transforms(dir / "transforms_train.json", intrinsics, names[0], poses[0], box);
    pipeline::write_transforms(dir / "transforms_test.json", intrinsics, names[1], poses[1], box);

    nlohmann::ordered_json j;
    j["output"] = dir.string();
    j["views"] = options.views;
    j["train"] = names[0].size();
    j["test"] = names[1].size();
    j["width"] = options.size[0];
    j["height"] = options.size[1];
    j["ms"] = watch.elapsed_ms();
    return j;
}

TrainRunResult train_volume(const nerf::Dataset& dataset, const TrainRunOptions& options,
                            FunctionRef<bool()> keep_going) {
    // The output's size, checked before a long run (the grid's is checked by nerf::train).
    const AABBd box = nerf::scene_box(dataset);
    const std::size_t out_bytes = nerf::export_bytes(box, options.exported);
    if (out_bytes > options.exported.max_bytes) {
        const volume::Dims d = nerf::export_dims(box, options.exported.resolution);
        throw InvalidInput(fmt::format(
            "nerf train: the exported {} x {} x {} {} volume would need {:.0f} MiB, more than the "
            "memory limit of {:.0f} MiB (lower --export-resolution)",
            d[0], d[1], d[2], volume::name(options.exported.type), out_bytes / 1048576.0,
            options.exported.max_bytes / 1048576.0));
    }
    const nerf::TrainResult result =
        nerf::train(dataset, options.train, [&](const nerf::TrainProgress& p) {
            if (options.on_progress) {
                options.on_progress(p);
            }
            return keep_going();
        });

    TrainRunResult out;
    out.volume = nerf::export_volume(result.grid, options.exported);
    if (options.clean) {
        volume::clean(out.volume, *options.clean);
    }
    out.stopped = result.stopped;
    const volume::Volume& vol = out.volume;
    const auto& gd = result.grid.dims();
    nlohmann::ordered_json& j = out.json;
    j["iterations"] = result.iterations;
    j["seconds"] = result.elapsed_ms / 1000.0;
    j["train_psnr"] = result.final_loss > 0.0 ? -10.0 * std::log10(result.final_loss) : 99.0;
    j["resolution"] = result.grid.resolution();
    j["grid_dims"] = {gd[0], gd[1], gd[2]};
    j["occupied_cells"] = result.grid.num_occupied();
    j["volume_dims"] = vol.dims();
    j["volume_spacing"] = {vol.spacing().x, vol.spacing().y, vol.spacing().z};
    j["peak_rss_bytes"] = peak_rss_bytes();
    j["interrupted"] = result.stopped;
    return out;
}

nlohmann::ordered_json evaluate_volume(const nerf::Dataset& dataset, const volume::Volume& volume,
                                       const std::array<float, 3>& background,
                                       const std::filesystem::path& images_dir) {
    if (volume::channels(volume.type()) != 4) {
        throw InvalidInput(fmt::format("nerf eval: a {} volume; an RGBA volume is needed",
                                       volume::name(volume.type())));
    }
    render::RayCastOptions rco;
    rco.background = {background[0], background[1], background[2]};
    const render::RayCaster caster(volume, nullptr, rco);
    if (!images_dir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(images_dir, ec);
        if (!std::filesystem::is_directory(images_dir)) {
            throw IoError(fmt::format("{}: cannot create the directory", images_dir.string()));
        }
    }
    nlohmann::ordered_json views = nlohmann::ordered_json::array();
    double sum_psnr = 0.0, sum_ssim = 0.0;
    render::Image image;
    for (std::size_t i = 0; i < dataset.views.size(); ++i) {
        const nerf::View& v = dataset.views[i];
        caster.render(nerf::camera_from_view(dataset.intrinsics, v.camera_to_world), image);
        const std::vector<float> rgb = nerf::from_image(image);
        const double p = nerf::psnr(rgb, v.rgb);
        const double s = nerf::ssim(rgb, v.rgb, image.width, image.height);
        sum_psnr += p;
        sum_ssim += s;
        nlohmann::ordered_json e;
        e["file_path"] = v.name;
        e["psnr"] = p;
        e["ssim"] = s;
        views.push_back(e);
        if (!images_dir.empty()) {
            io::write_png(images_dir / fmt::format("{}.png", i), image);
        }
    }
    const double n = static_cast<double>(dataset.views.size());
    nlohmann::ordered_json j;
    j["psnr"] = sum_psnr / n;
    j["ssim"] = sum_ssim / n;
    j["views"] = views;
    return j;
}

}  // namespace pliant::pipeline
