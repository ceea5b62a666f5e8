// Point-triangle proximity (the vertex-face narrow-phase query): the point of triangle (a, b, c)
// closest to p, as barycentric weights, with the distance, a contact normal and the Voronoi region.
//
//   const auto prox = point_triangle_proximity(p, a, b, c);
//   // closest point: prox.barycentric.x * a + prox.barycentric.y * b + prox.barycentric.z * c
//
// Contract
//   - Inputs: any length unit; distance is returned in the same unit. Real is float or double.
//   - barycentric = (w0, w1, w2): each in [0, 1], summing to 1 (to rounding); distance is
//     |p - (w0 a + w1 b + w2 c)|, the minimum over the (closed, solid) triangle.
//   - normal is a unit vector from the closest point towards p. When distance is 0 (p on the
//     triangle) it is the unit triangle normal cross(b - a, c - a) / |...|; for a degenerate
//     triangle, a unit vector perpendicular to its longest edge ((0, 0, 1) if all corners
//     coincide).
//   - region is the Voronoi feature of the closest point (PointTriangleRegion): 0 the face
//     interior, 1 / 2 / 3 the vertices a / b / c, 4 / 5 / 6 the edges ab / bc / ca.
//   - Degenerate triangles are data, not an error: when the height over the longest edge is at
//     most 16 ulps of that edge (collinear corners, two or three coincident corners) the face has
//     no interior and the result is the closest of the three edges ab, bc, ca as segments (ties go
//     to the first); region is then that edge, or its vertex when the closest point is an endpoint.
//     Points on the triangle's plane need no special case.
//   - Range: finite coordinates whose differences stay within about 1e±9 (float) or 1e±75 (double):
//     products of four coordinate differences are formed.
//   - Per-element kernel: no allocation, no exceptions, no state; thread safe; O(1).
//
// Accuracy: the distance is within a few ulps of the coordinates' magnitude of the exact one for
// every shape down to the degeneracy threshold (slivers included, checked down to height 1e-15 of
// the longest edge).
//
// Reference: C. Ericson, Real-Time Collision Detection (2005), §5.1.5 "Closest point on triangle to
// point" (ClosestPtPointTriangle): vertex, edge and face regions tested in that order. Changes for
// robustness: the edge parameters are the projections (p - a)·(b - a) / |b - a|² (d1 / (d1 - d3) in
// exact arithmetic), clamped; the triple products are evaluated as n·((b - a) x (p - a)) and
// alike (equal to Ericson's d1 d4 - d3 d2 by the Lagrange identity, but backward stable instead of
// losing eps * longest² / area); the face weights come from the frame of the longest edge and
// its height vector rather than from va, vb, vc (see Step 3).
#pragma once

#include <limits>

#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::collision {

// The Voronoi feature of a triangle that holds the closest point.
struct PointTriangleRegion {
    static constexpr int FACE = 0;
    static constexpr int VERTEX_A = 1;
    static constexpr int VERTEX_B = 2;
    static constexpr int VERTEX_C = 3;
    static constexpr int EDGE_AB = 4;
    static constexpr int EDGE_BC = 5;
    static constexpr int EDGE_CA = 6;
};

template <typename Real>
struct PointTriangleProximity {
    Real distance;           // |p - closest point| >= 0, in the unit of the inputs
    Vec3<Real> barycentric;  // weights (w0, w1, w2) of a, b, c: each >= 0, sum 1
    Vec3<Real> normal;       // unit; from the closest point towards p (see the header for 0)
    int region;              // PointTriangleRegion: 0 face, 1-3 vertices a-c, 4-6 edges ab, bc, ca
};

