#include "pliant/cloth/ogc_contact.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <span>
#include <vector>

#include "cloth/ogc_moving_pins.hpp"
#include "cloth/solver_checks.hpp"
#include "pliant/cloth/detail/sym3.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

// Two triangles 4 mm apart: a vertex of the upper one above the lower one's interior.
struct TwoTriangles {
    std::vector<geometry::Triangle> triangles{{0, 1, 2}, {3, 4, 5}};
    std::vector<Vec3d> x{{0.0, 0.0, 0.0},     {0.1, 0.0, 0.0},   {0.0, 0.1, 0.0},
                         {0.02, 0.02, 0.004}, {0.2, 0.02, 0.05}, {0.02, 0.2, 0.05}};
};

// A 0.12 m sheet of 12 × 12 quads folded twice along x into three layers `gap` apart (z = 0,
// gap, 2 gap), every coordinate jittered uniformly by ± `jitter_m` drawn from `random`.
geometry::TriangleMeshD folded_sheet(std::mt19937& random, double jitter_m, double gap) {
    geometry::TriangleMeshD sheet = test::flat_sheet(12, 0.12, 0.0);
    std::uniform_real_distribution<double> jitter(-jitter_m, jitter_m);
    for (Vec3d& p : sheet.positions) {
        const double u = p.x / 0.04 + 1.5;
        const int layer = std::clamp(static_cast<int>(std::floor(u)), 0, 2);
        const double along = layer % 2 == 0 ? u - layer : layer + 1 - u;
        p = {along * 0.04 + jitter(random), p.y + jitter(random), gap * layer + jitter(random)};
    }
    return sheet;
}

TEST(OgcContact, TruncationKeepsAVertexOnItsSideOfThePlane) {
    TwoTriangles t;
    OgcContact contact(t.triangles, t.x.size(), OgcOptions{}, 0.005, 100.0);
    contact.detect(t.x);
    ASSERT_TRUE(contact.has_detection());
    EXPECT_GE(contact.num_pairs(), 1U);
    EXPECT_EQ(contact.close_pairs(), 1);  // vertex 3 to triangle 0
    // Pushed straight through the lower triangle: held above its plane, in its feasible set.
    Vec3d x = {0.02, 0.02, -0.004};
    EXPECT_TRUE(contact.truncate(3, t.x[3], x));
    EXPECT_GT(x.z, 0.0);
    EXPECT_TRUE(contact.feasible(3, x));
    // Sliding along the contact is not held back (planar truncation): the ball is 2.5 mm.
    Vec3d slide = {0.022, 0.021, 0.004};
    EXPECT_FALSE(contact.truncate(3, t.x[3], slide));
    // Random moves of every vertex, each truncated: the triangles never touch.
    std::mt19937 random(7);
    std::uniform_real_distribution<double> offset(-0.01, 0.01);
    for (int trial = 0; trial < 2000; ++trial) {
        std::vector<Vec3d> y = t.x;
        for (std::size_t v = 0; v < y.size(); ++v) {
            const Vec3d from = y[v];
            y[v] += Vec3d{offset(random), offset(random), offset(random)};
            contact.truncate(v, from, y[v]);
            ASSERT_TRUE(contact.feasible(v, y[v]));
        }
        const auto prox = collision::point_triangle_proximity(y[3], y[0], y[1], y[2]);
        ASSERT_GT(prox.distance, 0.0) << trial;
        ASSERT_EQ(collision::count_intersecting_pairs(y, t.triangles), 0) << trial;
    }
}

