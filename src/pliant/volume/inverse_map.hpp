// InverseMap: where a deformed tet mesh takes each point of a target grid from, on a coarse grid
// of nodes — the route for rendering a deformed volume without resampling every voxel every
// frame (issue 29): a renderer samples the source through the map (trilinear in the map, then in
// the source) instead of sampling a resampled copy.
//
//   InverseMap map;
//   map.build(source, target_frame, grid.mesh.tets, grid.mesh.positions, body.positions());
//   double g[3];
//   if (map.source_coordinate(t, g)) { sample the source at grid coordinate g }
//
// Nodes: every `node_voxels`-th voxel centre of the target grid, node (a, b, c) at target grid
// coordinate (B·a, B·b, B·c) (grid coordinates: voxel centres at integers, as
// volume/resample.hpp), nodes[d] = (n_d − 1) / B + 2 along axis d, so that every target voxel
// centre lies in a node cell. Each node stores a source grid coordinate (3 floats):
//   - a node inside a deformed tet (barycentric coordinates ≥ −1e-9) gets that tet's affine map
//     from deformed to rest positions, r = r3 + Σ λk (rk − r3), in source grid coordinates (the
//     highest tet index wins where deformed tets overlap);
//   - a node outside every tet but in the 26-neighbourhood of an inside node gets the affine map of
//     one of those neighbours' tets extrapolated (the one with the largest smallest barycentric
//     coordinate at the node): outside the deformed body it points outside the rest body;
//   - other nodes are empty (NaN).
// Inside a tet the exact map is affine and the trilinear interpolation of the node values bends
// it only where neighbouring tets' maps differ (second order in the deformation's curvature);
// tests/volume/inverse_map_test.cpp measures it against the exact resampler.
//
// Cost: O(#V + #T) for the inside nodes (parallel over tets, 8 frames at a time, with AVX2 also
// their node boxes and the test of each box's first node, detail/tet_map_avx2.hpp: each raises
// the holder of the nodes it holds to its index, an atomic maximum, and records its map's value
// there where the holder was below; each held node then takes its final holder's record) and
// O(#nodes) for the extrapolated ones (parallel over chunks of node layers: per layer the maps
// of the held nodes next to the shell, kept for three layers, read by the shell nodes; a
// separable dilation of the held nodes first, so that nodes with no held neighbour are passed
// over without reading their 26 neighbours; 2 chunks per thread, 1 on one thread). About 10 ms
// CPU at the source scale (435,160 tets, 274,625 nodes), half of it the pass over the tets
// (docs/performance.md, issue 29).
// Deterministic: the same map for any number of threads. Not thread safe to build; const access
// from many threads is.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/volume/detail/tet_map.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

struct InverseMapOptions {
    int node_voxels = 4;  // B ≥ 1: target voxels between nodes (a TetGrid's cell_voxels)
};

struct InverseMapStats {
    std::int64_t num_nodes = 0;
    std::int64_t num_inside = 0;        // nodes inside a deformed tet
    std::int64_t num_extrapolated = 0;  // nodes next to the body
};

class InverseMap {
public:
    // source: the rest frame (its dims, spacing, origin; data unused); target: the output grid's
    // frame (likewise). tets: #T × 4 indices into rest_positions and deformed_positions (#V each,
    // world units, finite). InvalidInput for empty volumes, node_voxels < 1, a size mismatch,
    // an index out of range or a non-finite position.
    InverseMapStats build(const Volume& source, const Volume& target,
                          std::span<const geometry::Tet> tets,
                          std::span<const Vec3f> rest_positions,
                          std::span<const Vec3f> deformed_positions,
                          const InverseMapOptions& options = {});

    // The source grid coordinate out[3] of target grid coordinate t[3], trilinear in the node
    // values; false (out unchanged) when t lies outside the node grid or a node of its cell is
    // empty.
    bool source_coordinate(const double t[3], double out[3]) const;

    int node_voxels() const { return m_b; }
    const std::array<std::int64_t, 3>& nodes() const { return m_nodes; }
    // 3 floats per node (x fastest), source grid coordinates; NaN: empty.
    std::span<const float> node_coordinates() const { return m_g; }
    // Per row of nodes (y, z), at 2 (y + nodes()[1] · z): [first, end) along x, the range that
    // holds every node of the row that is not empty (first = end: every node is empty).
    std::span<const std::int32_t> node_row_extents() const { return m_row_extents; }

private:
    int m_b = 4;
    std::array<std::int64_t, 3> m_nodes{0, 0, 0};
    std::vector<float> m_g;
    std::vector<std::int32_t> m_row_extents;
    // Scratch of build(), kept between builds (no allocation per frame): the holder tet per node
    // (−1: none), the vertices in grid coordinates (deformed: target's, rest: source's), the
    // dilation and erosion of the held nodes, per held node next to the shell the index of its
    // map in its layer's list, and the lists (3 layers per chunk of layers).
    std::vector<std::int32_t> m_holder;
    std::vector<Vec3d> m_deformed_grid, m_rest_grid;
    std::vector<std::uint8_t> m_near_x, m_near_xy;
    std::vector<std::int32_t> m_slot;
    std::vector<std::vector<detail::TetMap>> m_lists;
    // Per chunk of the pass over the tets: the values its tets recorded at the nodes they held.
    std::vector<std::vector<detail::HeldValue>> m_held_values;
};

// Every voxel of target = the source sampled (trilinearly, as volume/resample.hpp samples) at the
// map's source coordinate of the voxel's centre, 0 where the map is empty: what a renderer that
// samples through the map sees at the voxel centres. target: the frame the map was built for,
// of a type volume::can_resample_into(source.type(), ·) accepts (else InvalidInput). Parallel
// over layers, deterministic.
void resample_through(const InverseMap& map, const Volume& source, Volume& target);

}  // namespace pliant::volume
