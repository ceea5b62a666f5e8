// Chebyshev semi-iterative acceleration of the soft body's constraint iterations (soft_body.hpp,
// "Iterations"; Wang, "A Chebyshev Semi-Iterative Approach for Accelerating Projective and
// Position-based Dynamics", SIGGRAPH Asia 2015, eq. 11–12). Within one substep, iteration k
// (0-based) takes the positions q^k to the positions q̂^{k+1} of one constraint sweep; the
// accelerated iterate is
//   q^{k+1} = ω_{k+1} (γ (q̂^{k+1} − q^k) + q^k − q^{k−1}) + q^{k−1},
// with the under-relaxation γ ∈ (0, 1], and ω from the spectral radius ρ ∈ [0, 1) of the plain
// iteration: ω_1 = 1, ω_2 = 2 / (2 − ρ²), ω_{k+1} = 4 / (4 − ρ² ω_k). The recurrence restarts
// in every substep (q^0: the prediction, q^{−1} unused as ω_1 = 1), and the last iteration of a
// substep ends with its plain sweep (and the inversion guard), not extrapolated: an
// extrapolation can push a tet through zero volume, the sweep after it flags and guards the tet.
// Only free vertices (w > 0) move: pinned and driven vertices keep the sweep's positions bitwise.
//
// Per-vertex, parallel in fixed chunks, written by index: bitwise identical for any number of
// threads. ω is computed in double and rounded once to float.
#pragma once

#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/pbd/detail/projection.hpp"

namespace pliant::pbd::detail {

// ω_{k+1} for the iteration k (0-based) of a substep: 1 for k = 0, then the recurrence with ρ.
// ρ ∈ [0, 1) (ρ = 0: ω = 1 throughout, plain under-relaxed iterations).
double chebyshev_omega(int iteration, double rho);

// Before the sweep of iteration 0: current (q^0) and previous = x's positions (#V).
void chebyshev_begin(const Float4* x, std::span<Vec3f> current, std::span<Vec3f> previous);

// After the sweep of iteration k: x (#V, holding q̂^{k+1}) becomes q^{k+1} for free vertices
// (x.w > 0); previous (q^{k−1}, #V) becomes q^k and current (q^k, #V) becomes q^{k+1}.
// omega: ω_{k+1}; gamma: γ.
void chebyshev_update(Float4* x, std::span<Vec3f> current, std::span<Vec3f> previous, float omega,
                      float gamma);

}  // namespace pliant::pbd::detail
