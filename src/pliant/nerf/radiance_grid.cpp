#include "pliant/nerf/radiance_grid.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::nerf {

RadianceGrid::RadianceGrid(const AABBd& box, int resolution, float density_raw, float color_raw)
    : m_box(box), m_resolution(resolution) {
    const Vec3d e = box.extent();
    if (box.is_empty() || !is_finite(box.lo) || !is_finite(box.hi) || !(e.x > 0.0) ||
        !(e.y > 0.0) || !(e.z > 0.0)) {
        throw InvalidInput(fmt::format(
            "nerf::RadianceGrid: box [({}, {}, {}), ({}, {}, {})] must be finite with min < max "
            "on every axis",
            box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z));
    }
    if (resolution < 2 || resolution > 2048) {
        throw InvalidInput(fmt::format(
            "nerf::RadianceGrid: resolution {}, expected a value in [2, 2048]", resolution));
    }
    m_scale = std::max({e.x, e.y, e.z});
    m_dims = dims_for(box, resolution);
    const std::int64_t n = num_voxels();
    m_params.resize(static_cast<std::size_t>(4 * n));
    for (std::int64_t v = 0; v < n; ++v) {
        m_params[4 * v] = density_raw;
        m_params[4 * v + 1] = color_raw;
        m_params[4 * v + 2] = color_raw;
        m_params[4 * v + 3] = color_raw;
    }
    m_occupied.assign(static_cast<std::size_t>(n), 1);
}

std::array<int, 3> RadianceGrid::dims_for(const AABBd& box, int resolution) {
    const Vec3d e = box.extent();
    const double scale = std::max({e.x, e.y, e.z});
    std::array<int, 3> dims{};
    for (int a = 0; a < 3; ++a) {
        dims[a] = std::max(2, static_cast<int>(std::lround(resolution * e[a] / scale)));
    }
    return dims;
}

detail::GridView RadianceGrid::view(bool with_occupancy) const {
    detail::GridView g;
    g.params = m_params.data();
    g.occupied = with_occupancy ? m_occupied.data() : nullptr;
    const Vec3d e = m_box.extent();
    for (int a = 0; a < 3; ++a) {
        g.dims[a] = m_dims[a];
        g.extent[a] = static_cast<float>(e[a] / m_scale);
        g.to_grid[a] = static_cast<float>(m_dims[a] / (e[a] / m_scale));
    }
    return g;
}

std::int64_t RadianceGrid::num_occupied() const {
    return parallel_reduce(
        static_cast<std::int64_t>(m_occupied.size()), std::int64_t{0},
        [&](std::int64_t b, std::int64_t e) {
            std::int64_t c = 0;
            for (std::int64_t i = b; i < e; ++i) {
                c += m_occupied[i];
            }
            return c;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, 1 << 16);
}

void RadianceGrid::set_all_occupied() {
    std::fill(m_occupied.begin(), m_occupied.end(), std::uint8_t{1});
}

void RadianceGrid::update_occupancy(float sigma_threshold) {
    const float s_threshold = density_raw_for_sigma(sigma_threshold);
    const int nx = m_dims[0], ny = m_dims[1], nz = m_dims[2];
    const std::int64_t sy = nx, sz = static_cast<std::int64_t>(nx) * ny;
    parallel_for(
        nz,
        [&](std::int64_t k) {
            for (int j = 0; j < ny; ++j) {
                for (int i = 0; i < nx; ++i) {
                    const std::int64_t v = i + sy * j + sz * k;
                    std::uint8_t occ = 0;
                    if (i + 1 < nx && j + 1 < ny && k + 1 < nz) {
                        float m = m_params[4 * v];
                        for (const std::int64_t o :
                             {std::int64_t{1}, sy, sy + 1, sz, sz + 1, sz + sy, sz + sy + 1}) {
                            m = std::max(m, m_params[4 * (v + o)]);
                        }
                        occ = m >= s_threshold ? 1 : 0;
                    }
                    m_occupied[v] = occ;
                }
            }
        },
        1);
}

RadianceGrid RadianceGrid::resampled(int resolution, float sigma_threshold) const {
    RadianceGrid out(m_box, resolution, 0.0f, 0.0f);
    const detail::GridView src = view(false);
    const detail::GridView dst = out.view(false);
    const int nx = out.m_dims[0], ny = out.m_dims[1], nz = out.m_dims[2];
    parallel_for(
        nz,
        [&](std::int64_t k) {
            for (int j = 0; j < ny; ++j) {
                for (int i = 0; i < nx; ++i) {
                    const float u[3] = {(static_cast<float>(i) + 0.5f) / dst.to_grid[0],
                                        (static_cast<float>(j) + 0.5f) / dst.to_grid[1],
                                        (static_cast<float>(k) + 0.5f) / dst.to_grid[2]};
                    float raw[4];
                    detail::interpolate(src, detail::locate(src, u), raw);
                    const std::int64_t v =
                        i + static_cast<std::int64_t>(nx) * (j + static_cast<std::int64_t>(ny) * k);
                    for (int c = 0; c < 4; ++c) {
                        out.m_params[4 * v + c] = raw[c];
                    }
                }
            }
        },
        1);
    out.update_occupancy(sigma_threshold);
    return out;
}

float density_raw_for_sigma(float sigma) {
    const double x = static_cast<double>(sigma) / detail::DENSITY_SCALE;
    return x > 20.0 ? static_cast<float>(x) : static_cast<float>(std::log(std::expm1(x)));
}

void RadianceGrid::save_state(ByteWriter& out) const {
    out.put(m_box.lo);
    out.put(m_box.hi);
    out.put(m_resolution);
    out.put_vector(m_params);
    out.put_vector(m_occupied);
}

void RadianceGrid::load_state(ByteReader& in, const AABBd& box, int resolution) {
    const auto lo = in.get<Vec3d>("grid.box.lo");
    const auto hi = in.get<Vec3d>("grid.box.hi");
    const int stored_resolution = in.get<int>("grid.resolution");
    if (lo != box.lo || hi != box.hi || stored_resolution != resolution) {
        throw InvalidInput(fmt::format(
            "{}: grid: resolution {} over ({}, {}, {})-({}, {}, {}), expected resolution {} over "
            "the scene box",
            in.source(), stored_resolution, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, resolution));
    }
    // The sizes a grid of this box and resolution has.
    RadianceGrid grid(box, resolution, 0.0f, 0.0f);
    in.get_vector("grid.params", grid.m_params, static_cast<std::int64_t>(grid.m_params.size()));
    in.get_vector("grid.occupancy", grid.m_occupied,
                  static_cast<std::int64_t>(grid.m_occupied.size()));
    *this = std::move(grid);
}

}  // namespace pliant::nerf
