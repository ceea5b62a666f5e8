// The dihedral angle of two triangles sharing an edge, and its gradient, for the bending
// constraint C = θ - θ_rest.
//
// Vertices: the shared edge (x2, x3); x0 is the third vertex of triangle A = (x0, x2, x3), x1 the
// third vertex of triangle B = (x1, x3, x2) (both wound the same way as the mesh when A and B are
// consistently oriented). With n_A = (x2 - x0) × (x3 - x0), n_B = (x3 - x1) × (x2 - x1) and
// e = x3 - x2, θ = atan2((n̂_A × n̂_B) · ê, n̂_A · n̂_B) ∈ (-π, π]: 0 for a flat pair, positive when
// the pair folds one way, negative the other.
//
// Gradient (R. Bridson, S. Marino, R. Fedkiw, "Simulation of Clothing with Folds and Wrinkles",
// SCA 2003, §4.1): with |e| the edge length,
//   ∂θ/∂x0 = -|e| n_A / |n_A|²,   ∂θ/∂x1 = -|e| n_B / |n_B|²,
//   ∂θ/∂x2 = -((x0 - x3)·e / |e|) n_A / |n_A|² - ((x1 - x3)·e / |e|) n_B / |n_B|²,
//   ∂θ/∂x3 =  ((x0 - x2)·e / |e|) n_A / |n_A|² + ((x1 - x2)·e / |e|) n_B / |n_B|²,
// with signs for θ as defined above (Bridson et al. measure the angle the other way; checked
// against finite differences in tests/cloth). The four gradients sum to zero (translation
// invariance).
//
// Degenerate input (a zero-area triangle or a zero-length edge): is_valid is false and the
// gradient is zero, so the constraint is skipped for that step.
#pragma once

#include <array>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

struct DihedralAngle {
    double angle;                   // radians, (-π, π]
    std::array<Vec3d, 4> gradient;  // ∂θ/∂x_k for k = 0..3
    bool is_valid;
};

DihedralAngle dihedral_angle(const Vec3d& x0, const Vec3d& x1, const Vec3d& x2, const Vec3d& x3);

// The angle alone (the rest angle of the bending constraint).
double dihedral_angle_value(const Vec3d& x0, const Vec3d& x1, const Vec3d& x2, const Vec3d& x3);

}  // namespace pliant::cloth
