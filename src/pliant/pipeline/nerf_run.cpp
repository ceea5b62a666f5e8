#include "pliant/pipeline/nerf_run.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/checkpoint.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/nerf/camera_refinement.hpp"
#include "pliant/nerf/crop.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/pose_alignment.hpp"
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

    const AABBd box = source.world_bounds();  // an oblique volume is rendered in world space
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

namespace {

// What training's result depends on (io::run_fingerprint): the dataset (intrinsics, poses,
// images, box, background) and the training options; not the thread count.
std::uint64_t train_fingerprint(const nerf::Dataset& dataset, const nerf::TrainOptions& o) {
    ByteWriter w;
    w.put_string("pliant nerf train");
    const nerf::Intrinsics& in = dataset.intrinsics;
    w.put(in.width);
    w.put(in.height);
    for (const double v : {in.fx, in.fy, in.cx, in.cy}) {
        w.put(v);
    }
    for (const nerf::View& view : dataset.views) {
        w.put(view.camera_to_world.m);
        w.put_vector(view.rgb);
    }
    w.put(dataset.box.has_value());
    if (dataset.box) {
        w.put(dataset.box->lo);
        w.put(dataset.box->hi);
    }
    w.put(dataset.background.r);
    w.put(dataset.background.g);
    w.put(dataset.background.b);
    w.put(o.resolution);
    w.put(o.stages);
    w.put(o.iterations);
    w.put(o.seconds);
    w.put(o.batch_rays);
    for (const float v :
         {o.lr_density, o.lr_color, o.lr_final_factor, o.tv_density, o.tv_color, o.density_init,
          o.color_init, o.occupancy_alpha, o.render.step_voxels, o.render.min_transmittance}) {
        w.put(v);
    }
    w.put(o.occupancy_interval);
    w.put(o.warmup_iterations);
    w.put(o.render.use_occupancy);
    w.put(o.seed);
    if (o.sparsity > 0.0f) {  // likewise
        w.put_string("sparsity");
        w.put(o.sparsity);
    }
    if (o.environment_width > 0) {  // older checkpoints (no environment) keep their fingerprint
        w.put_string("environment");
        w.put(o.environment_width);
        w.put(o.lr_environment);
    }
    if (o.distortion > 0.0f) {  // likewise
        w.put_string("distortion");
        w.put(o.distortion);
    }
    if (o.exposure) {  // likewise
        w.put_string("exposure");
        w.put(o.lr_exposure);
        w.put(o.exposure_prior);
    }
    if (o.refine_poses || o.refine_focal) {
        w.put_string("refine");
        w.put(o.refine_poses);
        w.put(o.refine_focal);
        w.put(o.lr_pose);
        w.put(o.lr_focal);
        w.put(o.refine_start);
    }
    return io::run_fingerprint(w.bytes());
}

// The held-out views moved by the training views' refinement (nerf::transfer_refinement) with
// the refined focal scale.
nerf::Dataset refined_test_views(const nerf::Dataset& train, const nerf::TrainResult& result,
                                 const nerf::Dataset& test) {
    std::vector<nerf::Pose> original, poses;
    for (const nerf::View& v : train.views) {
        original.push_back(v.camera_to_world);
    }
    for (const nerf::View& v : test.views) {
        poses.push_back(v.camera_to_world);
    }
    const std::vector<nerf::Pose> moved = nerf::transfer_refinement(original, result.poses, poses);
    nerf::Dataset out = test;
    const auto scale = [&](nerf::Intrinsics& in) {
        in.fx *= result.focal_scale;
        in.fy *= result.focal_scale;
    };
    scale(out.intrinsics);
    for (std::size_t i = 0; i < out.views.size(); ++i) {
        out.views[i].camera_to_world = moved[i];
        if (out.views[i].intrinsics) {
            scale(*out.views[i].intrinsics);
        }
    }
    return out;
}

// The training views' refined cameras as a transforms.json (write_transforms: the images are
// not rewritten; file_path names them as the dataset did).
void write_refined_poses(const nerf::Dataset& train, const nerf::TrainResult& result,
                         const std::filesystem::path& path) {
    nerf::Intrinsics in = train.intrinsics;
    in.fx *= result.focal_scale;
    in.fy *= result.focal_scale;
    std::vector<std::string> names;
    for (const nerf::View& v : train.views) {
        names.push_back(v.name);
    }
    write_transforms(path, in, names, result.poses, train.box);
}

}  // namespace

