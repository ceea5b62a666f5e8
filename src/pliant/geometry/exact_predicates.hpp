// Exact orientation predicates on double coordinates: the sign of a determinant, never wrong
// because of rounding.
//
//   orient3d(a, b, c, d) = sign det[b - a, c - a, d - a] = sign ((b - a) × (c - a)) · (d - a)
//     +1 when d lies on the side of the plane (a, b, c) that (b - a) × (c - a) points to (a, b, c
//        counter-clockwise seen from d), -1 on the other side, 0 when the four points are coplanar.
//        (Shewchuk's orient3d has the opposite sign.)
//   orient2d(a, b, c) = sign det[b - a, c - a] = sign ((bx - ax)(cy - ay) - (by - ay)(cx - ax))
//     +1 when c lies left of the directed line a → b (a, b, c counter-clockwise), -1 right of it,
//     0 when the three points are collinear.
//
// Method (J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
// Predicates", Discrete & Computational Geometry 18(3), 1997): the determinant is first evaluated
// in plain double arithmetic together with a rigorous static bound on its rounding error (stage A
// of the paper, with our own bound, derived in the .cpp); when |value| exceeds the bound, its sign
// is the exact sign. Otherwise the determinant is recomputed exactly as a floating-point expansion
// (a sum of non-overlapping doubles: two-sum, two-product through std::fma, grow / sum / scale
// expansion), whose largest component has the sign of the exact value. Nearly every call on
// generic data ends in the filter. Exactly degenerate inputs take the exact path, except points
// that share a coordinate (a flat cloth in an axis plane, points along a grid's rows): there a
// row or both products of the determinant are exactly zero, which is checked before (0).
//
// Domain of exactness: every coordinate must be 0 or have EXACT_MIN_MAGNITUDE ≤ |x| ≤
// EXACT_MAX_MAGNITUDE (2^-300 ≈ 4.9e-91 to 2^300 ≈ 2.0e90; in_exact_domain checks one value).
// Then no intermediate overflows and every product the exact path forms is a multiple of 2^-1056,
// so no bit is lost to underflow (see the .cpp). Outside the domain (and for NaN / Inf) the result
// is unspecified; callers validate at their entry points (collision::count_intersecting_pairs
// does).
//
// Requires IEEE 754 binary64 with round-to-nearest (the default mode), no -ffast-math, and no
// floating-point contraction in exact_predicates.cpp (pliant compiles with -ffp-contract=off,
// cmake/PliantCodegen.cmake).
// Thread safe, no allocation, no exceptions; the exact path uses about 5 KiB of stack.
#pragma once

#include "pliant/core/vec3.hpp"

namespace pliant::geometry {

inline constexpr double EXACT_MIN_MAGNITUDE = 0x1p-300;
inline constexpr double EXACT_MAX_MAGNITUDE = 0x1p+300;

// True when x is 0 or EXACT_MIN_MAGNITUDE ≤ |x| ≤ EXACT_MAX_MAGNITUDE (false for NaN and Inf).
constexpr bool in_exact_domain(double x) {
    const double m = x < 0 ? -x : x;
    return m == 0.0 || (m >= EXACT_MIN_MAGNITUDE && m <= EXACT_MAX_MAGNITUDE);
}

// Exact sign (+1, 0, -1) of det[b - a, c - a, d - a]; see the conventions above.
int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);

// Exact sign (+1, 0, -1) of (bx - ax)(cy - ay) - (by - ay)(cx - ax); see the conventions above.
int orient2d(double ax, double ay, double bx, double by, double cx, double cy);

}  // namespace pliant::geometry
