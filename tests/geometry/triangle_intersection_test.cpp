#include "pliant/geometry/triangle_intersection.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace pliant::geometry {
namespace {

using Tri = std::array<Vec3d, 3>;

constexpr double TINY = 0x1p-40;  // ≈ 9.1e-13

bool intersect(const Tri& p, const Tri& q) {
    return triangles_intersect(p[0], p[1], p[2], q[0], q[1], q[2]);
}

// Maps that change neither the answer nor, for these small dyadic inputs, a single bit of the
// geometry: power-of-two scales (≈ 1e-6 and 1e6), a dyadic translation, a shear that tilts the
// plane z = 0 onto z = x + 2y, and permutations of the axes (so every projection is used).
const std::vector<std::pair<std::string, std::function<Vec3d(const Vec3d&)>>>& exact_maps() {
    static const std::vector<std::pair<std::string, std::function<Vec3d(const Vec3d&)>>> maps = {
        {"identity",
         [](const Vec3d& p) {
             return p;
         }},
        {"scale 2^-20",
         [](const Vec3d& p) {
             return p * 0x1p-20;
         }},
        {"scale 2^20",
         [](const Vec3d& p) {
             return p * 0x1p20;
         }},
        {"translate",
         [](const Vec3d& p) {
             return p + Vec3d{1024.0, -2048.0, 1536.0};
         }},
        {"shear",
         [](const Vec3d& p) {
             return Vec3d{p.x, p.y, p.z + p.x + 2.0 * p.y};
         }},
        {"axes yzx",
         [](const Vec3d& p) {
             return Vec3d{p.y, p.z, p.x};
         }},
        {"axes zxy sheared",
         [](const Vec3d& p) {
             return Vec3d{p.z + p.y, p.x - p.y, p.y};
         }},
    };
    return maps;
}

// The answer for both argument orders and all 6 × 6 vertex orders.
void expect_symmetric(const Tri& p, const Tri& q, bool expected, const std::string& where) {
    std::array<int, 3> ip = {0, 1, 2};
    do {
        std::array<int, 3> iq = {0, 1, 2};
        do {
            const Tri pp = {p[ip[0]], p[ip[1]], p[ip[2]]};
            const Tri qq = {q[iq[0]], q[iq[1]], q[iq[2]]};
            ASSERT_EQ(intersect(pp, qq), expected) << where;
            ASSERT_EQ(intersect(qq, pp), expected) << where << " (swapped)";
        } while (std::next_permutation(iq.begin(), iq.end()));
    } while (std::next_permutation(ip.begin(), ip.end()));
}

// expect_symmetric under every exact map.
void expect_intersect(const Tri& p, const Tri& q, bool expected) {
    for (const auto& [name, map] : exact_maps()) {
        const Tri mp = {map(p[0]), map(p[1]), map(p[2])};
        const Tri mq = {map(q[0]), map(q[1]), map(q[2])};
        expect_symmetric(mp, mq, expected, name);
    }
}

const Tri P = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};

Tri moved(const Tri& t, const Vec3d& by) {
    return {t[0] + by, t[1] + by, t[2] + by};
}

TEST(TriangleIntersection, CrossingAndSeparated) {
    const Tri q = {Vec3d{0.2, 0.2, -1}, Vec3d{0.3, 0.2, 1}, Vec3d{0.2, 0.3, 1}};
    expect_intersect(P, q, true);
    expect_intersect(P, moved(q, {0, 0, 1.5}), false);     // above the plane
    expect_intersect(P, moved(q, {2, 0, 0}), false);       // pierces the plane outside P
    expect_intersect(P, moved(q, {0.25, 0.25, 0}), true);  // pierces P near its long edge
    expect_intersect(P, moved(q, {0.3, 0.3, 0}), false);
}

