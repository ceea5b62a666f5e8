#include "pliant/collision/segment_segment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <random>
#include <string>
#include <type_traits>

#include "support/proximity_reference.hpp"

namespace pliant::collision {
namespace {

using test::distance_tolerance;
using test::extent_of;
using test::Long;
using test::RealNames;
using test::RealTypes;
using test::reference_point_segment_distance;
using test::SampledDistance;
using test::to_long;
using test::vec;
using test::Vec3L;

// Independent reference in long double. |P(s) - Q(t)|² is convex on [0, 1]²: its minimum is the
// interior critical point (Cramer's rule) when that lies in the square, else on one of the four
// sides, each an endpoint against the other segment.
Long reference_segment_segment_distance(Vec3L p0, Vec3L p1, Vec3L q0, Vec3L q1) {
    Long best = std::min({reference_point_segment_distance(p0, q0, q1),
                          reference_point_segment_distance(p1, q0, q1),
                          reference_point_segment_distance(q0, p0, p1),
                          reference_point_segment_distance(q1, p0, p1)});
    const Vec3L d1 = p1 - p0;
    const Vec3L d2 = q1 - q0;
    const Vec3L r = p0 - q0;
    const Long a = dot(d1, d1);
    const Long b = dot(d1, d2);
    const Long e = dot(d2, d2);
    const Long c = dot(d1, r);
    const Long f = dot(d2, r);
    const Long determinant = a * e - b * b;
    if (determinant > 0) {
        const Long s = (b * f - c * e) / determinant;
        const Long t = (a * f - b * c) / determinant;
        if (s >= 0 && s <= 1 && t >= 0 && t <= 1) {
            best = std::min(best, norm((p0 + d1 * s) - (q0 + d2 * t)));
        }
    }
    return best;
}

// Dense sampling: s on a grid of n + 1 values with the exact closest point of Q for each, and the
// same with the roles swapped. A grid spacing of 1 / n leaves every parameter within 1 / (2n) of a
// sample, so the sampled minimum exceeds the true one by at most the longer length / (2n).
SampledDistance sampled_segment_segment_distance(Vec3L p0, Vec3L p1, Vec3L q0, Vec3L q1, int n) {
    Long min_distance = std::numeric_limits<Long>::infinity();
    for (int i = 0; i <= n; ++i) {
        const Long parameter = Long(i) / n;
        min_distance = std::min(
            {min_distance, reference_point_segment_distance(p0 + (p1 - p0) * parameter, q0, q1),
             reference_point_segment_distance(q0 + (q1 - q0) * parameter, p0, p1)});
    }
    return {min_distance, std::max(norm(p1 - p0), norm(q1 - q0)) / (2 * n)};
}

// Every invariant of the contract, and the distance against the exact reference.
template <typename Real>
void expect_valid(const SegmentSegmentProximity<Real>& prox, Vec3<Real> p0, Vec3<Real> p1,
                  Vec3<Real> q0, Vec3<Real> q1) {
    const Long eps = std::numeric_limits<Real>::epsilon();
    const Long tolerance = distance_tolerance<Real>(extent_of<Real>({p0, p1, q0, q1}));

    ASSERT_TRUE(std::isfinite(prox.distance));
    EXPECT_GE(prox.distance, Real(0));
    EXPECT_NEAR(
        prox.distance,
        reference_segment_segment_distance(to_long(p0), to_long(p1), to_long(q0), to_long(q1)),
        tolerance);
    EXPECT_GE(prox.s, Real(0));
    EXPECT_LE(prox.s, Real(1));
    EXPECT_GE(prox.t, Real(0));
    EXPECT_LE(prox.t, Real(1));

    const Vec3L closest_on_p = to_long(p0) + (to_long(p1) - to_long(p0)) * Long(prox.s);
    const Vec3L closest_on_q = to_long(q0) + (to_long(q1) - to_long(q0)) * Long(prox.t);
    EXPECT_NEAR(norm(closest_on_p - closest_on_q), prox.distance, tolerance)
        << "closest points reproduce the distance";

    EXPECT_NEAR(norm(to_long(prox.normal)), 1, 8 * eps);
    // From Q(t) towards P(s): dot = distance (the direction's rounding only matters when the
    // distance itself is within the tolerance).
    EXPECT_NEAR(dot(to_long(prox.normal), closest_on_p - closest_on_q), prox.distance,
                3 * tolerance);
}

template <typename Real>
void expect_matches_sampling(const SegmentSegmentProximity<Real>& prox, Vec3<Real> p0,
                             Vec3<Real> p1, Vec3<Real> q0, Vec3<Real> q1) {
    const SampledDistance sampled =
        sampled_segment_segment_distance(to_long(p0), to_long(p1), to_long(q0), to_long(q1), 512);
    const Long tolerance = distance_tolerance<Real>(extent_of<Real>({p0, p1, q0, q1}));
    EXPECT_LE(prox.distance, sampled.min_distance + tolerance);
    EXPECT_GE(prox.distance, sampled.min_distance - sampled.resolution - tolerance);
}

template <typename Real>
class SegmentSegmentTest : public ::testing::Test {};

TYPED_TEST_SUITE(SegmentSegmentTest, RealTypes, RealNames);

struct ExpectedProximity {
    double distance;
    double s;
    double t;
    Vec3<double> normal;
};

template <typename Real>
void expect_proximity(Vec3<Real> p0, Vec3<Real> p1, Vec3<Real> q0, Vec3<Real> q1,
                      const ExpectedProximity& expected) {
    const auto prox = segment_segment_proximity(p0, p1, q0, q1);
    const double eps = 8 * std::numeric_limits<Real>::epsilon();
    EXPECT_NEAR(prox.distance, expected.distance, eps);
    EXPECT_NEAR(prox.s, expected.s, eps);
    EXPECT_NEAR(prox.t, expected.t, eps);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(prox.normal[i], expected.normal[i], eps) << "normal component " << i;
    }
    expect_valid(prox, p0, p1, q0, q1);
}

TYPED_TEST(SegmentSegmentTest, AnalyticCases) {
    using Real = TypeParam;
    const double r2 = std::sqrt(0.5);
    {
        SCOPED_TRACE("skew, interior closest points");
        expect_proximity(vec<Real>(-1, 0, 1), vec<Real>(1, 0, 1), vec<Real>(0.5, -1, 0),
                         vec<Real>(0.5, 3, 0), {1, 0.75, 0.25, {0, 0, 1}});
    }
    {
        SCOPED_TRACE("skew, both clamped to endpoints");
        expect_proximity(vec<Real>(2, 0, 0), vec<Real>(3, 0, 0), vec<Real>(0, 1, 0),
                         vec<Real>(0, 2, 0),
                         {std::sqrt(5.0), 0, 0, vec<double>(2, -1, 0) * (1 / std::sqrt(5.0))});
    }
    {
        SCOPED_TRACE("T junction: an endpoint of q on the interior of p");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(2, 0, 0), vec<Real>(0.5, 0, 0),
                         vec<Real>(0.5, 0, 1), {0, 0.25, 0, {0, -1, 0}});
    }
    {
        SCOPED_TRACE("crossing at distance 0: normal perpendicular to both");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 1, 0), vec<Real>(1, 0, 0),
                         vec<Real>(0, 1, 0), {0, 0.5, 0.5, {0, 0, 1}});
    }
    {
        SCOPED_TRACE("parallel, overlapping");
        const auto prox = segment_segment_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 0, 0),
                                                    vec<Real>(0.5, 1, 0), vec<Real>(2, 1, 0));
        EXPECT_NEAR(prox.distance, Real(1), 4 * std::numeric_limits<Real>::epsilon());
        EXPECT_GE(prox.s, Real(0.5));
        EXPECT_NEAR(prox.normal.y, Real(-1), 4 * std::numeric_limits<Real>::epsilon());
        expect_valid(prox, vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(0.5, 1, 0),
                     vec<Real>(2, 1, 0));
    }
    {
        SCOPED_TRACE("parallel, disjoint: endpoint to endpoint");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(2, 1, 0),
                         vec<Real>(3, 1, 0), {std::sqrt(2.0), 1, 0, {-r2, -r2, 0}});
    }
    {
        SCOPED_TRACE("antiparallel, disjoint");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(3, 1, 0),
                         vec<Real>(2, 1, 0), {std::sqrt(2.0), 1, 1, {-r2, -r2, 0}});
    }
    {
        SCOPED_TRACE("collinear, disjoint");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(2, 0, 0),
                         vec<Real>(3, 0, 0), {1, 1, 0, {-1, 0, 0}});
    }
    {
        SCOPED_TRACE("collinear, touching at one endpoint");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(1, 0, 0),
                         vec<Real>(3, 0, 0), {0, 1, 0, {0, 0, 1}});
    }
    {
        SCOPED_TRACE("p a zero-length segment");
        expect_proximity(vec<Real>(1, 1, 0), vec<Real>(1, 1, 0), vec<Real>(0, 0, 0),
                         vec<Real>(4, 0, 0), {1, 0, 0.25, {0, 1, 0}});
    }
    {
        SCOPED_TRACE("q a zero-length segment beyond p's end");
        expect_proximity(vec<Real>(0, 0, 0), vec<Real>(0, 0, 2), vec<Real>(0, 0, 5),
                         vec<Real>(0, 0, 5), {3, 1, 0, {0, 0, -1}});
    }
    {
        SCOPED_TRACE("two points");
        expect_proximity(vec<Real>(0, 3, 0), vec<Real>(0, 3, 0), vec<Real>(0, 0, -4),
                         vec<Real>(0, 0, -4), {5, 0, 0, {0, 0.6, 0.8}});
    }
    {
        SCOPED_TRACE("two coincident points");
        expect_proximity(vec<Real>(1, 2, 3), vec<Real>(1, 2, 3), vec<Real>(1, 2, 3),
                         vec<Real>(1, 2, 3), {0, 0, 0, {0, 0, 1}});
    }
}

