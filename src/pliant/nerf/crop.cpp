#include "pliant/nerf/crop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pliant::nerf {

AABBd auto_crop(const RadianceGrid& grid, const AutoCropOptions& options) {
    const auto& d = grid.dims();
    const std::int64_t nx = d[0], ny = d[1], nz = d[2];
    const auto params = grid.params();
    const auto occupied = grid.occupancy();
    const double per_voxel = detail::DENSITY_SCALE / static_cast<double>(grid.resolution());
    std::vector<std::uint8_t> solid(static_cast<std::size_t>(nx * ny * nz), 0);
    std::vector<std::int64_t> count(static_cast<std::size_t>(nz), 0);
    for (std::int64_t v = 0; v < nx * ny * nz; ++v) {
        const double alpha = -std::expm1(-detail::softplus(params[4 * v]) * per_voxel);
        if (occupied[v] != 0 && alpha >= options.alpha_threshold) {
            solid[v] = 1;
            ++count[v / (nx * ny)];
        }
    }
    std::int64_t bottom = 0;
    std::int64_t top = 0;  // the fullest slice (the lowest of equals), then the plane's top
    for (std::int64_t z = 1; z < nz; ++z) {
        top = count[z] > count[top] ? z : top;
    }
    const std::int64_t fullest = count[top];
    if (static_cast<double>(fullest) >= options.plane_fraction * static_cast<double>(nx * ny)) {
        while (top + 1 < nz && 2 * count[top + 1] >= fullest) {
            ++top;
        }
        bottom = top + 2;  // one voxel above the plane's top slice
    }
    // Connected components (6-neighbours) of the solid voxels above the plane, labelled in
    // scan order by a breadth-first search.
    const std::int64_t sy = nx, sz = nx * ny;
    std::vector<std::int32_t> label(solid.size(), -1);
    std::vector<std::int64_t> sizes;
    std::vector<std::int64_t> queue;
    for (std::int64_t v = bottom * sz; v < nx * ny * nz; ++v) {
        if (solid[v] == 0 || label[v] >= 0) {
            continue;
        }
        const auto id = static_cast<std::int32_t>(sizes.size());
        std::int64_t size = 0;
        queue.assign(1, v);
        label[v] = id;
        while (!queue.empty()) {
            const std::int64_t u = queue.back();
            queue.pop_back();
            ++size;
            const std::int64_t i = u % nx, j = (u / sy) % ny, k = u / sz;
            const std::int64_t next[6][2] = {{i > 0, u - 1},       {i + 1 < nx, u + 1},
                                             {j > 0, u - sy},      {j + 1 < ny, u + sy},
                                             {k > bottom, u - sz}, {k + 1 < nz, u + sz}};
            for (const auto& [ok, w] : next) {
                if (ok != 0 && solid[w] != 0 && label[w] < 0) {
                    label[w] = id;
                    queue.push_back(w);
                }
            }
        }
        sizes.push_back(size);
    }
    const std::int64_t largest = sizes.empty() ? 0 : *std::max_element(sizes.begin(), sizes.end());
    // Per-axis voxel coordinates of the voxels of the kept components.
    std::vector<std::int64_t> coords[3];
    for (std::int64_t v = bottom * sz; v < nx * ny * nz; ++v) {
        if (label[v] >= 0 && static_cast<double>(sizes[static_cast<std::size_t>(label[v])]) >=
                                 options.component_fraction * static_cast<double>(largest)) {
            coords[0].push_back(v % nx);
            coords[1].push_back((v / sy) % ny);
            coords[2].push_back(v / sz);
        }
    }
    const AABBd& box = grid.box();
    if (coords[0].empty()) {
        return box;
    }
    const Vec3d e = box.extent();
    AABBd out;
    for (int a = 0; a < 3; ++a) {
        std::vector<std::int64_t>& c = coords[a];
        std::sort(c.begin(), c.end());
        const auto at = [&](double q) {
            const auto idx = static_cast<std::size_t>(q * static_cast<double>(c.size() - 1));
            return c[std::min(idx, c.size() - 1)];
        };
        // Voxel i covers [i, i + 1] / dims of the extent.
        double lo = static_cast<double>(at(options.quantile)) / d[a];
        double hi = static_cast<double>(at(1.0 - options.quantile) + 1) / d[a];
        if (a == 2) {
            lo = std::max(lo, static_cast<double>(bottom) / d[a]);
        }
        const double pad = options.margin * (hi - lo);
        lo = std::max(0.0, lo - (a == 2 && bottom > 0 ? 0.0 : pad));
        hi = std::min(1.0, hi + pad);
        out.lo[a] = box.lo[a] + lo * e[a];
        out.hi[a] = box.lo[a] + hi * e[a];
    }
    return out;
}

}  // namespace pliant::nerf