// The contact's force on each vertex of a vertex-face pair within the radius, with friction: the
// normal push k_c (r − d) w_v, and against the pair's tangential slip since the substep's start
// μ λ w_v (sliding) or μ λ w_v f₁(|u|)/|u| (sticking, below the slip ε); the forces on the four
// vertices sum to zero (the weights do), and the Hessian's tangential part is μ λ w_v² f₁/|u|.
TEST(OgcContact, FrictionOpposesTheSlipAndConservesMomentum) {
    TwoTriangles t;
    const double radius = 0.005;
    const double stiffness = 100.0;
    OgcContact contact(t.triangles, t.x.size(), OgcOptions{}, radius, stiffness);
    contact.detect(t.x);
    contact.snapshot(t.x);
    const double lambda = stiffness * (radius - 0.004);  // vertex 3 is 4 mm above triangle 0
    const double mu = 0.5;
    const double slip = 1e-4;
    const auto forces = [&](const Vec3d& slip_of_3, double friction) {
        std::vector<Vec3d> start = t.x;
        start[3] -= slip_of_3;  // vertex 3 moved by slip_of_3 since the start
        std::array<Vec3d, 4> f{};
        std::array<detail::Sym3, 4> h{};
        for (std::size_t v = 0; v < 4; ++v) {
            contact.add_forces(v, t.x[v], start, friction, slip, f[v], h[v]);
        }
        return std::pair{f, h};
    };
    // Without friction: the push alone, along +z, whatever the slip.
    const auto [f0, h0] = forces({0.01, 0.0, 0.0}, 0.0);
    EXPECT_NEAR(f0[3].x, 0.0, 1e-15);
    EXPECT_NEAR(f0[3].z, lambda, 1e-12);
    EXPECT_NEAR(h0[3].xx, 0.0, 1e-15);
    EXPECT_NEAR(h0[3].zz, stiffness, 1e-9);
    // Sliding 1 cm along +x: μ λ against it, on the vertex; the face's vertices are pulled along.
    const auto [f1, h1] = forces({0.01, 0.0, 0.0}, mu);
    EXPECT_NEAR(f1[3].x, -mu * lambda, 1e-12);
    EXPECT_NEAR(f1[3].y, 0.0, 1e-15);
    EXPECT_NEAR(f1[3].z, lambda, 1e-12);
    Vec3d sum{0.0, 0.0, 0.0};
    for (std::size_t v = 0; v < 3; ++v) {
        EXPECT_GE(f1[v].x, 0.0) << v;
        sum += f1[v];
    }
    sum += f1[3];
    EXPECT_NEAR(norm(sum), 0.0, 1e-12);
    EXPECT_NEAR(h1[3].xx, mu * lambda / 0.01, 1e-9);
    EXPECT_NEAR(h1[3].yy, mu * lambda / 0.01, 1e-9);
    EXPECT_NEAR(h1[3].zz, stiffness, 1e-9);
    // A slip along z (the normal) is no tangential slip (to rounding: the normal is computed).
    const auto [fz, hz] = forces({0.0, 0.0, 0.001}, mu);
    EXPECT_NEAR(fz[3].x, 0.0, 1e-12);
    EXPECT_NEAR(fz[3].z, lambda, 1e-12);
    // Sticking: a slip of ε/10 along −y gives μ λ (2y/ε − y²/ε²), along +y.
    const double y = slip / 10.0;
    const auto [f2, h2] = forces({0.0, -y, 0.0}, mu);
    EXPECT_NEAR(f2[3].y, mu * lambda * (2.0 * y / slip - y * y / (slip * slip)), 1e-12);
    EXPECT_NEAR(h2[3].yy, mu * lambda * (2.0 - y / slip) / slip, 1e-6);
}

// Detection against every non-incident VF and EE pair by brute force: a sheet folded into
// layers a few millimetres apart, its vertices jittered, finds exactly the pairs closer than the
// query radius, each once.
TEST(OgcContact, DetectsExactlyThePairsWithinTheQueryRadius) {
    std::mt19937 random(3);
    geometry::TriangleMeshD sheet = folded_sheet(random, 0.002, 0.004);
    const double radius = 0.003;
    OgcContact contact(sheet.triangles, sheet.positions.size(), OgcOptions{}, radius, 100.0);
    contact.detect(sheet.positions);
    using Key = std::array<std::int32_t, 5>;
    std::vector<Key> found;
    for (const OgcContact::Pair& pair : contact.pairs()) {
        found.push_back({pair.is_edge_edge ? 1 : 0, pair.v[0], pair.v[1], pair.v[2], pair.v[3]});
    }
    std::sort(found.begin(), found.end());
    EXPECT_EQ(std::adjacent_find(found.begin(), found.end()), found.end());

    const auto& x = sheet.positions;
    const double rq = contact.query_radius();
    std::vector<Key> expected;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(x.size()); ++v) {
        for (const geometry::Triangle& t : sheet.triangles) {
            if (t[0] != v && t[1] != v && t[2] != v &&
                collision::point_triangle_proximity(x[v], x[t[0]], x[t[1]], x[t[2]]).distance <
                    rq) {
                expected.push_back({0, v, t[0], t[1], t[2]});
            }
        }
    }
    const geometry::MeshTopology topology =
        geometry::build_topology(sheet.triangles, sheet.positions.size());
    for (std::size_t a = 0; a < topology.edges.size(); ++a) {
        for (std::size_t b = a + 1; b < topology.edges.size(); ++b) {
            const geometry::Edge& ea = topology.edges[a];
            const geometry::Edge& eb = topology.edges[b];
            if (ea[0] != eb[0] && ea[0] != eb[1] && ea[1] != eb[0] && ea[1] != eb[1] &&
                collision::segment_segment_proximity(x[ea[0]], x[ea[1]], x[eb[0]], x[eb[1]])
                        .distance < rq) {
                expected.push_back({1, ea[0], ea[1], eb[0], eb[1]});
            }
        }
    }
    std::sort(expected.begin(), expected.end());
    EXPECT_GT(expected.size(), 100U);
    EXPECT_EQ(found, expected);
}