namespace detail {

// Distance and normal of p to the closest point; fallback_normal (not necessarily unit) when p is
// on the triangle.
template <typename Real>
PLIANT_HOST_DEVICE inline PointTriangleProximity<Real> make_point_triangle_proximity(
    Vec3<Real> p, Vec3<Real> closest, Vec3<Real> barycentric, int region,
    Vec3<Real> fallback_normal) {
    const LengthAndDirection<Real> separation = length_and_direction(p - closest);
    Vec3<Real> normal = separation.direction;
    if (!separation.has_direction) {
        const LengthAndDirection<Real> unit_fallback = length_and_direction(fallback_normal);
        normal = unit_fallback.has_direction ? unit_fallback.direction
                                             : Vec3<Real>{Real(0), Real(0), Real(1)};
    }
    return {.distance = separation.length,
            .barycentric = barycentric,
            .normal = normal,
            .region = region};
}

// The closest of the segments ab, bc, ca: the whole answer for a zero-area triangle, and the
// fallback when the face weights contradict the region tests. normal_if_touching (not necessarily
// unit) is the normal when p is on the triangle; zero selects a unit vector perpendicular to the
// longest edge.
template <typename Real>
PLIANT_HOST_DEVICE inline PointTriangleProximity<Real> point_triangle_boundary_proximity(
    Vec3<Real> p, Vec3<Real> a, Vec3<Real> b, Vec3<Real> c, Vec3<Real> normal_if_touching) {
    const Vec3<Real> corners[3] = {a, b, c};
    int best_edge = 0;
    Real best_parameter = Real(0);
    Real best_distance = Real(0);
    Real longest_squared_length = Real(-1);
    Vec3<Real> longest_edge{};
    for (int edge = 0; edge < 3; ++edge) {
        // Edge e runs from corner e to corner (e + 1) % 3: ab, bc, ca.
        const Vec3<Real> start = corners[edge];
        const Vec3<Real> direction = corners[(edge + 1) % 3] - start;
        const Real parameter = closest_parameter_on_segment(p, start, direction);
        const Real distance = length_and_direction(p - (start + direction * parameter)).length;
        if (edge == 0 || distance < best_distance) {
            best_edge = edge;
            best_parameter = parameter;
            best_distance = distance;
        }
        if (squared_norm(direction) > longest_squared_length) {
            longest_squared_length = squared_norm(direction);
            longest_edge = direction;
        }
    }
    const int start_corner = best_edge;
    const int end_corner = (best_edge + 1) % 3;
    Vec3<Real> barycentric{};
    barycentric[start_corner] = Real(1) - best_parameter;
    barycentric[end_corner] = best_parameter;
    const int region = best_parameter == Real(0)   ? PointTriangleRegion::VERTEX_A + start_corner
                       : best_parameter == Real(1) ? PointTriangleRegion::VERTEX_A + end_corner
                                                   : PointTriangleRegion::EDGE_AB + best_edge;
    const Vec3<Real> start = corners[start_corner];
    const Vec3<Real> closest = start + (corners[end_corner] - start) * best_parameter;
    const bool has_normal = !(normal_if_touching == Vec3<Real>{});
    return make_point_triangle_proximity(
        p, closest, barycentric, region,
        has_normal ? normal_if_touching : any_perpendicular(longest_edge));
}

}  // namespace detail