TEST(TriangleIntersection, TouchingAtAVertex) {
    // Q's vertex on P's vertex, on P's edge, inside P; Q otherwise above.
    expect_intersect(P, {Vec3d{1, 0, 0}, Vec3d{2, 0, 1}, Vec3d{1, 1, 1}}, true);
    expect_intersect(P, {Vec3d{0.5, 0, 0}, Vec3d{0, 0, 1}, Vec3d{1, 1, 1}}, true);
    expect_intersect(P, {Vec3d{0.25, 0.25, 0}, Vec3d{0, 0, 1}, Vec3d{1, 0, 1}}, true);
    // Near misses: the touching vertex lifted by ≈ 1e-12, or moved just outside the edge.
    expect_intersect(P, {Vec3d{0.25, 0.25, TINY}, Vec3d{0, 0, 1}, Vec3d{1, 0, 1}}, false);
    expect_intersect(P, {Vec3d{0.5, -TINY, 0}, Vec3d{0, -1, 1}, Vec3d{1, -1, 1}}, false);
    expect_intersect(P, {Vec3d{0.5, 0.5 + TINY, 0}, Vec3d{1, 1, 1}, Vec3d{1, 1, -1}}, false);
    expect_intersect(P, {Vec3d{0.5, 0.5 - TINY, 0}, Vec3d{1, 1, 1}, Vec3d{1, 1, -1}}, true);
}

TEST(TriangleIntersection, TouchingAlongAnEdge) {
    // Q contains [0.2, 0.8] × {0} × {0} and leans away from P (y < 0, z > 0).
    const Tri q = {Vec3d{0.2, 0, 0}, Vec3d{0.8, 0, 0}, Vec3d{0.5, -1, 1}};
    expect_intersect(P, q, true);
    expect_intersect(P, moved(q, {0, -TINY, 0}), false);
    expect_intersect(P, moved(q, {0, 0, TINY}), false);
    expect_intersect(P, moved(q, {0, TINY, 0}), true);
    // An edge of Q crossing P's edge on the x axis, the only common point (Q lies in x = 0.5,
    // where P is the segment 0 ≤ y ≤ 0.5 and Q the region y + z ≤ 0).
    const Tri cross = {Vec3d{0.5, -1, 1}, Vec3d{0.5, 1, -1}, Vec3d{0.5, -1, -1}};
    expect_intersect(P, cross, true);
    expect_intersect(P, moved(cross, {0, -TINY, 0}), false);
    expect_intersect(P, moved(cross, {0, 0, TINY}), true);
}

TEST(TriangleIntersection, Coplanar) {
    expect_intersect(P, P, true);
    expect_intersect(P, {Vec3d{0.25, 0.25, 0}, Vec3d{2, 0.25, 0}, Vec3d{0.25, 2, 0}}, true);
    expect_intersect(P, {Vec3d{0.1, 0.1, 0}, Vec3d{0.2, 0.1, 0}, Vec3d{0.1, 0.2, 0}},
                     true);                                                           // inside
    expect_intersect(P, {Vec3d{-1, -1, 0}, Vec3d{3, -1, 0}, Vec3d{-1, 3, 0}}, true);  // around
    expect_intersect(P, {Vec3d{1, 1, 0}, Vec3d{2, 1, 0}, Vec3d{1, 2, 0}}, false);
    expect_intersect(P, {Vec3d{1, 0, 0}, Vec3d{2, 0, 0}, Vec3d{2, 1, 0}}, true);     // a vertex
    expect_intersect(P, {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{1, 1, 0}}, true);     // an edge
    expect_intersect(P, {Vec3d{0.5, 0, 0}, Vec3d{2, 0, 0}, Vec3d{1, -1, 0}}, true);  // overlap
    // A star of David: edges cross, no vertex inside the other.
    expect_intersect({Vec3d{0, 0, 0}, Vec3d{4, 0, 0}, Vec3d{2, 3, 0}},
                     {Vec3d{0, 2, 0}, Vec3d{4, 2, 0}, Vec3d{2, -1, 0}}, true);
    // A vertex on the long edge x + y = 1, then 1e-12 outside and inside.
    const auto corner = [](double d) {
        return Tri{Vec3d{0.5 + d, 0.5, 0}, Vec3d{2, 0.5, 0}, Vec3d{2, 2, 0}};
    };
    expect_intersect(P, corner(0), true);
    expect_intersect(P, corner(TINY), false);
    expect_intersect(P, corner(-TINY), true);
}

TEST(TriangleIntersection, ParallelPlanes) {
    expect_intersect(P, moved(P, {0, 0, TINY}), false);
    expect_intersect(P, moved(P, {0, 0, -TINY}), false);
    expect_intersect(P, moved(P, {0.25, 0.25, 0}), true);
}