// Truncation against the ball and every detected pair's plane, recomputed here from the pairs'
// closest points at the detection: equal to OgcContact's, which skips the planes its ball cannot
// reach. Layers 4 mm apart, jittered by 2 mm: pairs from 0 to 6 mm apart, their planes 0 to 2.7 mm
// from the vertices against a 1.5 mm ball.
TEST(OgcContact, TruncationMatchesTheBallAndEveryPlane) {
    std::mt19937 random(5);
    geometry::TriangleMeshD sheet = folded_sheet(random, 0.002, 0.004);
    const std::vector<Vec3d>& x = sheet.positions;
    OgcContact contact(sheet.triangles, x.size(), OgcOptions{}, 0.003, 100.0);
    contact.detect(x);
    const double ball = contact.ball_radius();
    // Every vertex's planes: {normal on its side, offset}.
    std::vector<std::vector<std::pair<Vec3d, double>>> planes(x.size());
    int beyond_ball = 0;
    for (const OgcContact::Pair& pair : contact.pairs()) {
        const std::array<Vec3d, 4> p = {x[pair.v[0]], x[pair.v[1]], x[pair.v[2]], x[pair.v[3]]};
        Vec3d first;
        Vec3d second;
        Vec3d normal;
        double distance = 0.0;
        if (pair.is_edge_edge) {
            const auto prox = collision::segment_segment_proximity(p[0], p[1], p[2], p[3]);
            first = p[0] + (p[1] - p[0]) * prox.s;
            second = p[2] + (p[3] - p[2]) * prox.t;
            normal = prox.normal;
            distance = prox.distance;
        } else {
            const auto prox = collision::point_triangle_proximity(p[0], p[1], p[2], p[3]);
            first = p[0];
            second = p[0] - prox.normal * prox.distance;
            normal = prox.normal;
            distance = prox.distance;
        }
        const Vec3d middle = (first + second) * 0.5;
        const double keep = OgcContact::PLANE_MARGIN * 0.5 * distance;
        for (int k = 0; k < 4; ++k) {
            const Vec3d side = k < (pair.is_edge_edge ? 2 : 1) ? normal : normal * -1.0;
            const double offset = dot(side, middle) + keep;
            planes[static_cast<std::size_t>(pair.v[k])].emplace_back(side, offset);
            beyond_ball += dot(side, p[static_cast<std::size_t>(k)]) - offset > ball ? 1 : 0;
        }
    }
    EXPECT_GT(beyond_ball, 100);
    std::uniform_real_distribution<double> move(-0.004, 0.004);
    int held_by_planes = 0;
    for (int trial = 0; trial < 20; ++trial) {
        for (std::size_t v = 0; v < x.size(); ++v) {
            const Vec3d target = x[v] + Vec3d{move(random), move(random), move(random)};
            // The farthest point of the segment from x_v inside the ball and every half-space.
            const Vec3d step = target - x[v];
            double t = norm(step) > ball ? ball / norm(step) : 1.0;
            double t_ball = t;
            for (const auto& [normal, offset] : planes[v]) {
                const double end = dot(normal, target) - offset;
                if (end < 0.0) {
                    const double begin = dot(normal, x[v]) - offset;
                    t = std::min(t, begin > 0.0 ? begin / (begin - end) : 0.0);
                }
            }
            held_by_planes += t < t_ball ? 1 : 0;
            Vec3d truncated = target;
            contact.truncate(v, x[v], truncated);
            const Vec3d expected = x[v] + step * t;
            ASSERT_LT(norm(truncated - expected), 1e-12) << v << " " << trial;
            ASSERT_TRUE(contact.feasible(v, truncated));
        }
    }
    EXPECT_GT(held_by_planes, 100);
}

