// Seams: pairs of vertices on garment panels sewn together the way garment tools assemble flat
// patterns. Each pair is an XPBD distance constraint C = |x_a - x_b| - d(t) (compliance 0) whose
// target d(t) shrinks linearly from the pair's distance at the start to the gap over `seconds`,
// then holds at the gap: the panels are pulled together over the first frames and then held
// closed. The gap is the cloth's thickness, so that sewn edges meet where self-collision (which
// keeps non-adjacent triangles a thickness apart) lets them: the panels stay separate meshes in
// the output, as the input has them, seamed edge to edge.
//
// Project once per substep after the cloth's own constraints (xpbd_stepper.hpp), pair after pair
// in the order added (Gauss-Seidel; deterministic). Pairs with both vertices pinned are skipped.
// Units: SI.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

class Seams {
public:
    // Sews a[k] to b[k] for every k, over `seconds` (> 0, finite) from time 0, down to `gap`
    // (m, >= 0); start distances from `positions` (#V). InvalidInput: lengths that differ, an
    // empty seam, an index outside [0, #V), a vertex sewn to itself, seconds or gap out of range.
    void add(std::span<const std::int32_t> a, std::span<const std::int32_t> b, double seconds,
             double gap, std::span<const Vec3d> positions);

    bool empty() const { return m_pairs.empty(); }
    std::size_t num_pairs() const { return m_pairs.size(); }

    // The target distance of pair k at time t (s).
    double target(std::size_t k, double t) const;

    // One projection of every pair at time t.
    void project(std::span<Vec3d> positions, std::span<const double> inverse_masses,
                 double t) const;

    // The largest |x_a - x_b| - gap over the pairs (m; 0 without pairs): how far the seams are
    // from closed.
    double max_opening(std::span<const Vec3d> positions) const;

private:
    struct Pair {
        std::int32_t a;
        std::int32_t b;
        double start;    // m, the distance at time 0
        double gap;      // m
        double seconds;  // s
    };
    std::vector<Pair> m_pairs;
};

}  // namespace pliant::cloth
