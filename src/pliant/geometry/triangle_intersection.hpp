// Exact intersection test of two closed triangles in 3D (double coordinates).
//
//   triangles_intersect(p0, p1, p2, q0, q1, q2)
//     true iff the closed triangles conv{p0, p1, p2} and conv{q0, q1, q2} have a common point:
//     touching at a vertex, along an edge or over an area counts. Exact (no false positive or
//     negative from rounding) for coordinates in the domain of exact_predicates.hpp (0 or
//     2^-300 ≤ |x| ≤ 2^300); decided by orient3d / orient2d signs and exact comparisons of
//     coordinates only, no constructed points. Symmetric in the two triangles and invariant under
//     any permutation of either triangle's vertices.
//
// Method:
//   - Non-degenerate, not coplanar: Q is rejected when all its vertices lie strictly on one side
//     of P's plane (and vice versa). Otherwise two closed triangles in distinct planes intersect
//     iff an edge of one meets the other triangle: P ∩ Q lies on the line where the planes meet,
//     as the overlap of two segments whose endpoints lie on the triangles' boundaries, and a
//     nonempty overlap of two segments contains an endpoint of one of them. An edge [a, b] meets
//     a triangle t when a and b are not strictly on one side of its plane and the line ab passes
//     through the closed triangle: orient3d(a, b, t_i, t_i+1) for the three edges of t are never
//     of opposite strict signs (they are the barycentric coordinates of the crossing point, up to
//     a common factor). An edge lying in t's plane is tested in 2D as below.
//   - Coplanar: both triangles are projected onto the coordinate plane in which P's projection
//     has nonzero area (an affine bijection of their common plane, so incidences are preserved
//     exactly), where they intersect iff two edges meet (closed segments, collinear overlaps
//     included) or a vertex of one lies in the other.
//   - Degenerate triangles (collinear or repeated vertex positions; exact test: all three
//     coordinate projections have orient2d = 0) are the point sets they are: the segment between
//     their two extreme vertices (found by exact comparisons along an axis on which the vertices
//     differ), or a point when all three vertices coincide. A degenerate triangle against a
//     non-degenerate one is a segment-triangle test (a point is the segment [p, p]); two
//     degenerate triangles are a segment-segment test: coplanar (orient3d = 0), then in 2D on a
//     coordinate plane that is injective on the plane of the four points, or in 1D along an axis
//     when all four are collinear.
//
// Cost: 6 orient2d to classify the triangles, then 3 to 6 orient3d for a pair separated by the
// plane of one of them, at most 24 orient3d in the non-coplanar case; the coplanar case costs up
// to 42 orient2d.
// Thread safe, no allocation, no exceptions.
#pragma once

#include "pliant/core/vec3.hpp"

namespace pliant::geometry {

bool triangles_intersect(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& q0,
                         const Vec3d& q1, const Vec3d& q2);

}  // namespace pliant::geometry