// project() looks only at the pairs with a vertex past its slack (half its pairs' least margin
// d − r) and skips those whose relative motion cannot close their margin: the same pushes, bit
// for bit, as a projection that tests every detected pair, written out here without friction. A
// folded sheet at the larger query radius (2.5 r, ball 0.3 r_q = 2.25 mm), every vertex moved by up
// to 0 to 3 mm: some stay within their slack, some pass it, some pairs come closer than r.
TEST(OgcContact, ProjectionSkipsOnlyPairsThatCannotBeClose) {
    std::mt19937 random(11);
    geometry::TriangleMeshD sheet = folded_sheet(random, 0.001, 0.005);
    const std::vector<Vec3d>& x = sheet.positions;
    const double radius = 0.003;
    OgcOptions options;
    options.query_factor = 2.5;
    options.bound_share = 0.3;
    OgcContact contact(sheet.triangles, x.size(), options, radius, 100.0);
    contact.detect(x);
    ASSERT_GT(contact.num_pairs(), 100U);
    const std::vector<double> inverse_masses(x.size(), 1.0);
    // A pair's distance, normal and signed weights (first feature +, second −) at positions y.
    struct Geometry {
        double distance;
        Vec3d normal;
        std::array<double, 4> weights;
    };
    const auto geometry = [](const OgcContact::Pair& pair, const std::vector<Vec3d>& y) {
        const std::array<Vec3d, 4> p = {y[pair.v[0]], y[pair.v[1]], y[pair.v[2]], y[pair.v[3]]};
        if (pair.is_edge_edge) {
            const auto prox = collision::segment_segment_proximity(p[0], p[1], p[2], p[3]);
            return Geometry{
                prox.distance, prox.normal, {1.0 - prox.s, prox.s, -(1.0 - prox.t), -prox.t}};
        }
        const auto prox = collision::point_triangle_proximity(p[0], p[1], p[2], p[3]);
        return Geometry{prox.distance,
                        prox.normal,
                        {1.0, -prox.barycentric.x, -prox.barycentric.y, -prox.barycentric.z}};
    };
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_real_distribution<double> reach(0.0, 0.003);
    std::int64_t total_pushed = 0;
    for (int trial = 0; trial < 10; ++trial) {
        std::vector<Vec3d> y = x;
        for (Vec3d& p : y) {
            const Vec3d direction{unit(random), unit(random), unit(random)};
            p += direction * (reach(random) / std::max(norm(direction), 1e-3));
        }
        std::vector<Vec3d> expected = y;
        std::int64_t expected_pushed = 0;
        for (const OgcContact::Pair& pair : contact.pairs()) {
            Geometry g = geometry(pair, expected);
            const Vec3d detected = geometry(pair, x).normal;
            if (dot(g.normal, detected) < 0.0) {
                Vec3d gap{0.0, 0.0, 0.0};
                for (std::size_t j = 0; j < 4; ++j) {
                    gap += expected[pair.v[j]] * g.weights[j];
                }
                g.normal = detected;
                g.distance = dot(gap, detected);
            }
            if (!(g.distance < radius)) {
                continue;
            }
            double denominator = 0.0;
            for (std::size_t j = 0; j < 4; ++j) {
                denominator += inverse_masses[pair.v[j]] * g.weights[j] * g.weights[j];
            }
            const double lambda = (radius - g.distance) / denominator;
            for (std::size_t j = 0; j < 4; ++j) {
                expected[pair.v[j]] +=
                    g.normal * (inverse_masses[pair.v[j]] * g.weights[j] * lambda);
            }
            ++expected_pushed;
        }
        const std::int64_t pushed = contact.project(y, x, inverse_masses, 0.0, 0.0);
        EXPECT_EQ(pushed, expected_pushed) << trial;
        for (std::size_t v = 0; v < y.size(); ++v) {
            ASSERT_EQ(y[v].x, expected[v].x) << v << " " << trial;
            ASSERT_EQ(y[v].y, expected[v].y) << v << " " << trial;
            ASSERT_EQ(y[v].z, expected[v].z) << v << " " << trial;
        }
        total_pushed += pushed;
    }
    EXPECT_GT(total_pushed, 10);
}

TEST(OgcContact, ShiftMovesTheFeasibleSetsTogether) {
    TwoTriangles t;
    OgcContact contact(t.triangles, t.x.size(), OgcOptions{}, 0.005, 100.0);
    contact.detect(t.x);
    // Everything translated by 1 m: within the sets once the shift follows.
    std::vector<Vec3d> moved = t.x;
    for (Vec3d& p : moved) {
        p += Vec3d{0.0, 0.0, -1.0};
    }
    EXPECT_FALSE(contact.feasible(0, moved[0]));
    const std::vector<double> inverse_masses(t.x.size(), 1.0);
    contact.set_shift(moved, inverse_masses);
    for (std::size_t v = 0; v < moved.size(); ++v) {
        Vec3d p = moved[v];
        EXPECT_FALSE(contact.truncate(v, moved[v], p)) << v;
    }
}