TrainRunResult train_volume(const nerf::Dataset& dataset, const TrainRunOptions& options,
                            FunctionRef<bool()> keep_going) {
    // The output's size, checked before a long run (the grid's is checked by nerf::train).
    // --crop auto: at most a cube of the box's largest side at the export resolution.
    AABBd box = options.crop.value_or(nerf::scene_box(dataset));
    if (options.auto_crop && !options.crop) {
        const Vec3d e = box.extent();
        box.hi = box.lo + Vec3d{1, 1, 1} * std::max({e.x, e.y, e.z});
    }
    const std::size_t out_bytes = nerf::export_bytes(box, options.exported);
    if (out_bytes > options.exported.max_bytes) {
        const volume::Dims d = nerf::export_dims(box, options.exported.resolution);
        throw InvalidInput(fmt::format(
            "nerf train: the exported {} x {} x {} {} volume would need {:.0f} MiB, more than the "
            "memory limit of {:.0f} MiB (lower --export-resolution)",
            d[0], d[1], d[2], volume::name(options.exported.type), out_bytes / 1048576.0,
            options.exported.max_bytes / 1048576.0));
    }
    nerf::TrainCheckpoints checkpoints;
    io::Checkpoint resumed;
    std::error_code ec;
    if (!options.checkpoint.empty()) {
        const std::uint64_t fingerprint = train_fingerprint(dataset, options.train);
        if (options.resume && std::filesystem::exists(options.checkpoint, ec)) {
            resumed =
                io::read_checkpoint(options.checkpoint, io::CheckpointKind::nerf, fingerprint);
            checkpoints.resume_from = resumed.payload;
            checkpoints.resume_source = options.checkpoint.string();
            log_info("nerf train: resuming from {}", options.checkpoint.string());
        } else if (options.resume) {
            log_info("nerf train: no checkpoint at {}: starting from iteration 0",
                     options.checkpoint.string());
        } else {
            std::filesystem::remove(options.checkpoint, ec);
        }
        checkpoints.every = options.checkpoint_every;
        checkpoints.save = [&options, fingerprint](std::span<const std::byte> state,
                                                   std::int64_t /*iteration*/) {
            io::Checkpoint checkpoint;
            checkpoint.kind = io::CheckpointKind::nerf;
            checkpoint.fingerprint = fingerprint;
            checkpoint.payload.assign(state.begin(), state.end());
            io::write_checkpoint(options.checkpoint, checkpoint);
        };
    }
    const nerf::TrainResult result = nerf::train(
        dataset, options.train,
        [&](const nerf::TrainProgress& p) {
            if (options.on_progress) {
                options.on_progress(p);
            }
            return keep_going();
        },
        checkpoints);
    if (!options.checkpoint.empty() && !result.stopped) {
        std::filesystem::remove(options.checkpoint, ec);  // training is complete
    }

    TrainRunResult out;
    nlohmann::ordered_json test_json;
    if (options.test != nullptr) {
        const render::Color b = dataset.background;
        if (result.poses.empty()) {
            test_json = evaluate_field(*options.test, result.grid, result.environment,
                                       {b.r, b.g, b.b}, options.compare);
        } else {
            const nerf::Dataset moved = refined_test_views(dataset, result, *options.test);
            test_json = evaluate_field(moved, result.grid, result.environment, {b.r, b.g, b.b},
                                       options.compare);
        }
    }
    if (!options.refined_poses.empty() && !result.poses.empty()) {
        write_refined_poses(dataset, result, options.refined_poses);
    }
    nerf::ExportOptions exported = options.exported;
    if (options.crop) {
        exported.box = options.crop;
    } else if (options.auto_crop) {
        exported.box = nerf::auto_crop(result.grid, nerf::AutoCropOptions{});
    }
    out.volume = nerf::export_volume(result.grid, exported);
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
    if (exported.box) {
        const AABBd& c = *exported.box;
        j["crop"] = {{c.lo.x, c.lo.y, c.lo.z}, {c.hi.x, c.hi.y, c.hi.z}};
    }
    if (!result.poses.empty()) {
        j["focal_scale"] = result.focal_scale;
        double sum_angle = 0.0, sum_move = 0.0;
        for (std::size_t i = 0; i < result.poses.size(); ++i) {
            const nerf::Pose& a = dataset.views[i].camera_to_world;
            sum_angle += nerf::rotation_angle_deg(a, result.poses[i]);
            sum_move += norm(result.poses[i].eye() - a.eye());
        }
        const double n = static_cast<double>(result.poses.size());
        j["pose_change_deg"] = sum_angle / n;  // mean over the training views
        j["pose_change_eye"] = sum_move / n;   // mean, world units
    }
    if (!result.exposure.empty()) {
        double sum_gain = 0.0, sum_bias = 0.0;
        for (const nerf::ViewExposure& e : result.exposure) {
            for (int k = 0; k < 3; ++k) {
                sum_gain += std::fabs(e.gain[k]);
                sum_bias += std::fabs(e.bias[k]);
            }
        }
        const double n = 3.0 * static_cast<double>(result.exposure.size());
        j["exposure_gain"] = sum_gain / n;  // mean |gain − 1| over views and channels
        j["exposure_bias"] = sum_bias / n;  // mean |bias|
    }
    if (options.test != nullptr) {
        j["test_psnr"] = test_json["psnr"];
        j["test_ssim"] = test_json["ssim"];
        j["test_views"] = test_json["views"];
    }
    return out;
}