TEST(TriangleIntersection, DegenerateTriangles) {
    const Tri wall = {Vec3d{2, 0, -1}, Vec3d{0, 2, -1}, Vec3d{1, 1, 1}};  // in the plane x + y = 2
    // Collinear triangles (the extreme vertices listed in any place) are segments.
    expect_intersect({Vec3d{0, 0, 0}, Vec3d{2, 2, 0}, Vec3d{1.5, 1.5, 0}}, wall, true);
    expect_intersect({Vec3d{0, 0, 0}, Vec3d{0.9, 0.9, 0}, Vec3d{0.5, 0.5, 0}}, wall, false);
    expect_intersect({Vec3d{0, 0, 0}, Vec3d{1, 1, 0}, Vec3d{0.5, 0.5, 0}}, wall, true);  // end
    // Repeated vertices: a segment and a point.
    expect_intersect({Vec3d{1, 1, 0}, Vec3d{1, 1, 0}, Vec3d{0, 0, 0}}, wall, true);
    expect_intersect({Vec3d{1, 1, 0}, Vec3d{1, 1, 0}, Vec3d{1, 1, 0}}, wall, true);
    expect_intersect({Vec3d{1, 1, 1}, Vec3d{1, 1, 1}, Vec3d{1, 1, 1}}, wall, true);  // a vertex
    expect_intersect({Vec3d{1, 1, 1.5}, Vec3d{1, 1, 1.5}, Vec3d{1, 1, 1.5}}, wall, false);
    expect_intersect({Vec3d{1, 1, TINY}, Vec3d{1, 1, 0}, Vec3d{0, 0, 0}}, wall, true);
    // A segment in the triangle's plane: across it, outside it, ending on its vertex.
    expect_intersect({Vec3d{-1, 0.5, 0}, Vec3d{2, 0.5, 0}, Vec3d{0.5, 0.5, 0}}, P, true);
    expect_intersect({Vec3d{-1, 2, 0}, Vec3d{2, 2, 0}, Vec3d{0, 2, 0}}, P, false);
    expect_intersect({Vec3d{-1, 1, 0}, Vec3d{0, 1, 0}, Vec3d{-0.5, 1, 0}}, P, true);
    expect_intersect({Vec3d{-1, 1, 0}, Vec3d{-TINY, 1, 0}, Vec3d{-0.5, 1, 0}}, P, false);
}

TEST(TriangleIntersection, TwoDegenerateTriangles) {
    const auto segment = [](const Vec3d& a, const Vec3d& b) {
        return Tri{a, b, (a + b) * 0.5};
    };
    const auto point = [](const Vec3d& a) {
        return Tri{a, a, a};
    };
    const Tri diagonal = segment({0, 0, 0}, {2, 2, 0});
    expect_intersect(diagonal, segment({0, 2, 0}, {2, 0, 0}), true);         // crossing
    expect_intersect(diagonal, segment({0, 2, TINY}, {2, 0, TINY}), false);  // skew
    expect_intersect(diagonal, segment({0, 1, 0}, {2, 3, 0}), false);        // parallel
    expect_intersect(diagonal, segment({1, 1, 0}, {3, 3, 0}), true);         // collinear overlap
    expect_intersect(diagonal, segment({2, 2, 0}, {3, 3, 0}), true);         // end to end
    expect_intersect(diagonal, segment({2 + TINY, 2 + TINY, 0}, {3, 3, 0}), false);
    expect_intersect(diagonal, segment({2, 2, 0}, {2, 3, 5}), true);  // at an end
    expect_intersect(diagonal, point({0.5, 0.5, 0}), true);
    expect_intersect(diagonal, point({0.5, 0.5 + TINY, 0}), false);
    expect_intersect(point({1, 2, 3}), point({1, 2, 3}), true);
    expect_intersect(point({1, 2, 3}), point({1, 2, 3 + TINY}), false);
}

// Robust cases (margins far above rounding) stay the same under decimal scales 1e-6 and 1e6,
// which round the coordinates.
TEST(TriangleIntersection, DecimalScales) {
    const Tri crossing = {Vec3d{0.2, 0.2, -1}, Vec3d{0.3, 0.2, 1}, Vec3d{0.2, 0.3, 1}};
    const Tri near_miss = {Vec3d{0.25, 0.25, 1e-9}, Vec3d{0, 0, 1}, Vec3d{1, 0, 1}};
    for (const double scale : {1e-6, 1e6}) {
        const auto s = [&](const Tri& t) {
            return Tri{t[0] * scale, t[1] * scale, t[2] * scale};
        };
        expect_symmetric(s(P), s(crossing), true, "crossing");
        expect_symmetric(s(P), s(near_miss), false, "near miss");
    }
}

