#include "pliant/nerf/render.hpp"

#include <fmt/format.h>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::nerf {

NormalizedRay normalize_ray(const RadianceGrid& grid, const render::Ray& world_ray) {
    const Vec3d o = grid.normalized_from_world(world_ray.origin);
    const Vec3d d = world_ray.direction;
    return {{static_cast<float>(o.x), static_cast<float>(o.y), static_cast<float>(o.z)},
            {static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)}};
}

std::vector<float> render_view(const RadianceGrid& grid, const Intrinsics& intrinsics,
                               const Pose& pose, render::Color background,
                               const FieldRenderOptions& options) {
    return render_view(grid, EnvironmentMap{}, intrinsics, pose, background, options);
}

std::vector<float> render_view(const RadianceGrid& grid, const EnvironmentMap& environment,
                               const Intrinsics& intrinsics, const Pose& pose,
                               render::Color background, const FieldRenderOptions& options) {
    const int w = intrinsics.width, h = intrinsics.height;
    std::vector<float> rgb(3 * static_cast<std::size_t>(w) * h);
    const detail::GridView g = grid.view(options.use_occupancy);
    const float step = options.step_voxels * grid.voxel_size();
    const float bg[3] = {background.r, background.g, background.b};
    parallel_for(
        h,
        [&](std::int64_t y) {
            for (int x = 0; x < w; ++x) {
                const NormalizedRay r =
                    normalize_ray(grid, view_ray(intrinsics, pose, x + 0.5, y + 0.5));
                float ray_bg[3] = {bg[0], bg[1], bg[2]};
                if (!environment.empty()) {
                    environment.color(r.direction, ray_bg);
                }
                const detail::RayOutput out =
                    detail::march(g, r.origin, r.direction, step, ray_bg, options.min_transmittance,
                                  [](const detail::SampleRecord&) {});
                float* p = rgb.data() + 3 * (y * w + x);
                p[0] = out.rgb[0];
                p[1] = out.rgb[1];
                p[2] = out.rgb[2];
            }
        },
        1);
    return rgb;
}

double photometric_loss(const RadianceGrid& grid, std::span<const NormalizedRay> rays,
                        std::span<const float> targets, render::Color background,
                        const FieldRenderOptions& options, std::span<float> grad) {
    if (targets.size() != 3 * rays.size() ||
        grad.size() != static_cast<std::size_t>(4 * grid.num_voxels())) {
        throw InvalidInput(fmt::format(
            "nerf::photometric_loss: {} rays, {} target values (expected {}), {} gradient values "
            "(expected {})",
            rays.size(), targets.size(), 3 * rays.size(), grad.size(), 4 * grid.num_voxels()));
    }
    const detail::GridView g = grid.view(options.use_occupancy);
    const float step = options.step_voxels * grid.voxel_size();
    const float bg[3] = {background.r, background.g, background.b};
    const double norm = 1.0 / (3.0 * static_cast<double>(rays.size()));
    std::vector<detail::SampleRecord> samples;
    double loss = 0.0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        samples.clear();
        const detail::RayOutput out =
            detail::march(g, rays[i].origin, rays[i].direction, step, bg, options.min_transmittance,
                          [&](const detail::SampleRecord& s) { samples.push_back(s); });
        float gc[3];
        for (int c = 0; c < 3; ++c) {
            const double e = out.rgb[c] - targets[3 * i + c];
            loss += e * e * norm;
            gc[c] = static_cast<float>(2.0 * e * norm);
        }
        detail::backward(g, samples.data(), static_cast<int>(samples.size()), out.rgb, gc,
                         [&](std::int32_t v, const float d[4]) {
                             for (int c = 0; c < 4; ++c) {
                                 grad[4 * static_cast<std::size_t>(v) + c] += d[c];
                             }
                         });
    }
    return loss;
}

}  // namespace pliant::nerf