namespace {

// PSNR over the view's unmasked pixels; masked pixels of `rgb` set to the reference (for SSIM).
double masked_psnr(std::vector<float>& rgb, const nerf::View& v) {
    if (v.mask.empty()) {
        return nerf::psnr(rgb, v.rgb);
    }
    std::vector<float> kept, kept_ref;
    for (std::size_t q = 0; q < v.mask.size(); ++q) {
        for (std::size_t c = 0; c < 3; ++c) {
            if (v.mask[q] != 0) {
                kept.push_back(rgb[3 * q + c]);
                kept_ref.push_back(v.rgb[3 * q + c]);
            } else {
                rgb[3 * q + c] = v.rgb[3 * q + c];
            }
        }
    }
    return kept.empty() ? 0.0 : nerf::psnr(kept, kept_ref);
}

// Each view's PSNR (unmasked pixels) and SSIM, and their means, as `nerf eval` and
// `nerf train --test` report them.
class ViewScores {
public:
    // Scores a render (linear RGB, width × height) against the view; masked pixels of `rgb` are
    // set to the reference.
    void add(const nerf::View& v, std::vector<float>& rgb, int width, int height) {
        const double p = masked_psnr(rgb, v);
        const double s = nerf::ssim(rgb, v.rgb, width, height);
        m_sum_psnr += p;
        m_sum_ssim += s;
        nlohmann::ordered_json e;
        e["file_path"] = v.name;
        e["psnr"] = p;
        e["ssim"] = s;
        m_views.push_back(e);
    }
    // {"psnr", "ssim": the means (0 without views), "views": [{"file_path", "psnr", "ssim"}]}.
    nlohmann::ordered_json json() const {
        const double n = static_cast<double>(m_views.size());
        nlohmann::ordered_json j;
        j["psnr"] = n > 0 ? m_sum_psnr / n : 0.0;
        j["ssim"] = n > 0 ? m_sum_ssim / n : 0.0;
        j["views"] = m_views;
        return j;
    }

private:
    nlohmann::ordered_json m_views = nlohmann::ordered_json::array();
    double m_sum_psnr = 0.0;
    double m_sum_ssim = 0.0;
};

// Whether render::Camera models these intrinsics (nerf::camera_from_view's conditions).
bool fits_ray_caster_camera(const nerf::Intrinsics& in) {
    return in.lens.is_identity() && std::fabs(in.fx - in.fy) <= 1e-6 * in.fx &&
           std::fabs(in.cx - 0.5 * in.width) <= 1e-3 && std::fabs(in.cy - 0.5 * in.height) <= 1e-3;
}

// The view's pixel-centre rays (nerf::view_ray: any principal point, any lens) ray-cast into
// an 8-bit image, as RayCaster::render would write it.
void render_view_rays(const render::RayCaster& caster, const nerf::Intrinsics& in,
                      const nerf::Pose& pose, render::Image& image) {
    std::vector<render::Ray> rays;
    rays.reserve(static_cast<std::size_t>(in.width) * in.height);
    for (int y = 0; y < in.height; ++y) {
        for (int x = 0; x < in.width; ++x) {
            rays.push_back(nerf::view_ray(in, pose, x + 0.5, y + 0.5));
        }
    }
    std::vector<float> rgb(3 * rays.size());
    caster.render_rays(rays, rgb);
    image = render::Image(in.width, in.height);
    for (std::size_t p = 0; p < rays.size(); ++p) {
        const render::Rgb8 c = render::to_rgb8({rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]});
        image.pixels[3 * p] = c.r;
        image.pixels[3 * p + 1] = c.g;
        image.pixels[3 * p + 2] = c.b;
    }
}

}  // namespace

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
    ViewScores scores;
    render::Image image;
    for (std::size_t i = 0; i < dataset.views.size(); ++i) {
        const nerf::View& v = dataset.views[i];
        const nerf::Intrinsics& in = nerf::intrinsics_of(dataset, v);
        if (fits_ray_caster_camera(in)) {
            caster.render(nerf::camera_from_view(in, v.camera_to_world), image);
        } else {
            render_view_rays(caster, in, v.camera_to_world, image);
        }
        std::vector<float> rgb = nerf::from_image(image);
        // Masked pixels: left out of PSNR, and equal to the reference for SSIM's windows.
        scores.add(v, rgb, image.width, image.height);
        if (!images_dir.empty()) {
            io::write_png(images_dir / fmt::format("{}.png", i), image);
        }
    }
    return scores.json();
}

