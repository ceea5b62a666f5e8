// The constraint projection sweep of the XPBD soft body (soft_body.hpp, steps 2 and 3): every
// constraint once, colour after colour (Gauss–Seidel across colours), the constraints of a colour
// in parallel (they share no vertex) in fixed chunks (grains.hpp), 8 at a time (AVX2, when
// use_avx2), 4 (SSE) or 1 (projection.hpp, projection_avx2.hpp: the same bits). On a TetGrid the
// sweep is layer-blocked (constraint_layout.hpp, LayerBlocking); with AVX2 a grid's body takes
// lattice_sweep.hpp instead. The result is bitwise that of the plain colour-by-colour sweep with
// the scalar kernels, for any number of threads and either SIMD width.
//
// x: #V positions (world units) packed with this substep's inverse mass (Float4 {x, y, z, w}; w = 0
// for pinned and driven vertices), read and written. Not thread safe on one x; parallel inside.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "pliant/pbd/constraint_coloring.hpp"
#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/detail/projection.hpp"

namespace pliant::pbd::detail {

// XPBD parameters of one constraint type for a substep h (soft_body.hpp, "Stiffness"): a
// projection takes Δλ = −C / (w_j · inv_k + alpha), w_j = Σ_k w_k |∇_k C|², which is XPBD's
// Δλ = −C / (w_j + α̃) with α̃ = (1 − k) / k · w_j + α / h².
struct ConstraintStiffness {
    float inv_k = 1.0f;  // 1 / k, k ∈ (0, 1] the PBD stiffness
    float alpha = 0.0f;  // α / h², α the physical compliance (edges m/N, volumes m⁵/N)
};

// Calls project_range(c, lo, hi) on ranges [lo, hi) of the constraints of colour c (indices within
// the colour) that cover every constraint of `coloring` once. Without a blocking (num_layers = 0)
// each range is a whole colour, colour after colour; with one, slab after slab of LAYERS_PER_SLAB
// layers, colour c's layers shifted back by skew[c], empty ranges skipped: every two constraints
// sharing a vertex are still visited in the order of their colours (LayerBlocking).
template <typename ProjectRange>
void sweep_colours(const LayerBlocking& blocking, const ConstraintColoring& coloring,
                   const ProjectRange& project_range) {
    const std::int32_t num_colors = coloring.num_colors();
    if (blocking.num_layers == 0) {
        for (std::int32_t c = 0; c < num_colors; ++c) {
            project_range(c, 0,
                          coloring.offsets[static_cast<std::size_t>(c) + 1] -
                              coloring.offsets[static_cast<std::size_t>(c)]);
        }
        return;
    }
    const std::int64_t layers = blocking.num_layers;
    for (std::int64_t t = 0; t < layers + blocking.max_skew; t += LAYERS_PER_SLAB) {
        for (std::int32_t c = 0; c < num_colors; ++c) {
            const std::int64_t skew = blocking.skew[static_cast<std::size_t>(c)];
            const std::int64_t z0 = std::clamp<std::int64_t>(t - skew, 0, layers);
            const std::int64_t z1 = std::clamp<std::int64_t>(t - skew + LAYERS_PER_SLAB, 0, layers);
            const std::int64_t* layer_begin =
                blocking.layer_begin.data() + static_cast<std::size_t>(c) * (layers + 1);
            if (layer_begin[z0] < layer_begin[z1]) {
                project_range(c, layer_begin[z0], layer_begin[z1]);
            }
        }
    }
}

// Projects every edge-distance constraint once (C = |x_a − x_b| − L, projection.hpp's
// project_edge), in the order of sweep_colours.
void project_edges(Float4* x, const EdgeConstraints& edges, ConstraintStiffness stiffness,
                   bool use_avx2);

// Projects every tet-volume constraint once (C = V − V0, project_tet), in the order of
// sweep_colours, and flags the tets at risk of inversion (V below AT_RISK_RATIO · V0 before their
// projection): tet_at_risk[k] = 1 (#T, colour order) and colour_at_risk[c] = 1 for their colours
// (#tet colours); other entries are left as they are. Writes are by index (no two chunks write
// one tet's entry) or, for a colour's flag, an idempotent relaxed atomic store of 1.
void project_tets(Float4* x, const TetConstraints& tets, ConstraintStiffness stiffness,
                  bool use_avx2, std::span<std::uint8_t> tet_at_risk,
                  std::span<std::uint8_t> colour_at_risk);

}  // namespace pliant::pbd::detail