// The wide radius (OgcOptions::wide_query_factor): a detection the truncations ask for within
// WIDE_TRIGGER_SUBSTEPS substeps of the previous one starts a hold of WIDE_HOLD_SUBSTEPS
// substeps of wide detections; other detections neither start nor end it.
TEST(OgcContact, WideRadiusFollowsShortDetectionIntervals) {
    TwoTriangles t;
    OgcOptions options;
    options.wide_query_factor = 2.5;
    const double r = 0.005;
    OgcContact contact(t.triangles, t.x.size(), options, r, 100.0);
    const auto expect_radii = [&](bool wide, int line) {
        SCOPED_TRACE(line);
        EXPECT_EQ(contact.wide(), wide);
        EXPECT_DOUBLE_EQ(contact.query_radius(), (wide ? 2.5 : 2.0) * r);
        // Pairs not detected keep (1 − 2 · 0.25) · 2 r = r apart either way.
        EXPECT_DOUBLE_EQ(contact.ball_radius(), (wide ? 0.75 : 0.5) * r);
    };
    contact.begin_substep();
    contact.detect(t.x);
    expect_radii(false, __LINE__);
    contact.begin_substep();
    contact.redetect(t.x);  // the first the truncations asked for: no interval yet
    expect_radii(false, __LINE__);
    for (int s = 0; s < 3; ++s) {
        contact.begin_substep();
    }
    contact.redetect(t.x);  // 3 substeps later
    expect_radii(false, __LINE__);
    contact.begin_substep();
    contact.begin_substep();
    contact.detect(t.x);  // a pin's detection: not an interval
    expect_radii(false, __LINE__);
    contact.redetect(t.x);  // 2 substeps after the last redetect()
    expect_radii(true, __LINE__);
    EXPECT_EQ(contact.wide_detections(), 1);
    for (std::int64_t s = 0; s + 1 < OgcContact::WIDE_HOLD_SUBSTEPS; ++s) {
        contact.begin_substep();
    }
    contact.detect(t.x);  // the hold's last substep
    expect_radii(true, __LINE__);
    contact.begin_substep();
    contact.detect(t.x);
    expect_radii(false, __LINE__);
    EXPECT_EQ(contact.wide_detections(), 2);
    options.wide_query_factor = 1.5;  // below query_factor
    EXPECT_THROW(OgcContact::check_options(options), InvalidInput);
    // VBD detects several times within a substep: the wide radius is XPBD's.
    options.wide_query_factor = 2.5;
    const ClothModel model(test::flat_sheet(2, 1.0, 0.0), ClothMaterial{});
    VBDOptions vbd;
    vbd.ogc = options;
    EXPECT_THROW(VBDStepper(model, vbd), InvalidInput);
}

