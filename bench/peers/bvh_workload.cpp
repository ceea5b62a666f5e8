#include "peers/bvh_workload.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::bench {
namespace {

constexpr std::int64_t MAX_TRIANGLES = 2LL * 16384 * 16384;  // make_grid_sheet's limit

void check_positive(const char* name, float value) {
    if (!(value > 0.0f) || !std::isfinite(value)) {
        throw InvalidInput(fmt::format(
            "BvhWorkload::make: options.{} ({}) must be finite and positive", name, value));
    }
}

}  // namespace

BvhWorkload BvhWorkload::make(std::int64_t triangles, const BvhWorkloadOptions& options) {
    if (triangles < 2 || triangles > MAX_TRIANGLES) {
        throw InvalidInput(fmt::format("BvhWorkload::make: triangles ({}) not in [2, {}]",
                                       triangles, MAX_TRIANGLES));
    }
    check_positive("sheet_size", options.sheet_size);
    check_positive("panel_fraction", options.panel_fraction);
    check_positive("gap_edges", options.gap_edges);
    check_positive("wavelength", options.wavelength);
    if (!(options.inflation_edges >= 0.0f) || !std::isfinite(options.inflation_edges) ||
        !(options.amplitude_edges >= 0.0f) || !std::isfinite(options.amplitude_edges) ||
        !std::isfinite(options.phase_per_step)) {
        throw InvalidInput(fmt::format(
            "BvhWorkload::make: options.inflation_edges ({}), amplitude_edges ({}) must be finite "
            "and >= 0, phase_per_step ({}) finite",
            options.inflation_edges, options.amplitude_edges, options.phase_per_step));
    }

    BvhWorkload w;
    w.quads_per_side = geometry::nearest_square_sheet(triangles);
    w.mesh = geometry::make_grid_sheet(w.quads_per_side, w.quads_per_side, options.sheet_size,
                                       options.sheet_size);
    w.edge_length = options.sheet_size / static_cast<float>(w.quads_per_side);
    geometry::fold_accordion(w.mesh.positions, options.panel_fraction * options.sheet_size,
                             options.gap_edges * w.edge_length);
    w.inflation = options.inflation_edges * w.edge_length;
    w.amplitude = options.amplitude_edges * w.edge_length;
    w.wavenumber = 2.0f * std::numbers::pi_v<float> / options.wavelength;
    w.phase_per_step = options.phase_per_step;
    return w;
}

std::vector<Vec3f> BvhWorkload::positions(int step) const {
    std::vector<Vec3f> out(mesh.positions.size());
    const float phase = static_cast<float>(step) * phase_per_step;
    parallel_for(static_cast<std::int64_t>(out.size()), [&](std::int64_t i) {
        const Vec3f p = mesh.positions[static_cast<std::size_t>(i)];
        out[static_cast<std::size_t>(i)] = {
            p.x, p.y, p.z + amplitude * std::sin(wavenumber * (p.x + p.y) - phase)};
    });
    return out;
}

void BvhWorkload::compute_boxes(int step, std::vector<AABB>& out) const {
    const std::vector<Vec3f> moved = positions(step);
    out.resize(mesh.triangles.size());
    parallel_for(static_cast<std::int64_t>(out.size()), [&](std::int64_t t) {
        const geometry::Triangle& tri = mesh.triangles[static_cast<std::size_t>(t)];
        AABB box = AABB::of_point(moved[static_cast<std::size_t>(tri[0])]);
        box.extend(moved[static_cast<std::size_t>(tri[1])]);
        box.extend(moved[static_cast<std::size_t>(tri[2])]);
        out[static_cast<std::size_t>(t)] = box.inflated(inflation);
    });
}

std::vector<AABB> BvhWorkload::boxes(int step) const {
    std::vector<AABB> out;
    compute_boxes(step, out);
    return out;
}

}  // namespace pliant::bench