// Collinear overlapping and coincident segments: distance 0 at matching points, and a unit normal
// perpendicular to the common direction.
TYPED_TEST(SegmentSegmentTest, CollinearOverlappingAndCoincident) {
    using Real = TypeParam;
    const Real eps = 8 * std::numeric_limits<Real>::epsilon();
    const auto p0 = vec<Real>(1, 1, 1);
    const auto p1 = vec<Real>(3, 2, 0);
    const Vec3<Real> direction = p1 - p0;
    struct Case {
        const char* name;
        Vec3<Real> q0, q1;
    };
    const Case cases[] = {
        {"identical", p0, p1},
        {"reversed", p1, p0},
        {"q inside p", p0 + direction * Real(0.25), p0 + direction * Real(0.5)},
        {"p inside q", p0 - direction, p1 + direction},
        {"partial overlap", p0 + direction * Real(0.5), p0 + direction * Real(2)},
        {"partial overlap, reversed", p0 + direction * Real(2), p0 - direction * Real(-0.5)},
    };
    for (const Case& overlap : cases) {
        SCOPED_TRACE(overlap.name);
        const auto prox = segment_segment_proximity(p0, p1, overlap.q0, overlap.q1);
        EXPECT_NEAR(prox.distance, Real(0), eps * 4);
        EXPECT_NEAR(dot(prox.normal, direction) / norm(direction), Real(0), eps);
        expect_valid(prox, p0, p1, overlap.q0, overlap.q1);
    }
}

