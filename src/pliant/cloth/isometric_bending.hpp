// The isometric bending stencil of a hinge that is flat at rest: four weights K_k such that
// b(x) = Σ_k K_k x_k is a 3-vector whose length is the hinge's bend angle to first order.
//
// Vertices as for the dihedral angle (dihedral.hpp): the shared edge (x2, x3), x0 the third vertex
// of triangle A = (x0, x2, x3), x1 that of B = (x1, x3, x2). At rest the four points lie in a
// plane, x0 and x1 on opposite sides of the edge, and K is their affine dependency: Σ K_k = 0 and
// Σ K_k X_k = 0 for the rest positions X. So b vanishes for every rigid motion (indeed every
// affine map) of the rest hinge and is linear in the positions: b is the hinge's term of the
// discrete mean-curvature normal, and |b|² the quadratic bending energy of M. Bergou,
// M. Wardetzky, D. Harmon, D. Zorin, E. Grinspun, "A Quadratic Bending Model for Inextensible
// Surfaces", SGP 2006 (their Q = K Kᵀ up to the scale below).
//
// Scale: K_0 = |e| / |n_A| = 1 / h_A and K_1 = |e| / |n_B| = 1 / h_B (h: the distance of x0, x1
// from the edge's line; n_A, n_B and e as in dihedral.hpp), the magnitudes of ∂θ/∂x0 and ∂θ/∂x1
// at rest; then K_3 = −(K_0 (X_0 − X_2)·ê + K_1 (X_1 − X_2)·ê) / |e| and K_2 = −(K_0 + K_1 + K_3).
// Folding one wing by θ about the edge gives b = 2 sin(θ/2) times the unit normal bisecting the
// wings: |b| = θ for small angles, 2 at a full fold.
//
// The solver's constraint (material.bending = isometric; detail/constraint_kernels.hpp) is b's
// component along the hinge's normal, C = n̂ · b with n = K_0 n_A + K_1 n_B (at rest both terms
// have length |e|, so n bisects the wings as b does, whatever their sizes), gradient K_k n̂ (n̂
// held fixed within a projection). Bergou et al. keep all of b because their cloth is inextensible;
// this cloth stretches and shears to wrap doubly curved shapes, and b's in-plane part would
// resist that in-plane distortion as stiffly as bending (a 1.2 m sheet of 24 × 24 quads dropped on
// a 0.3 m sphere had slid 0.15 m off its top after 2 s with the whole vector, 0.10 m with its
// normal part, 0.07 m with the dihedral constraint). For a fold of one wing C = |b| = 2 sin(θ/2)
// (the normal's weights matter here: with n = n_A + n_B a hinge whose wings differ in height had
// C fall back to 0 near a full fold, a second rest state). As stiff as the dihedral constraint
// C = θ − 0 for small angles, softer towards a full fold, and cheap: no square root or
// arctangent, one division.
//
// A hinge within ISOMETRIC_FLAT_ANGLE of flat at rest counts as flat: its b at rest, up to that
// angle, is pulled to 0 as if the rest shape were flat.
//
// Units: K in 1/m, b and C in radians (to first order).
#pragma once

#include <array>
#include <optional>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

// Hinges whose rest dihedral angle is at most this (radians) in magnitude count as flat.
inline constexpr double ISOMETRIC_FLAT_ANGLE = 1e-4;

// The stencil of a hinge at rest positions x0 … x3 (as above), or nothing when the hinge is not
// flat (|dihedral angle| > ISOMETRIC_FLAT_ANGLE) or degenerate (a zero-length edge or a
// zero-area triangle).
std::optional<std::array<double, 4>> isometric_bending_stencil(const Vec3d& x0, const Vec3d& x1,
                                                               const Vec3d& x2, const Vec3d& x3);

// b = Σ K_k x_k (the kernels evaluate it relative to x2, which Σ K_k = 0 allows).
Vec3d isometric_bending_vector(const std::array<double, 4>& stencil, const Vec3d& x0,
                               const Vec3d& x1, const Vec3d& x2, const Vec3d& x3);

}  // namespace pliant::cloth