// Closest point of triangle (a, b, c) to p; see the header comment for the contract.
template <typename Real>
PLIANT_HOST_DEVICE inline PointTriangleProximity<Real> point_triangle_proximity(Vec3<Real> p,
                                                                                Vec3<Real> a,
                                                                                Vec3<Real> b,
                                                                                Vec3<Real> c) {
    using Region = PointTriangleRegion;
    const Real zero = Real(0);
    const Real one = Real(1);
    const Vec3<Real> ab = b - a;
    const Vec3<Real> ac = c - a;
    const Vec3<Real> bc = c - b;
    const Vec3<Real> face_normal = cross(ab, ac);

    // Step 1: zero-area triangles (height over the longest edge <= 16 ulps of it) have no face.
    const Real ab_squared = squared_norm(ab);
    const Real ac_squared = squared_norm(ac);
    const Real bc_squared = squared_norm(bc);
    const Real longest_squared = ab_squared > ac_squared
                                     ? (ab_squared > bc_squared ? ab_squared : bc_squared)
                                     : (ac_squared > bc_squared ? ac_squared : bc_squared);
    const Real sine2 = detail::degenerate_sine<Real>() * detail::degenerate_sine<Real>();
    if (!(squared_norm(face_normal) > (sine2 * longest_squared) * longest_squared)) {
        return detail::point_triangle_boundary_proximity(p, a, b, c, Vec3<Real>{});
    }

    // Step 2: vertex regions and edge regions (Ericson §5.1.5).
    const Vec3<Real> ap = p - a;
    const Real d1 = dot(ab, ap);
    const Real d2 = dot(ac, ap);
    if (d1 <= zero && d2 <= zero) {
        return detail::make_point_triangle_proximity(p, a, Vec3<Real>{one, zero, zero},
                                                     Region::VERTEX_A, face_normal);
    }
    const Vec3<Real> bp = p - b;
    const Real d3 = dot(ab, bp);
    const Real d4 = dot(ac, bp);
    if (d3 >= zero && d4 <= d3) {
        return detail::make_point_triangle_proximity(p, b, Vec3<Real>{zero, one, zero},
                                                     Region::VERTEX_B, face_normal);
    }
    const Real vc = dot(face_normal, cross(ab, ap));
    if (vc <= zero && d1 >= zero && d3 <= zero) {
        const Real v = detail::clamp01(d1 / ab_squared);
        return detail::make_point_triangle_proximity(p, a + ab * v, Vec3<Real>{one - v, v, zero},
                                                     Region::EDGE_AB, face_normal);
    }
    const Vec3<Real> cp = p - c;
    const Real d5 = dot(ab, cp);
    const Real d6 = dot(ac, cp);
    if (d6 >= zero && d5 <= d6) {
        return detail::make_point_triangle_proximity(p, c, Vec3<Real>{zero, zero, one},
                                                     Region::VERTEX_C, face_normal);
    }
    const Real vb = dot(face_normal, cross(ap, ac));
    if (vb <= zero && d2 >= zero && d6 <= zero) {
        const Real w = detail::clamp01(d2 / ac_squared);
        return detail::make_point_triangle_proximity(p, a + ac * w, Vec3<Real>{one - w, zero, w},
                                                     Region::EDGE_CA, face_normal);
    }
    const Real va = dot(cross(ab, bc), cross(bc, bp));
    if (va <= zero && (d4 - d3) >= zero && (d5 - d6) >= zero) {
        const Real w = detail::clamp01(dot(bc, bp) / bc_squared);
        return detail::make_point_triangle_proximity(p, b + bc * w, Vec3<Real>{zero, one - w, w},
                                                     Region::EDGE_BC, face_normal);
    }

    // Step 3: the face. Ericson normalises va, vb, vc, but for slivers those signed areas carry
    // errors of eps * longest / height relative, which would move the point along the sliver.
    // Instead take the coordinates in the orthogonal frame of the longest edge i -> j and the
    // height vector m of the opposite corner k: the position along the edge (sigma) is a plain
    // projection, and an error in the across coordinate (eta) only moves the point across the
    // sliver, by at most its height.
    const Vec3<Real> corners[3] = {a, b, c};
    const int i = longest_squared == ab_squared ? 0 : (longest_squared == bc_squared ? 1 : 2);
    const int j = (i + 1) % 3;
    const int k = (i + 2) % 3;
    const Vec3<Real> edge = corners[j] - corners[i];
    const Vec3<Real> to_k = corners[k] - corners[i];
    const Vec3<Real> to_p = p - corners[i];
    const Real foot = dot(to_k, edge) / longest_squared;
    const Vec3<Real> height = to_k - edge * foot;
    const Real sigma = dot(to_p, edge) / longest_squared;
    // Remove the along-edge part first: height is orthogonal to edge only to eps * longest, and
    // that error times the along-edge part would dominate eta.
    const Real eta = dot(to_p - edge * sigma, height) / squared_norm(height);
    Vec3<Real> barycentric{};
    barycentric[j] = sigma - eta * foot;
    barycentric[k] = eta;
    barycentric[i] = one - barycentric[j] - barycentric[k];
    // Rounding can leave a weight slightly negative at a region boundary: clamp those; a clearly
    // negative weight means the region tests disagreed, and then the boundary is the answer.
    const Real boundary_slack = Real(4) * std::numeric_limits<Real>::epsilon();
    Real weight_sum = zero;
    for (int corner = 0; corner < 3; ++corner) {
        if (!(barycentric[corner] >= -boundary_slack)) {
            return detail::point_triangle_boundary_proximity(p, a, b, c, face_normal);
        }
        barycentric[corner] = barycentric[corner] > zero ? barycentric[corner] : zero;
        weight_sum += barycentric[corner];
    }
    barycentric = barycentric / weight_sum;
    return detail::make_point_triangle_proximity(p, a + ab * barycentric.y + ac * barycentric.z,
                                                 barycentric, Region::FACE, face_normal);
}

}  // namespace pliant::collision