// A wide detection's guarantee, by brute force: the pairs of a folded, jittered sheet that the
// detection left out (every non-incident VF and EE pair at least r_w apart), the nearest first,
// each pair's vertices pushed 1 cm straight toward each other along its closest points (the
// move that closes a pair fastest) and truncated: every such pair stays at least the contact
// radius r apart, and the nearest come within a few percent of r (the ball is as large as the
// guarantee allows: (r_w − (1 − 2 g) r_q) / 2).
TEST(OgcContact, WideBallsKeepUndetectedPairsApart) {
    std::mt19937 random(11);
    geometry::TriangleMeshD sheet = folded_sheet(random, 0.002, 0.006);
    const std::vector<Vec3d>& x = sheet.positions;
    const double radius = 0.003;
    OgcOptions options;
    options.wide_query_factor = 3.0;
    OgcContact contact(sheet.triangles, x.size(), options, radius, 100.0);
    contact.redetect(x);
    contact.begin_substep();
    contact.redetect(x);
    ASSERT_TRUE(contact.wide());
    const double r_w = contact.query_radius();
    // Undetected pairs: vertices (VF: the vertex first; EE: edge a's two first) and distance.
    struct Undetected {
        std::array<std::int32_t, 4> v;
        int num_first;
        double distance;
    };
    std::vector<Undetected> pairs;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(x.size()); ++v) {
        for (const geometry::Triangle& t : sheet.triangles) {
            if (t[0] != v && t[1] != v && t[2] != v) {
                const double d =
                    collision::point_triangle_proximity(x[v], x[t[0]], x[t[1]], x[t[2]]).distance;
                if (d >= r_w) {
                    pairs.push_back({{v, t[0], t[1], t[2]}, 1, d});
                }
            }
        }
    }
    const geometry::MeshTopology topology = geometry::build_topology(sheet.triangles, x.size());
    for (std::size_t a = 0; a < topology.edges.size(); ++a) {
        for (std::size_t b = a + 1; b < topology.edges.size(); ++b) {
            const geometry::Edge& ea = topology.edges[a];
            const geometry::Edge& eb = topology.edges[b];
            if (ea[0] != eb[0] && ea[0] != eb[1] && ea[1] != eb[0] && ea[1] != eb[1]) {
                const double d =
                    collision::segment_segment_proximity(x[ea[0]], x[ea[1]], x[eb[0]], x[eb[1]])
                        .distance;
                if (d >= r_w) {
                    pairs.push_back({{ea[0], ea[1], eb[0], eb[1]}, 2, d});
                }
            }
        }
    }
    std::sort(pairs.begin(), pairs.end(),
              [](const Undetected& a, const Undetected& b) { return a.distance < b.distance; });
    ASSERT_GT(pairs.size(), 200U);
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < 200; ++i) {
        const Undetected& pair = pairs[i];
        std::array<Vec3d, 4> p;
        for (std::size_t k = 0; k < 4; ++k) {
            p[k] = x[static_cast<std::size_t>(pair.v[k])];
        }
        // The closest points' direction, from the second feature toward the first.
        Vec3d n;
        if (pair.num_first == 1) {
            const auto prox = collision::point_triangle_proximity(p[0], p[1], p[2], p[3]);
            n = prox.normal;
        } else {
            const auto prox = collision::segment_segment_proximity(p[0], p[1], p[2], p[3]);
            n = prox.normal;
        }
        for (int k = 0; k < 4; ++k) {
            const auto v = static_cast<std::size_t>(pair.v[static_cast<std::size_t>(k)]);
            Vec3d& q = p[static_cast<std::size_t>(k)];
            q += n * (k < pair.num_first ? -0.01 : 0.01);
            contact.truncate(v, x[v], q);
        }
        const double d =
            pair.num_first == 1
                ? collision::point_triangle_proximity(p[0], p[1], p[2], p[3]).distance
                : collision::segment_segment_proximity(p[0], p[1], p[2], p[3]).distance;
        least = std::min(least, d);
    }
    EXPECT_GE(least, radius * (1.0 - 1e-9));
    EXPECT_LT(least, radius * 1.05);
}

// The wide radius's state (the current detection's radius, the hold, the substeps since the
// last redetect()) survives save_state / load_state: a loaded contact detects as the original.
TEST(OgcContact, WideStateSurvivesSaveAndLoad) {
    TwoTriangles t;
    OgcOptions options;
    options.wide_query_factor = 2.5;
    // In a hold: a redetect() 1 substep after the previous one, then 1 substep.
    const auto original = [&] {
        auto c = std::make_unique<OgcContact>(t.triangles, t.x.size(), options, 0.005, 100.0);
        c->redetect(t.x);
        c->begin_substep();
        c->redetect(t.x);
        c->begin_substep();
        return c;
    };
    ByteWriter out;
    original()->save_state(out);
    const auto loaded = [&] {
        auto c = std::make_unique<OgcContact>(t.triangles, t.x.size(), options, 0.005, 100.0);
        ByteReader in(out.bytes(), "state");
        c->load_state(in);
        return c;
    };
    for (const bool load : {false, true}) {
        SCOPED_TRACE(load ? "loaded" : "original");
        std::unique_ptr<OgcContact> c = load ? loaded() : original();
        EXPECT_TRUE(c->wide());
        EXPECT_DOUBLE_EQ(c->query_radius(), 2.5 * 0.005);
        EXPECT_EQ(c->wide_detections(), 1);
        // The hold goes on: 3 substeps later a detection is still wide.
        for (int s = 0; s < 3; ++s) {
            c->begin_substep();
        }
        c->detect(t.x);
        EXPECT_TRUE(c->wide());
        // 2 substeps after the last redetect(): a new hold, whose last substep detects wide.
        c = load ? loaded() : original();
        c->begin_substep();
        c->redetect(t.x);
        for (std::int64_t s = 0; s + 1 < OgcContact::WIDE_HOLD_SUBSTEPS; ++s) {
            c->begin_substep();
        }
        c->detect(t.x);
        EXPECT_TRUE(c->wide());
        c->begin_substep();
        c->detect(t.x);
        EXPECT_FALSE(c->wide());
        EXPECT_EQ(c->wide_detections(), 3);
    }
    // A truncated state.
    std::vector<std::byte> bytes(out.bytes().begin(), out.bytes().end());
    bytes.resize(bytes.size() - 4);
    ByteReader truncated(bytes, "state");
    OgcContact c(t.triangles, t.x.size(), options, 0.005, 100.0);
    EXPECT_THROW(c.load_state(truncated), InvalidInput);
}

