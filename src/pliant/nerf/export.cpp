#include "pliant/nerf/export.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::nerf {

volume::Dims export_dims(const AABBd& box, int resolution) {
    const Vec3d e = box.extent();
    const double largest = std::max({e.x, e.y, e.z});
    volume::Dims dims{};
    for (int a = 0; a < 3; ++a) {
        dims[a] = std::max<std::int64_t>(1, std::lround(resolution * e[a] / largest));
    }
    return dims;
}

std::size_t export_bytes(const AABBd& box, const ExportOptions& options) {
    const volume::Dims d = export_dims(box, options.resolution);
    return static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) *
           static_cast<std::size_t>(d[2]) * volume::bytes_per_voxel(options.type);
}

volume::Volume export_volume(const RadianceGrid& grid, const ExportOptions& options) {
    if (options.resolution < 1 || options.resolution > 2048) {
        throw InvalidInput(
            fmt::format("nerf::export_volume: resolution {}, expected a value in [1, 2048]",
                        options.resolution));
    }
    if (options.type != volume::VoxelType::rgba8 && options.type != volume::VoxelType::rgba32f) {
        throw InvalidInput(
            fmt::format("nerf::export_volume: voxel type {}, expected rgba8 or rgba32f",
                        volume::name(options.type)));
    }
    const AABBd box = options.box.value_or(grid.box());
    const Vec3d e = box.extent();
    if (box.is_empty() || !is_finite(box.lo) || !is_finite(box.hi) || !(e.x > 0.0) ||
        !(e.y > 0.0) || !(e.z > 0.0)) {
        throw InvalidInput(fmt::format(
            "nerf::export_volume: box [({}, {}, {}), ({}, {}, {})], expected a finite box with "
            "min < max on every axis",
            box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z));
    }
    const volume::Dims dims = export_dims(box, options.resolution);
    Vec3d spacing;
    for (int a = 0; a < 3; ++a) {
        spacing[a] = e[a] / static_cast<double>(dims[a]);
    }
    volume::Volume out =
        volume::Volume::allocate(dims, options.type, spacing, box.lo, options.max_bytes);
    const double unit = std::min({spacing.x, spacing.y, spacing.z});
    // σ_world · u = softplus(s) · DENSITY_SCALE · u / scale.
    const double optical_per_softplus = detail::DENSITY_SCALE * unit / grid.scale();
    const detail::GridView g = grid.view(true);
    const bool is_u8 = options.type == volume::VoxelType::rgba8;
    std::uint8_t* u8 = is_u8 ? out.values<volume::VoxelType::rgba8>().data() : nullptr;
    float* f32 = is_u8 ? nullptr : out.values<volume::VoxelType::rgba32f>().data();
    parallel_for(
        dims[2],
        [&](std::int64_t k) {
            for (std::int64_t j = 0; j < dims[1]; ++j) {
                for (std::int64_t i = 0; i < dims[0]; ++i) {
                    const Vec3d u = grid.normalized_from_world(out.voxel_center(i, j, k));
                    const float uf[3] = {static_cast<float>(u.x), static_cast<float>(u.y),
                                         static_cast<float>(u.z)};
                    bool inside = true;
                    for (int a = 0; a < 3; ++a) {
                        inside = inside && uf[a] >= 0.0f && uf[a] <= g.extent[a];
                    }
                    const detail::Corner c = detail::locate(g, uf);
                    float rgba[4] = {0, 0, 0, 0};
                    if (inside && g.occupied[c.base] != 0) {
                        float raw[4];
                        detail::interpolate(g, c, raw);
                        rgba[3] = static_cast<float>(
                            -std::expm1(-detail::softplus(raw[0]) * optical_per_softplus));
                        rgba[0] = detail::sigmoid(raw[1]);
                        rgba[1] = detail::sigmoid(raw[2]);
                        rgba[2] = detail::sigmoid(raw[3]);
                    }
                    const std::int64_t v = 4 * out.index(i, j, k);
                    for (int q = 0; q < 4; ++q) {
                        if (is_u8) {
                            u8[v + q] = static_cast<std::uint8_t>(
                                std::lround(255.0 * std::clamp(rgba[q], 0.0f, 1.0f)));
                        } else {
                            f32[v + q] = rgba[q];
                        }
                    }
                }
            }
        },
        1);
    return out;
}

}  // namespace pliant::nerf
