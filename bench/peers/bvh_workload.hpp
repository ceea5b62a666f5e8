// The BVH benchmark's workload: a square sheet folded like an accordion, with a small travelling
// wave on top so that refits see moved boxes.
//
// Geometry (all lengths in metres unless said otherwise):
//   - a square grid sheet of side `sheet_size` with n × n quads, n = nearest_square_sheet(T), so
//     2n² triangles (2,244 → 2,178; 27,030 → 26,912; 35,992 → 35,912); edge length e = side / n;
//   - folded isometrically (geometry::fold_accordion) into panels of `panel_fraction` × side,
//     consecutive layers `gap_edges` · e apart;
//   - at step s every vertex moves along z by a · sin(k·(x + y) − s·ω), a = amplitude_edges · e,
//     k = 2π / wavelength, ω = phase_per_step (a travelling sine; step 0 has phase 0);
//   - triangle boxes: the tight box of the three moved vertices, grown by inflation_edges · e on
//     every side.
// With the defaults, flat layers are 1.5 e apart and boxes 0.5 e thick, so pairs come from
// in-sheet neighbours that share no vertex and from the folds, as in a cloth broad phase.
//
// Deterministic (no randomness, identical for any number of threads). Boxes are computed in
// parallel through pliant's parallel layer. Immutable after make(): const calls may run
// concurrently.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::bench {

struct BvhWorkloadOptions {
    float sheet_size = 1.0f;        // m, side of the square sheet before folding
    float panel_fraction = 0.125f;  // panel length as a fraction of the side (8 panels)
    float gap_edges = 1.5f;         // distance between folded layers, in edge lengths
    float inflation_edges = 0.25f;  // box growth on every side, in edge lengths
    float amplitude_edges = 0.1f;   // travelling-wave amplitude, in edge lengths
    float wavelength = 0.25f;       // m
    float phase_per_step = 0.3f;    // rad per step
};

struct BvhWorkload {
    geometry::TriangleMesh mesh;  // folded sheet, without the wave (#V positions, #T triangles)
    int quads_per_side = 0;       // n
    float edge_length = 0.0f;     // e = sheet_size / n (m)
    float inflation = 0.0f;       // m
    float amplitude = 0.0f;       // m
    float wavenumber = 0.0f;      // rad / m
    float phase_per_step = 0.0f;  // rad

    // The folded sheet nearest to `triangles` triangles. Throws InvalidInput for triangles < 2,
    // more than 2 · 16384² triangles, or options that are not finite and positive.
    static BvhWorkload make(std::int64_t triangles, const BvhWorkloadOptions& options = {});

    std::size_t num_triangles() const { return mesh.triangles.size(); }
    std::span<const geometry::Triangle> triangles() const { return mesh.triangles; }

    // Vertex positions at `step` (#V).
    std::vector<Vec3f> positions(int step) const;
    // Inflated triangle boxes at `step` into `out` (resized to #T).
    void compute_boxes(int step, std::vector<AABB>& out) const;
    std::vector<AABB> boxes(int step) const;
};

}  // namespace pliant::bench
