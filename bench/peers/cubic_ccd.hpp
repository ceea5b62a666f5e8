// The plain floating-point CCD most users would pick instead of pliant's: the coplanarity cubic of
// Provot ("Collision and self-collision handling in cloth model dedicated to design garments",
// Graphics Interface 1997) and Bridson, Fedkiw, Anderson ("Robust treatment of collisions, contact
// and friction for cloth animation", SIGGRAPH 2002). A peer for bench/ccd_bench.cpp, not for use.
//
//   double toi = 1.0;
//   if (cubic_vertex_face_ccd(v0, a0, b0, c0, v1, a1, b1, c1, toi)) { /* contact at toi */ }
//
// Method: every point moves as x(t) = x_t0 + t (x_t1 - x_t0). Four points can only touch when they
// are coplanar, i.e. at a root in [0, 1] of the cubic
//   vertex-face  p(t) = det[f1 - f0, f2 - f0, v - f0](t)
//   edge-edge    p(t) = det[ea1 - ea0, eb0 - ea0, eb1 - ea0](t)
// solved in double: the roots of p' (a quadratic, or linear, or none when p has lower degree) split
// [0, 1] into monotone pieces; a piece whose end values differ in sign holds one root, found by
// safeguarded Newton (bisection when Newton leaves the bracket) to ~1e-15; a piece end where
// |p| <= 1e-12 · (|c0| + |c1| + |c2| + |c3|) is also a root (a tangential touch, or p ≡ 0 when the
// four points stay coplanar: then only t = 0, p's critical points and t = 1 are tried). At each
// root in increasing order the positions are evaluated and tested:
//   vertex-face  the barycentrics of v projected onto the triangle's plane are all >= -1e-10
//                (a triangle of zero area, |n|² <= 1e-30 · scale⁴, never passes);
//   edge-edge    the closest points of the two segments (Ericson, Real-Time Collision Detection,
//                §5.1.9) are within 1e-10 · scale, scale = the largest |coordinate| of the 8
//                inputs.
// The first root that passes is the time of impact.
//
// NOT conservative — this is the point of the comparison with pliant::collision's CCD. It misses
// contacts (false negatives) when: the root is found in floating point on the wrong side of a
// sign change or not at all (near-double roots, p nearly ≡ 0: coplanar or near-coplanar motion,
// contacts between the tried times of a p ≡ 0 case); rounding of the position at the root puts
// the point just outside the epsilon band; a triangle or edge is degenerate. It reports spurious
// contacts (false positives) within the epsilons. Nothing here bounds either error.
//
// Thread safety: pure functions, no allocation, no exceptions. Inputs must be finite (non-finite
// inputs give an unspecified result, never UB beyond NaN propagation). Cost: a few hundred flops
// per query plus ~10 Newton steps per root.
#pragma once

#include "pliant/core/vec3.hpp"

namespace pliant::bench {

// Vertex v against triangle (f0, f1, f2); _t0 / _t1 are the positions at the start / end of the
// step. Returns whether a contact was found; toi is set to its time in [0, 1], or to 1 when none.
bool cubic_vertex_face_ccd(const Vec3d& v_t0, const Vec3d& f0_t0, const Vec3d& f1_t0,
                           const Vec3d& f2_t0, const Vec3d& v_t1, const Vec3d& f0_t1,
                           const Vec3d& f1_t1, const Vec3d& f2_t1, double& toi);

// Edge (ea0, ea1) against edge (eb0, eb1); _t0 / _t1 and the result as above.
bool cubic_edge_edge_ccd(const Vec3d& ea0_t0, const Vec3d& ea1_t0, const Vec3d& eb0_t0,
                         const Vec3d& eb1_t0, const Vec3d& ea0_t1, const Vec3d& ea1_t1,
                         const Vec3d& eb0_t1, const Vec3d& eb1_t1, double& toi);

}  // namespace pliant::bench