template <typename Real>
Vec3<Real> random_point(std::mt19937& rng, double half_width) {
    std::uniform_real_distribution<double> coordinate(-half_width, half_width);
    return vec<Real>(coordinate(rng), coordinate(rng), coordinate(rng));
}

// Random configurations of every kind, times scale: general position, nearly parallel (angles
// 1e-2 … 1e-9), exactly parallel, collinear, crossing (q through a point of p) and zero-length.
template <typename Real>
void check_random_queries(unsigned seed, int num_queries, double scale) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int query = 0; query < num_queries; ++query) {
        const Vec3<double> p0 = random_point<double>(rng, 1);
        const Vec3<double> p1 = random_point<double>(rng, 1);
        Vec3<double> q0 = random_point<double>(rng, 1);
        Vec3<double> q1 = random_point<double>(rng, 1);
        const Vec3<double> direction = p1 - p0;
        const int kind = query % 6;
        if (kind == 1) {
            const double angle = std::pow(10.0, -2 - 7 * unit(rng));
            q1 = q0 + (direction + random_point<double>(rng, 1) * (angle * norm(direction))) *
                          (2 * unit(rng) - 1);
        } else if (kind == 2) {
            q1 = q0 + direction * (2 * unit(rng) - 1);
        } else if (kind == 3) {
            q0 = p0 + direction * (3 * unit(rng) - 1);
            q1 = p0 + direction * (3 * unit(rng) - 1);
        } else if (kind == 4) {
            const Vec3<double> on_p = p0 + direction * unit(rng);
            q1 = on_p + (on_p - q0) * unit(rng);
        } else if (kind == 5) {
            q1 = q0;
        }
        const auto scaled = [scale](Vec3<double> point) {
            return vec3_cast<Real>(point * scale);
        };
        const Vec3<Real> a0 = scaled(p0);
        const Vec3<Real> a1 = scaled(p1);
        const Vec3<Real> b0 = scaled(q0);
        const Vec3<Real> b1 = scaled(q1);
        SCOPED_TRACE("query " + std::to_string(query) + " kind " + std::to_string(kind));
        const auto prox = segment_segment_proximity(a0, a1, b0, b1);
        expect_valid(prox, a0, a1, b0, b1);
        expect_matches_sampling(prox, a0, a1, b0, b1);
        // Symmetry: swapping the segments swaps s and t and flips the normal's direction.
        const auto swapped = segment_segment_proximity(b0, b1, a0, a1);
        EXPECT_NEAR(swapped.distance, prox.distance,
                    distance_tolerance<Real>(extent_of<Real>({a0, a1, b0, b1})));
    }
}

TYPED_TEST(SegmentSegmentTest, RandomQueriesMatchReferenceAndDenseSampling) {
    check_random_queries<TypeParam>(17, 600, 1.0);
}

TYPED_TEST(SegmentSegmentTest, ScaleInvariance) {
    for (const double scale : {1e-6, 1e6}) {
        SCOPED_TRACE("scale " + std::to_string(scale));
        check_random_queries<TypeParam>(23, 120, scale);
    }
}

// Segments far apart relative to their length keep the distance's relative accuracy.
TYPED_TEST(SegmentSegmentTest, FarApart) {
    using Real = TypeParam;
    std::mt19937 rng(29);
    for (int query = 0; query < 50; ++query) {
        const Vec3<Real> offset = random_point<Real>(rng, 1e3);
        const Vec3<Real> p0 = random_point<Real>(rng, 1);
        const Vec3<Real> p1 = random_point<Real>(rng, 1);
        const Vec3<Real> q0 = random_point<Real>(rng, 1) + offset;
        const Vec3<Real> q1 = random_point<Real>(rng, 1) + offset;
        expect_valid(segment_segment_proximity(p0, p1, q0, q1), p0, p1, q0, q1);
    }
}

}  // namespace
}  // namespace pliant::collision