TEST(OgcContact, RejectsBadOptions) {
    TwoTriangles t;
    EXPECT_THROW(OgcContact(t.triangles, 6, OgcOptions{}, 0.0, 1.0), InvalidInput);
    EXPECT_THROW(OgcContact(t.triangles, 6, OgcOptions{}, 0.005, 0.0), InvalidInput);
    for (const auto& change : std::vector<void (*)(OgcOptions&)>{
             [](OgcOptions& o) { o.bound_share = 0.5; }, [](OgcOptions& o) { o.bound_share = 0.0; },
             [](OgcOptions& o) { o.query_factor = 0.9; },
             [](OgcOptions& o) { o.redetect_share = 1.5; }, [](OgcOptions& o) { o.radius = -1.0; },
             [](OgcOptions& o) {
                 o.stiffness = std::numeric_limits<double>::infinity();
             }}) {
        OgcOptions options;
        change(options);
        EXPECT_THROW(OgcContact::check_options(options), InvalidInput);
        const ClothModel model(test::flat_sheet(2, 1.0, 0.0), ClothMaterial{});
        VBDOptions vbd;
        vbd.ogc = options;
        EXPECT_THROW(VBDStepper(model, vbd), InvalidInput);
    }
}

VBDOptions ogc_options() {
    VBDOptions options;
    options.ogc = OgcOptions{};
    return options;
}

// colliding_sheets() with VBD and OGC contact.
std::unique_ptr<ClothSolver> colliding_sheets(int n) {
    auto solver = test::colliding_sheets(n);
    solver->use_vbd(ogc_options());
    return solver;
}

TEST(OgcContact, SheetsPushedTogetherNeverIntersect) {
    auto solver = colliding_sheets(16);
    ASSERT_NE(solver->vbd()->ogc(), nullptr);
    for (int f = 0; f < 12; ++f) {
        const ClothStepStats stats = solver->step(1.0 / 24.0, 8);
        ASSERT_TRUE(stats.has_ogc);
        // The bounds alone kept them apart: the CCD audit put nothing back.
        EXPECT_EQ(stats.self.reverted_vertices, 0) << "frame " << f;
    }
    // The upper one rests on the lower one (z = 5 mm), at the contact radius (5 mm) to within
    // half a millimetre.
    const std::span<const Vec3d> x = solver->positions();
    double lowest = std::numeric_limits<double>::infinity();
    for (std::size_t v = x.size() / 2; v < x.size(); ++v) {
        lowest = std::min(lowest, x[v].z);
    }
    EXPECT_GT(lowest, 0.005);
    EXPECT_LT(lowest, 0.0105);
}

TEST(OgcContact, SettledSheetDetectsLessThanOncePerSubstep) {
    ClothSolver solver(test::flat_sheet(16, 1.0, 0.02), ClothMaterial{});
    solver.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    solver.enable_self_collision(true);
    solver.use_vbd(ogc_options());
    const int substeps = 8;
    std::int64_t early = 0;
    std::int64_t late = 0;
    for (int f = 0; f < 48; ++f) {
        const ClothStepStats stats = solver.step(1.0 / 24.0, substeps);
        (f < 24 ? early : late) += stats.ogc_detections;
    }
    // Resting on the plane for the last 24 frames: far fewer detections than substeps.
    EXPECT_LT(late, 24 * substeps / 8);
    EXPECT_GE(early, 1);
}

// Pins that move the cloth faster than the ball lets a free vertex move in a substep, beside
// too few neighbours for the share rule: the sheet stays as little stretched as VBD's proximity
// path keeps it, and free of intersections.
TEST(OgcContact, FollowsPinsFasterThanItsBall) {
    auto proximity = test::sheet_on_turning_pins([](ClothSolver& s) { s.use_vbd(VBDOptions{}); });
    const test::MovingPinsRun reference = test::run_moving_pins(*proximity, 24, 16);
    auto solver = test::sheet_on_turning_pins([](ClothSolver& s) {
        VBDOptions options;
        options.ogc = test::small_ball_ogc();
        s.use_vbd(options);
    });
    ASSERT_NE(solver->vbd()->ogc(), nullptr);
    const test::MovingPinsRun run = test::run_moving_pins(*solver, 24, 16);
    test::expect_follows_pins(reference, run, 24);
}

