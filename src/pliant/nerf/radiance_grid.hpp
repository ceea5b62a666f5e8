// RadianceGrid: a dense voxel-grid radiance field over a scene box (the Plenoxels / DVGO /
// ReLU-field family, without the MLP): per voxel four raw parameters (s, a_r, a_g, a_b) —
// density and RGB colour before activation — and an occupancy grid for empty-space skipping.
// The field, its activations and the rendering equation are in detail/field_kernel.hpp.
//
// Layout: the grid covers the box exactly, dims_a = max(2, round(resolution · extent_a /
// largest extent)) voxels per axis (voxel centres at lo + (i + 0.5) · extent_a / dims_a, the
// Volume convention); parameters interleaved per voxel, 4 floats (16 bytes: the 8 corners of a
// sample are 8 aligned 16-byte loads instead of 32 scattered ones), x fastest, then y, then z.
// Rays and sampling steps are in normalized units (the box's largest side = 1); densities are
// per normalized unit (detail::DENSITY_SCALE).
//
// Memory: 16 bytes per voxel for the parameters plus 1 for the occupancy (128³: 34 MiB).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/nerf/detail/field_kernel.hpp"

namespace pliant::nerf {

class RadianceGrid {
public:
    RadianceGrid() = default;
    // A grid over `box` with `resolution` voxels along its longest side, every voxel holding
    // (density_raw, color_raw, color_raw, color_raw), all cells occupied. InvalidInput for an
    // empty or non-finite box, a side of zero length, or resolution outside [2, 2048].
    RadianceGrid(const AABBd& box, int resolution, float density_raw, float color_raw);

    // dims_a = max(2, round(resolution · extent_a / largest extent)). Precondition: the box and
    // resolution are valid as the constructor requires.
    static std::array<int, 3> dims_for(const AABBd& box, int resolution);

    const AABBd& box() const { return m_box; }
    int resolution() const { return m_resolution; }
    const std::array<int, 3>& dims() const { return m_dims; }
    std::int64_t num_voxels() const {
        return static_cast<std::int64_t>(m_dims[0]) * m_dims[1] * m_dims[2];
    }
    // World units per normalized unit (the box's largest side).
    double scale() const { return m_scale; }
    Vec3d normalized_from_world(const Vec3d& p) const { return (p - m_box.lo) / m_scale; }
    // One voxel along the longest side, normalized units (1 / resolution).
    float voxel_size() const { return 1.0f / static_cast<float>(m_resolution); }

    std::span<float> params() { return m_params; }  // 4 · num_voxels
    std::span<const float> params() const { return m_params; }
    std::span<const std::uint8_t> occupancy() const { return m_occupied; }
    std::int64_t num_occupied() const;

    // The kernel's view; with_occupancy = false evaluates every sample.
    detail::GridView view(bool with_occupancy = true) const;

    // Marks a cell (indexed by its lower corner) occupied when the largest raw density of its 8
    // corners gives σ ≥ sigma_threshold (per normalized unit). O(8 · voxels), parallel over z.
    void update_occupancy(float sigma_threshold);
    void set_all_occupied();

    // The same field at another resolution: raw parameters interpolated trilinearly at the new
    // voxel centres (coarse to fine); occupancy recomputed with sigma_threshold.
    RadianceGrid resampled(int resolution, float sigma_threshold) const;

    // The whole grid (box, resolution, parameters, occupancy), for checkpoints (core/bytes.hpp).
    // load_state: InvalidInput for a truncated state or one of another box or resolution than
    // those expected.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in, const AABBd& box, int resolution);

private:
    AABBd m_box;
    int m_resolution = 0;
    std::array<int, 3> m_dims{0, 0, 0};
    double m_scale = 1.0;
    std::vector<float> m_params;
    std::vector<std::uint8_t> m_occupied;
};

// The raw density s with softplus(s) · DENSITY_SCALE = sigma (inverse softplus; sigma > 0).
float density_raw_for_sigma(float sigma);

}  // namespace pliant::nerf