// Independent reference for non-degenerate triangles with small integer coordinates: the
// separating axis theorem with exact integer arithmetic. P - Q is a convex polytope whose facet
// normals are among n_P, n_Q, e_P × e_Q and, when it is flat, the in-plane normals n × e; the
// closed triangles are disjoint iff their projections onto one of these axes do not overlap.
using I3 = std::array<std::int64_t, 3>;

I3 isub(const I3& a, const I3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
I3 icross(const I3& a, const I3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
std::int64_t idot(const I3& a, const I3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

bool separating_axis_intersect(const std::array<I3, 3>& p, const std::array<I3, 3>& q) {
    std::vector<I3> axes;
    const std::array<I3, 3> ep = {isub(p[1], p[0]), isub(p[2], p[1]), isub(p[0], p[2])};
    const std::array<I3, 3> eq = {isub(q[1], q[0]), isub(q[2], q[1]), isub(q[0], q[2])};
    const I3 np = icross(ep[0], ep[1]);
    const I3 nq = icross(eq[0], eq[1]);
    axes.push_back(np);
    axes.push_back(nq);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            axes.push_back(icross(ep[i], eq[j]));
        }
        for (const I3& n : {np, nq}) {
            axes.push_back(icross(n, ep[i]));
            axes.push_back(icross(n, eq[i]));
        }
    }
    for (const I3& axis : axes) {
        if (axis == I3{0, 0, 0}) {
            continue;
        }
        const auto range = [&](const std::array<I3, 3>& t) {
            const std::int64_t a = idot(axis, t[0]);
            const std::int64_t b = idot(axis, t[1]);
            const std::int64_t c = idot(axis, t[2]);
            return std::pair{std::min({a, b, c}), std::max({a, b, c})};
        };
        const auto [p_lo, p_hi] = range(p);
        const auto [q_lo, q_hi] = range(q);
        if (p_hi < q_lo || q_hi < p_lo) {
            return false;
        }
    }
    return true;
}

TEST(TriangleIntersection, RandomIntegerTrianglesMatchSeparatingAxes) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> coordinate(-2, 2);
    const auto random_triangle = [&] {
        std::array<I3, 3> t;
        for (I3& v : t) {
            v = {coordinate(rng), coordinate(rng), coordinate(rng)};
        }
        return t;
    };
    const auto to_tri = [](const std::array<I3, 3>& t) {
        Tri out;
        for (int i = 0; i < 3; ++i) {
            out[static_cast<std::size_t>(i)] = {double(t[i][0]), double(t[i][1]), double(t[i][2])};
        }
        return out;
    };
    int num_true = 0;
    int num_false = 0;
    int num_coplanar = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const std::array<I3, 3> p = random_triangle();
        std::array<I3, 3> q = random_triangle();
        if (trial % 3 == 0) {  // force coplanar pairs: q in p's plane (p's affine combinations)
            const I3 e1 = isub(p[1], p[0]);
            const I3 e2 = isub(p[2], p[0]);
            for (I3& v : q) {
                const int a = coordinate(rng);
                const int b = coordinate(rng);
                v = {p[0][0] + a * e1[0] + b * e2[0], p[0][1] + a * e1[1] + b * e2[1],
                     p[0][2] + a * e1[2] + b * e2[2]};
            }
            ++num_coplanar;
        }
        if (icross(isub(p[1], p[0]), isub(p[2], p[0])) == I3{0, 0, 0} ||
            icross(isub(q[1], q[0]), isub(q[2], q[0])) == I3{0, 0, 0}) {
            continue;  // degenerate: covered by the analytic tests
        }
        const bool expected = separating_axis_intersect(p, q);
        (expected ? num_true : num_false) += 1;
        const Tri tp = to_tri(p);
        const Tri tq = to_tri(q);
        ASSERT_EQ(intersect(tp, tq), expected) << "trial " << trial;
        if (trial % 50 == 0) {
            expect_intersect(tp, tq, expected);
        }
    }
    EXPECT_GT(num_true, 1000);
    EXPECT_GT(num_false, 1000);
    EXPECT_GT(num_coplanar, 1000);
}

}  // namespace
}  // namespace pliant::geometry
