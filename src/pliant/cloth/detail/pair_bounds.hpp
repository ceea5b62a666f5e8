// Lower bounds on the distance of a feature pair (vertex-face or edge-edge), or of two point
// sets, that cost a few operations, for filters that must never drop a pair closer than a
// threshold: the self-collision's candidate, contact and fail-safe filters (self_collision.hpp) run
// them before the exact distance (collision/point_triangle.hpp, collision/segment_segment.hpp).
//
// Each takes the pair's four vertex values: the first feature is p0 (vertex-face: the vertex,
// then the triangle p1 p2 p3) or p0 p1 (edge-edge: then the edge p2 p3). EDGE_EDGE selects the
// split at compile time.
//
// The point-set overloads take the two sets directly (the triangle-pair filter's triangles).
//
// Contract: box_gap and centroid_axis_gap never exceed the exact distance between the features
// or sets (the convex hulls of their points) by more than rounding (a few ulps of the coordinates);
// both are 0 when the features' hulls overlap along the tested directions; finite inputs give
// finite results. largest_pair_difference is max |d_i − d_j| over i in the first feature and j
// in the second: with d the vertices' displacements, no feature distance changes by more
// (distance is 1-Lipschitz in it), with d their velocities, it bounds the relative speed.
// Per-element kernels: no allocation, no state.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// The distance between the boxes of point sets a and b: a lower bound on the distance between
// their convex hulls.
template <std::size_t NA, std::size_t NB>
inline double box_gap(const Vec3d (&a)[NA], const Vec3d (&b)[NB]) {
    Vec3d a_lo = a[0];
    Vec3d a_hi = a[0];
    for (std::size_t k = 1; k < NA; ++k) {
        a_lo = min(a_lo, a[k]);
        a_hi = max(a_hi, a[k]);
    }
    Vec3d b_lo = b[0];
    Vec3d b_hi = b[0];
    for (std::size_t k = 1; k < NB; ++k) {
        b_lo = min(b_lo, b[k]);
        b_hi = max(b_hi, b[k]);
    }
    const Vec3d gap = max(max(a_lo - b_hi, b_lo - a_hi), Vec3d{0.0, 0.0, 0.0});
    return std::sqrt(dot(gap, gap));
}

// The gap between the projections of point sets a and b on the line through their centroids: a
// separating-axis lower bound on the distance between their hulls (any axis gives one), tight
// where box_gap is not (neighbouring features of a sheet that lies diagonally to the axes).
// About a tenth of an exact distance's cost. For sets of equal size the axis is the difference
// of the sums (the centroids' difference scaled, which the gap does not depend on).
template <std::size_t NA, std::size_t NB>
inline double centroid_axis_gap(const Vec3d (&a)[NA], const Vec3d (&b)[NB]) {
    Vec3d a_sum = a[0];
    for (std::size_t k = 1; k < NA; ++k) {
        a_sum = a_sum + a[k];
    }
    Vec3d b_sum = b[0];
    for (std::size_t k = 1; k < NB; ++k) {
        b_sum = b_sum + b[k];
    }
    const Vec3d axis = NA == NB ? b_sum - a_sum
                                : b_sum * (1.0 / static_cast<double>(NB)) -
                                      a_sum * (1.0 / static_cast<double>(NA));
    double a_max = dot(a[0], axis);
    for (std::size_t k = 1; k < NA; ++k) {
        a_max = std::max(a_max, dot(a[k], axis));
    }
    double b_min = dot(b[0], axis);
    for (std::size_t k = 1; k < NB; ++k) {
        b_min = std::min(b_min, dot(b[k], axis));
    }
    const double length = norm(axis);
    return b_min > a_max && length > 0.0 ? (b_min - a_max) / length : 0.0;
}

// The two bounds on a feature pair's four vertices.
template <bool EDGE_EDGE>
inline double box_gap(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& p3) {
    if constexpr (EDGE_EDGE) {
        const Vec3d a[2] = {p0, p1};
        const Vec3d b[2] = {p2, p3};
        return box_gap(a, b);
    } else {
        const Vec3d a[1] = {p0};
        const Vec3d b[3] = {p1, p2, p3};
        return box_gap(a, b);
    }
}

template <bool EDGE_EDGE>
inline double centroid_axis_gap(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2,
                                const Vec3d& p3) {
    if constexpr (EDGE_EDGE) {
        const Vec3d a[2] = {p0, p1};
        const Vec3d b[2] = {p2, p3};
        return centroid_axis_gap(a, b);
    } else {
        const Vec3d a[1] = {p0};
        const Vec3d b[3] = {p1, p2, p3};
        return centroid_axis_gap(a, b);
    }
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
