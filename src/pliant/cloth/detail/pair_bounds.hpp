// Lower bounds on the distance of a feature pair (vertex-face or edge-edge) that cost a few
// operations, for filters that must never drop a pair closer than a threshold: the
// self-collision's candidate, contact and fail-safe filters (self_collision.hpp) run them before
// the exact distance (collision/point_triangle.hpp, collision/segment_segment.hpp).
//
// Each takes the pair's four vertex values: the first feature is p0 (vertex-face: the vertex,
// then the triangle p1 p2 p3) or p0 p1 (edge-edge: then the edge p2 p3). EDGE_EDGE selects the
// split at compile time.
//
// Contract: box_gap and centroid_axis_gap never exceed the exact distance between the features
// (the convex hulls of their vertices) by more than rounding (a few ulps of the coordinates);
// both are 0 when the features' hulls overlap along the tested directions; finite inputs give
// finite results. largest_pair_difference is max |d_i − d_j| over i in the first feature and j
// in the second: with d the vertices' displacements, no feature distance changes by more
// (distance is 1-Lipschitz in it), with d their velocities, it bounds the relative speed.
// Per-element kernels: no allocation, no state.
#pragma once

#include <algorithm>
#include <cmath>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// The distance between the boxes of the two features' vertices: a lower bound on their distance.
template <bool EDGE_EDGE>
inline double box_gap(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& p3) {
    Vec3d a_lo = p0;
    Vec3d a_hi = p0;
    Vec3d b_lo = min(p2, p3);
    Vec3d b_hi = max(p2, p3);
    if constexpr (EDGE_EDGE) {
        a_lo = min(a_lo, p1);
        a_hi = max(a_hi, p1);
    } else {
        b_lo = min(b_lo, p1);
        b_hi = max(b_hi, p1);
    }
    const Vec3d gap = max(max(a_lo - b_hi, b_lo - a_hi), Vec3d{0.0, 0.0, 0.0});
    return std::sqrt(dot(gap, gap));
}

// The gap between the projections of the two features' vertices on the line through their
// centroids: a separating-axis lower bound on their distance, tight where box_gap is not
// (neighbouring features of a sheet that lies diagonally to the axes). About a tenth of an exact
// distance's cost (a separating axis: any axis gives a lower bound).
template <bool EDGE_EDGE>
inline double centroid_axis_gap(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2,
                                const Vec3d& p3) {
    // The axis points from hull A's centroid to hull B's: the gap is B's lowest projection less
    // A's highest (A the triangle and B the vertex, or A the first edge and B the second).
    double a_max = 0.0;
    double b_min = 0.0;
    Vec3d axis{};
    if constexpr (EDGE_EDGE) {
        axis = (p2 + p3) - (p0 + p1);
        a_max = std::max(dot(p0, axis), dot(p1, axis));
        b_min = std::min(dot(p2, axis), dot(p3, axis));
    } else {
        axis = p0 - (p1 + p2 + p3) * (1.0 / 3.0);
        a_max = std::max({dot(p1, axis), dot(p2, axis), dot(p3, axis)});
        b_min = dot(p0, axis);
    }
    const double length = norm(axis);
    return b_min > a_max && length > 0.0 ? (b_min - a_max) / length : 0.0;
}

// The largest |d_i − d_j| over i in the first feature and j in the second (of velocities or
// displacements).
template <bool EDGE_EDGE>
inline double largest_pair_difference(const Vec3d& d0, const Vec3d& d1, const Vec3d& d2,
                                      const Vec3d& d3) {
    double m = 0.0;
    if constexpr (EDGE_EDGE) {
        m = std::max({squared_norm(d0 - d2), squared_norm(d0 - d3), squared_norm(d1 - d2),
                      squared_norm(d1 - d3)});
    } else {
        m = std::max({squared_norm(d0 - d1), squared_norm(d0 - d2), squared_norm(d0 - d3)});
    }
    return std::sqrt(m);
}

}  // namespace pliant::cloth::detail
