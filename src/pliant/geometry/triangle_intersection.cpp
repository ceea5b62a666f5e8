#include "pliant/geometry/triangle_intersection.hpp"

#include <algorithm>
#include <array>

#include "pliant/geometry/exact_predicates.hpp"

namespace pliant::geometry {
namespace {

// Invariant of every helper: decisions are made only from exact predicate signs and exact
// comparisons of input coordinates, so each helper computes the exact answer for its stated
// preconditions.

using Triangle3 = std::array<Vec3d, 3>;

struct Point2 {
    double x;
    double y;
};

// The projection that drops axis `drop` and keeps the next two axes in cyclic order, so that
// orient2d of a projected triangle is the sign of component `drop` of its normal
// (p1 - p0) × (p2 - p0).
Point2 project(const Vec3d& p, int drop) {
    return {p[(drop + 1) % 3], p[(drop + 2) % 3]};
}

int orient(const Point2& a, const Point2& b, const Point2& c) {
    return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

bool mixed_signs(int s0, int s1, int s2) {
    const bool has_positive = s0 > 0 || s1 > 0 || s2 > 0;
    const bool has_negative = s0 < 0 || s1 < 0 || s2 < 0;
    return has_positive && has_negative;
}

bool same_strict_side(int s0, int s1, int s2) {
    return (s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0);
}

// The axis along which the triangle's normal has a nonzero component (its projection dropping
// that axis has nonzero area), or -1 when the three points are collinear (all three components
// zero).
int normal_axis(const Triangle3& t) {
    for (int axis = 0; axis < 3; ++axis) {
        if (orient(project(t[0], axis), project(t[1], axis), project(t[2], axis)) != 0) {
            return axis;
        }
    }
    return -1;
}

// --- 2D, closed sets ---------------------------------------------------------------------------

// p, known to be collinear with a and b, lies on the closed segment [a, b] (a = b allowed).
bool on_collinear_segment(const Point2& a, const Point2& b, const Point2& p) {
    return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
           p.y <= std::max(a.y, b.y);
}

// Closed segments [a, b] and [c, d] have a common point (degenerate segments allowed).
bool segments_intersect_2d(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
    const int o_abc = orient(a, b, c);
    const int o_abd = orient(a, b, d);
    const int o_cda = orient(c, d, a);
    const int o_cdb = orient(c, d, b);
    if (o_abc * o_abd < 0 && o_cda * o_cdb < 0) {
        return true;  // proper crossing
    }
    // Otherwise they meet only if an endpoint of one lies on the other.
    return (o_abc == 0 && on_collinear_segment(a, b, c)) ||
           (o_abd == 0 && on_collinear_segment(a, b, d)) ||
           (o_cda == 0 && on_collinear_segment(c, d, a)) ||
           (o_cdb == 0 && on_collinear_segment(c, d, b));
}

// p lies in the closed triangle t, whose projection has nonzero area: the three edge
// orientations never have opposite strict signs (they sum to twice the nonzero area, so they
// cannot all be ≤ 0 for a counter-clockwise t, nor all ≥ 0 for a clockwise one).
bool point_in_triangle_2d(const Point2& p, const std::array<Point2, 3>& t) {
    return !mixed_signs(orient(t[0], t[1], p), orient(t[1], t[2], p), orient(t[2], t[0], p));
}

// Closed segment [a, b] meets the closed, non-degenerate triangle t: an endpoint inside, or the
// segment crossing the boundary.
bool segment_triangle_2d(const Point2& a, const Point2& b, const std::array<Point2, 3>& t) {
    if (point_in_triangle_2d(a, t) || point_in_triangle_2d(b, t)) {
        return true;
    }
    for (int i = 0; i < 3; ++i) {
        if (segments_intersect_2d(a, b, t[static_cast<std::size_t>(i)],
                                  t[static_cast<std::size_t>((i + 1) % 3)])) {
            return true;
        }
    }
    return false;
}

std::array<Point2, 3> project(const Triangle3& t, int drop) {
    return {project(t[0], drop), project(t[1], drop), project(t[2], drop)};
}

// Two coplanar non-degenerate triangles, projected dropping `axis` (on which p's projection has
// nonzero area, hence q's too: the projection is a bijection of their common plane). If no two
// edges meet, the triangles are disjoint or one contains the other, so one vertex each decides.
bool coplanar_triangles_intersect(const Triangle3& p, const Triangle3& q, int axis) {
    const std::array<Point2, 3> p2 = project(p, axis);
    const std::array<Point2, 3> q2 = project(q, axis);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            if (segments_intersect_2d(
                    p2[static_cast<std::size_t>(i)], p2[static_cast<std::size_t>((i + 1) % 3)],
                    q2[static_cast<std::size_t>(j)], q2[static_cast<std::size_t>((j + 1) % 3)])) {
                return true;
            }
        }
    }
    return point_in_triangle_2d(p2[0], q2) || point_in_triangle_2d(q2[0], p2);
}

// --- 3D -----------------------------------------------------------------------------------------

// Closed segment [a, b] (a = b allowed) meets the closed non-degenerate triangle t, given
// side_a = orient3d(t, a), side_b = orient3d(t, b) and t's normal_axis.
bool segment_triangle(const Vec3d& a, const Vec3d& b, int side_a, int side_b, const Triangle3& t,
                      int t_axis) {
    if (side_a * side_b > 0) {
        return false;  // strictly on one side of t's plane
    }
    if (side_a == 0 && side_b == 0) {
        // In t's plane (this includes a = b on the plane).
        return segment_triangle_2d(project(a, t_axis), project(b, t_axis), project(t, t_axis));
    }
    // a ≠ b and the line ab crosses t's plane at one point X of the segment; the three volumes
    // are (b - a) · ((t_i - X) × (t_i+1 - X)): X's barycentric coordinates times one factor.
    return !mixed_signs(orient3d(a, b, t[0], t[1]), orient3d(a, b, t[1], t[2]),
                        orient3d(a, b, t[2], t[0]));
}

struct Segment3 {
    Vec3d a;
    Vec3d b;
};

// The point set of a degenerate (collinear) triangle: the segment between its two extreme
// vertices along an axis on which they differ (that coordinate is an affine parameter of their
// common line), or [t0, t0] when all three coincide.
Segment3 hull_of_collinear(const Triangle3& t) {
    for (int axis = 0; axis < 3; ++axis) {
        const double c0 = t[0][axis];
        const double c1 = t[1][axis];
        const double c2 = t[2][axis];
        if (c0 == c1 && c1 == c2) {
            continue;
        }
        std::size_t lo = 0;
        std::size_t hi = 0;
        for (std::size_t i = 1; i < 3; ++i) {
            if (t[i][axis] < t[lo][axis]) {
                lo = i;
            }
            if (t[i][axis] > t[hi][axis]) {
                hi = i;
            }
        }
        return {t[lo], t[hi]};
    }
    return {t[0], t[0]};
}

bool segment_triangle(const Segment3& s, const Triangle3& t, int t_axis) {
    return segment_triangle(s.a, s.b, orient3d(t[0], t[1], t[2], s.a),
                            orient3d(t[0], t[1], t[2], s.b), t, t_axis);
}

// Closed segments [a, b] and [c, d] in 3D (either may be a point).
bool segments_intersect_3d(const Segment3& s, const Segment3& r) {
    if (orient3d(s.a, s.b, r.a, r.b) != 0) {
        return false;  // not coplanar: no common point
    }
    // A coordinate projection injective on the plane of the four points: one in which some
    // three of them span a nonzero area.
    const std::array<Triangle3, 4> triples = {Triangle3{s.a, s.b, r.a}, Triangle3{s.a, s.b, r.b},
                                              Triangle3{s.a, r.a, r.b}, Triangle3{s.b, r.a, r.b}};
    for (const Triangle3& triple : triples) {
        const int axis = normal_axis(triple);
        if (axis >= 0) {
            return segments_intersect_2d(project(s.a, axis), project(s.b, axis), project(r.a, axis),
                                         project(r.b, axis));
        }
    }
    // All four collinear: compare intervals along an axis on which they differ.
    for (int axis = 0; axis < 3; ++axis) {
        const double s_lo = std::min(s.a[axis], s.b[axis]);
        const double s_hi = std::max(s.a[axis], s.b[axis]);
        const double r_lo = std::min(r.a[axis], r.b[axis]);
        const double r_hi = std::max(r.a[axis], r.b[axis]);
        if (s_lo == s_hi && r_lo == r_hi && s_lo == r_lo) {
            continue;  // all four equal on this axis
        }
        return s_lo <= r_hi && r_lo <= s_hi;
    }
    return true;  // all four points coincide
}

}  // namespace