nlohmann::ordered_json evaluate_field(const nerf::Dataset& dataset, const nerf::RadianceGrid& grid,
                                      const nerf::EnvironmentMap& environment,
                                      const std::array<float, 3>& background,
                                      const std::filesystem::path& compare_png) {
    const render::Color bg{background[0], background[1], background[2]};
    ViewScores scores;
    const std::size_t n = dataset.views.size();
    const std::size_t columns = std::min<std::size_t>(4, n);
    const int w = dataset.intrinsics.width, h = dataset.intrinsics.height;
    render::Image strip(static_cast<int>(columns) * w, 2 * h);
    for (std::size_t i = 0; i < n; ++i) {
        const nerf::View& v = dataset.views[i];
        const nerf::Intrinsics& in = nerf::intrinsics_of(dataset, v);
        std::vector<float> rgb =
            nerf::render_view(grid, environment, in, v.camera_to_world, bg, {});
        nerf::View render_as_view;
        render_as_view.rgb = rgb;
        const render::Image rendered = nerf::to_image(in, render_as_view);
        const render::Image photo = nerf::to_image(in, v);
        scores.add(v, rgb, in.width, in.height);
        // Columns at views 0, n/4, n/2, 3n/4 (for n ≥ 4).
        for (std::size_t c = 0; c < columns; ++c) {
            if (c * n / columns != i) {
                continue;
            }
            for (int y = 0; y < h; ++y) {
                for (int x = 0; x < w; ++x) {
                    const std::size_t src = 3 * (static_cast<std::size_t>(y) * w + x);
                    const std::size_t top =
                        3 * (static_cast<std::size_t>(y) * strip.width + c * w + x);
                    const std::size_t bottom = top + 3 * static_cast<std::size_t>(h) * strip.width;
                    for (int q = 0; q < 3; ++q) {
                        strip.pixels[top + q] = photo.pixels[src + q];
                        strip.pixels[bottom + q] = rendered.pixels[src + q];
                    }
                }
            }
        }
    }
    if (!compare_png.empty() && columns > 0) {
        io::write_png(compare_png, strip);
    }
    return scores.json();
}

}  // namespace pliant::pipeline