TEST(OgcContact, MovingPinsBitwiseIdenticalForOneAndTwoThreads) {
    const auto make = [] {
        return test::sheet_on_turning_pins([](ClothSolver& s) {
            VBDOptions options;
            options.ogc = test::small_ball_ogc();
            s.use_vbd(options);
        });
    };
    EXPECT_EQ(test::positions_after_8_frames(make, 1, 8),
              test::positions_after_8_frames(make, 2, 8));
}

TEST(OgcContact, BitwiseIdenticalForOneAndTwoThreads) {
    const auto make = [] {
        return colliding_sheets(12);
    };
    EXPECT_EQ(test::positions_after_8_frames(make, 1, 6),
              test::positions_after_8_frames(make, 2, 6));
}

TEST(OgcContact, SavedStateContinuesBitForBit) {
    test::expect_saved_state_continues_bit_for_bit([] { return colliding_sheets(10); }, 4, 6);
}

// Two identical sheets of n × n quads, `size` wide, the upper one `gap` straight above the lower
// one: every upper vertex over a lower vertex, every upper edge over a lower edge.
geometry::TriangleMeshD stacked_sheets(int n, double size, double gap) {
    geometry::TriangleMeshD mesh = test::flat_sheet(n, size, 0.0);
    const geometry::TriangleMeshD upper = test::flat_sheet(n, size, gap);
    const auto offset = static_cast<std::int32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), upper.positions.begin(), upper.positions.end());
    for (const geometry::Triangle& t : upper.triangles) {
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    return mesh;
}

// A vertex straight over a vertex is one contact, though 6 vertex-face pairs each way and 36
// edge-edge pairs see it at the same distance: the energy counts it once, so the push on an
// inner upper vertex is k_c (r − d), and on its lower partner the same, downward.
TEST(OgcContact, AContactSeenByManyPairsCountsOnce) {
    const double radius = 0.005;
    const double stiffness = 100.0;
    const double gap = 0.004;
    const geometry::TriangleMeshD mesh = stacked_sheets(4, 0.04, gap);
    OgcContact contact(mesh.triangles, mesh.positions.size(), OgcOptions{}, radius, stiffness);
    contact.detect(mesh.positions);
    contact.snapshot(mesh.positions);
    EXPECT_GT(contact.close_pairs(), 48);
    const std::size_t lower = 12;  // an inner vertex of the 5 × 5 grid (row 2, column 2)
    const std::size_t upper = lower + 25;
    ASSERT_NEAR(mesh.positions[upper].x, mesh.positions[lower].x, 1e-12);
    ASSERT_NEAR(mesh.positions[upper].y, mesh.positions[lower].y, 1e-12);
    for (const auto& [v, sign] : {std::pair{upper, 1.0}, std::pair{lower, -1.0}}) {
        Vec3d force{0.0, 0.0, 0.0};
        detail::Sym3 hessian;
        contact.add_forces(v, mesh.positions[v], mesh.positions, 0.0, 1.0, force, hessian);
        EXPECT_NEAR(force.z, sign * stiffness * (radius - gap), 1e-12) << v;
        EXPECT_NEAR(force.x, 0.0, 1e-12) << v;
        EXPECT_NEAR(force.y, 0.0, 1e-12) << v;
        EXPECT_NEAR(hessian.zz, stiffness, 1e-9) << v;
    }
}

// Stacked 0.2 m sheets of 8 × 8 quads 5.5 mm apart, the lower one pinned, under gravity tilted
// 8° (friction holds the upper one: tan 8° < 0.2), with VBD: the upper one settles onto it and
// lies flat. When every pair counted its contact, the upper sheet was thrown up (to 1.7 cm within
// 2 frames; scenes/stress/resting_sheet_vbd_ogc.json stacked so, 16 × 16 quads: 3.4 cm).
TEST(OgcContact, StackedSheetsSettleFlat) {
    const geometry::TriangleMeshD mesh = stacked_sheets(8, 0.2, 0.0055);
    const std::size_t per_sheet = mesh.positions.size() / 2;
    std::vector<std::int32_t> pinned(per_sheet);
    std::iota(pinned.begin(), pinned.end(), 0);  // the lower sheet
    ClothSolver solver(mesh, ClothMaterial{}, pinned);
    solver.set_gravity({0.0, -1.3653, -9.7145});
    solver.enable_self_collision(true);
    solver.use_vbd(ogc_options());
    for (int f = 0; f < 2; ++f) {
        solver.step(1.0 / 24.0, 40);
    }
    const std::span<const Vec3d> x = solver.positions();
    for (std::size_t v = per_sheet; v < x.size(); ++v) {
        EXPECT_GT(x[v].z, 0.0049) << v;
        EXPECT_LT(x[v].z, 0.0055) << v;
    }
}

}  // namespace
}  // namespace pliant::cloth