bool triangles_intersect(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& q0,
                         const Vec3d& q1, const Vec3d& q2) {
    const Triangle3 p = {p0, p1, p2};
    const Triangle3 q = {q0, q1, q2};
    const int p_axis = normal_axis(p);
    const int q_axis = normal_axis(q);

    // 1. Degenerate triangles: segments or points.
    if (p_axis < 0 && q_axis < 0) {
        return segments_intersect_3d(hull_of_collinear(p), hull_of_collinear(q));
    }
    if (p_axis < 0) {
        return segment_triangle(hull_of_collinear(p), q, q_axis);
    }
    if (q_axis < 0) {
        return segment_triangle(hull_of_collinear(q), p, p_axis);
    }

    // 2. Sides of each triangle's vertices relative to the other's plane.
    const std::array<int, 3> q_side = {orient3d(p0, p1, p2, q0), orient3d(p0, p1, p2, q1),
                                       orient3d(p0, p1, p2, q2)};
    if (same_strict_side(q_side[0], q_side[1], q_side[2])) {
        return false;
    }
    if (q_side[0] == 0 && q_side[1] == 0 && q_side[2] == 0) {
        return coplanar_triangles_intersect(p, q, p_axis);
    }
    const std::array<int, 3> p_side = {orient3d(q0, q1, q2, p0), orient3d(q0, q1, q2, p1),
                                       orient3d(q0, q1, q2, p2)};
    if (same_strict_side(p_side[0], p_side[1], p_side[2])) {
        return false;
    }

    // 3. Distinct planes: some edge of one triangle meets the other.
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t j = (i + 1) % 3;
        if (segment_triangle(p[i], p[j], p_side[i], p_side[j], q, q_axis) ||
            segment_triangle(q[i], q[j], q_side[i], q_side[j], p, p_axis)) {
            return true;
        }
    }
    return false;
}

}  // namespace pliant::geometry
