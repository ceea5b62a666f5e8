#include "pliant/collision/point_triangle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

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
using Region = PointTriangleRegion;

// Independent reference in long double: the projection onto the plane if it lies inside the
// triangle (signed-area barycentrics), else the closest of the three edges as segments.
Long reference_point_triangle_distance(Vec3L p, Vec3L a, Vec3L b, Vec3L c) {
    const Vec3L normal = cross(b - a, c - a);
    const Long squared_area = squared_norm(normal);
    if (squared_area > 0) {
        const Long weight_a = dot(normal, cross(b - p, c - p)) / squared_area;
        const Long weight_b = dot(normal, cross(c - p, a - p)) / squared_area;
        const Long weight_c = dot(normal, cross(a - p, b - p)) / squared_area;
        if (weight_a >= 0 && weight_b >= 0 && weight_c >= 0) {
            return std::fabs(dot(p - a, normal)) / std::sqrt(squared_area);
        }
    }
    return std::min({reference_point_segment_distance(p, a, b),
                     reference_point_segment_distance(p, b, c),
                     reference_point_segment_distance(p, c, a)});
}

// Dense sampling: the minimum distance to the barycentric grid points (i, j, k) / n, i + j + k = n.
// Every point of the triangle lies within the longest edge / n of a grid point (it lies in a
// sub-triangle whose edges are the triangle's edges / n), which bounds the sampling error.
SampledDistance sampled_point_triangle_distance(Vec3L p, Vec3L a, Vec3L b, Vec3L c, int n) {
    Long min_distance = std::numeric_limits<Long>::infinity();
    for (int i = 0; i <= n; ++i) {
        for (int j = 0; i + j <= n; ++j) {
            const Long wa = Long(i) / n;
            const Long wb = Long(j) / n;
            const Long wc = Long(n - i - j) / n;
            min_distance = std::min(min_distance, norm(p - (a * wa + b * wb + c * wc)));
        }
    }
    const Long longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    return {min_distance, longest / n};
}

// Every invariant of the contract, and the distance against the exact reference.
template <typename Real>
void expect_valid(const PointTriangleProximity<Real>& prox, Vec3<Real> p, Vec3<Real> a,
                  Vec3<Real> b, Vec3<Real> c) {
    const Long eps = std::numeric_limits<Real>::epsilon();
    const Long tolerance = distance_tolerance<Real>(extent_of<Real>({p, a, b, c}));
    const Vec3L pl = to_long(p);
    const Vec3L w = to_long(prox.barycentric);

    ASSERT_TRUE(std::isfinite(prox.distance));
    EXPECT_GE(prox.distance, Real(0));
    EXPECT_NEAR(prox.distance,
                reference_point_triangle_distance(pl, to_long(a), to_long(b), to_long(c)),
                tolerance);

    for (int i = 0; i < 3; ++i) {
        EXPECT_GE(w[i], 0) << "weight " << i;
        EXPECT_LE(w[i], 1) << "weight " << i;
    }
    EXPECT_NEAR(w.x + w.y + w.z, 1, 4 * eps);

    const Vec3L closest = to_long(a) * w.x + to_long(b) * w.y + to_long(c) * w.z;
    EXPECT_NEAR(norm(pl - closest), prox.distance, tolerance)
        << "closest point reproduces distance";

    EXPECT_NEAR(norm(to_long(prox.normal)), 1, 8 * eps);
    // Points from the closest point towards p: dot = distance (up to the direction's rounding,
    // which only matters when the distance itself is within the tolerance).
    EXPECT_NEAR(dot(to_long(prox.normal), pl - closest), prox.distance, 3 * tolerance);

    ASSERT_GE(prox.region, Region::FACE);
    ASSERT_LE(prox.region, Region::EDGE_CA);
    if (prox.region >= Region::VERTEX_A && prox.region <= Region::VERTEX_C) {
        EXPECT_EQ(w[prox.region - Region::VERTEX_A], 1) << "vertex region " << prox.region;
    } else if (prox.region >= Region::EDGE_AB) {
        // Edge ab has weight 0 on c, bc on a, ca on b.
        const int opposite_corner = (prox.region - Region::EDGE_AB + 2) % 3;
        EXPECT_EQ(w[opposite_corner], 0) << "edge region " << prox.region;
    }
}

template <typename Real>
void expect_matches_sampling(const PointTriangleProximity<Real>& prox, Vec3<Real> p, Vec3<Real> a,
                             Vec3<Real> b, Vec3<Real> c, int grid) {
    const SampledDistance sampled =
        sampled_point_triangle_distance(to_long(p), to_long(a), to_long(b), to_long(c), grid);
    const Long tolerance = distance_tolerance<Real>(extent_of<Real>({p, a, b, c}));
    EXPECT_LE(prox.distance, sampled.min_distance + tolerance);
    EXPECT_GE(prox.distance, sampled.min_distance - sampled.resolution - tolerance);
}

template <typename Real>
class PointTriangleTest : public ::testing::Test {};

TYPED_TEST_SUITE(PointTriangleTest, RealTypes, RealNames);

// The unit right triangle a = 0, b = x, c = y, and one query point per Voronoi region.
TYPED_TEST(PointTriangleTest, EveryVoronoiRegionOfTheUnitTriangle) {
    using Real = TypeParam;
    const auto a = vec<Real>(0, 0, 0);
    const auto b = vec<Real>(1, 0, 0);
    const auto c = vec<Real>(0, 1, 0);
    struct Case {
        Vec3<Real> p;
        int region;
        Vec3<Real> barycentric;
        double distance;
        Vec3<Real> normal;
    };
    const double r2 = std::sqrt(0.5);
    const Case cases[] = {
        {vec<Real>(0.2, 0.3, 2), Region::FACE, vec<Real>(0.5, 0.2, 0.3), 2, vec<Real>(0, 0, 1)},
        {vec<Real>(0.2, 0.3, -2), Region::FACE, vec<Real>(0.5, 0.2, 0.3), 2, vec<Real>(0, 0, -1)},
        {vec<Real>(-1, -1, 0), Region::VERTEX_A, vec<Real>(1, 0, 0), std::sqrt(2.0),
         vec<Real>(-r2, -r2, 0)},
        {vec<Real>(3, -1, 0), Region::VERTEX_B, vec<Real>(0, 1, 0), std::sqrt(5.0),
         vec<Real>(2 / std::sqrt(5.0), -1 / std::sqrt(5.0), 0)},
        {vec<Real>(0.5, 2, -1), Region::VERTEX_C, vec<Real>(0, 0, 1), 1.5,
         vec<Real>(1.0 / 3, 2.0 / 3, -2.0 / 3)},
        {vec<Real>(0.25, -1, 1), Region::EDGE_AB, vec<Real>(0.75, 0.25, 0), std::sqrt(2.0),
         vec<Real>(0, -r2, r2)},
        {vec<Real>(1, 1, 0), Region::EDGE_BC, vec<Real>(0, 0.5, 0.5), r2, vec<Real>(r2, r2, 0)},
        {vec<Real>(-2, 0.75, 0), Region::EDGE_CA, vec<Real>(0.25, 0, 0.75), 2, vec<Real>(-1, 0, 0)},
    };
    const double eps = 8 * std::numeric_limits<Real>::epsilon();
    for (const Case& expected : cases) {
        SCOPED_TRACE("region " + std::to_string(expected.region));
        const auto prox = point_triangle_proximity(expected.p, a, b, c);
        EXPECT_EQ(prox.region, expected.region);
        EXPECT_NEAR(prox.distance, expected.distance, eps * 4);
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(prox.barycentric[i], expected.barycentric[i], eps);
            EXPECT_NEAR(prox.normal[i], expected.normal[i], eps);
        }
        expect_valid(prox, expected.p, a, b, c);
    }
}

TYPED_TEST(PointTriangleTest, PointsOnThePlane) {
    using Real = TypeParam;
    const auto a = vec<Real>(1, 0, 0);
    const auto b = vec<Real>(0, 1, 0);
    const auto c = vec<Real>(0, 0, 1);
    const Real inv_sqrt3 = Real(1) / std::sqrt(Real(3));
    const double eps = 8 * std::numeric_limits<Real>::epsilon();

    // Inside, on an edge and on a vertex: distance 0, normal = the unit triangle normal.
    const Vec3<Real> on_triangle[] = {vec<Real>(0.2, 0.3, 0.5), vec<Real>(0.5, 0.5, 0), a, b, c};
    for (const Vec3<Real> p : on_triangle) {
        const auto prox = point_triangle_proximity(p, a, b, c);
        EXPECT_NEAR(prox.distance, 0, eps);
        if (prox.distance == Real(0)) {
            for (int i = 0; i < 3; ++i) {
                EXPECT_NEAR(prox.normal[i], inv_sqrt3, eps);
            }
        }
        expect_valid(prox, p, a, b, c);
    }
    EXPECT_EQ(point_triangle_proximity(a, a, b, c).region, Region::VERTEX_A);
    EXPECT_EQ(point_triangle_proximity(c, a, b, c).region, Region::VERTEX_C);
    EXPECT_EQ(point_triangle_proximity(vec<Real>(0.2, 0.3, 0.5), a, b, c).region, Region::FACE);

    // In the plane but outside: an edge or vertex, and the normal lies in the plane.
    const Vec3<Real> outside[] = {vec<Real>(1, 1, -1), vec<Real>(2, -0.5, -0.5),
                                  vec<Real>(-1, 1, 1)};
    for (const Vec3<Real> p : outside) {
        const auto prox = point_triangle_proximity(p, a, b, c);
        EXPECT_NE(prox.region, Region::FACE);
        EXPECT_NEAR(dot(prox.normal, vec<Real>(1, 1, 1)), 0, 4 * eps);
        expect_valid(prox, p, a, b, c);
    }
}

template <typename Real>
Vec3<Real> random_point(std::mt19937& rng, double half_width, double scale) {
    std::uniform_real_distribution<double> coordinate(-half_width, half_width);
    return vec<Real>(coordinate(rng) * scale, coordinate(rng) * scale, coordinate(rng) * scale);
}

// Random triangles in [-1, 1]³ times scale, points in [-2, 2]³ times scale (so that every region
// is hit); against the reference and dense sampling. Returns how often each region was hit.
template <typename Real>
std::array<int, 7> check_random_queries(unsigned seed, int num_queries, double scale) {
    std::mt19937 rng(seed);
    std::array<int, 7> region_hits{};
    for (int query = 0; query < num_queries; ++query) {
        const auto a = random_point<Real>(rng, 1, scale);
        const auto b = random_point<Real>(rng, 1, scale);
        const auto c = random_point<Real>(rng, 1, scale);
        const auto p = random_point<Real>(rng, 2, scale);
        const auto prox = point_triangle_proximity(p, a, b, c);
        SCOPED_TRACE("query " + std::to_string(query));
        expect_valid(prox, p, a, b, c);
        expect_matches_sampling(prox, p, a, b, c, 48);
        ++region_hits[static_cast<std::size_t>(prox.region)];
    }
    return region_hits;
}

TYPED_TEST(PointTriangleTest, RandomQueriesMatchReferenceAndDenseSampling) {
    const std::array<int, 7> region_hits = check_random_queries<TypeParam>(7, 400, 1.0);
    for (int region = 0; region < 7; ++region) {
        EXPECT_GT(region_hits[static_cast<std::size_t>(region)], 0) << "region " << region;
    }
}

TYPED_TEST(PointTriangleTest, ScaleInvariance) {
    for (const double scale : {1e-6, 1e6}) {
        SCOPED_TRACE("scale " + std::to_string(scale));
        check_random_queries<TypeParam>(11, 100, scale);
    }
    // The same configuration at three scales: distance and weights scale exactly (powers of 2 up
    // to rounding of the scale factor), so compare relative to the unit result.
    using Real = TypeParam;
    const auto a = vec<Real>(0.1, -0.3, 0.2);
    const auto b = vec<Real>(0.9, 0.1, -0.1);
    const auto c = vec<Real>(-0.2, 0.8, 0.3);
    const auto p = vec<Real>(0.3, 0.2, 0.9);
    const auto unit = point_triangle_proximity(p, a, b, c);
    for (const Real scale : {Real(1e-6), Real(1e6)}) {
        const auto scaled = point_triangle_proximity(p * scale, a * scale, b * scale, c * scale);
        const Real eps = 64 * std::numeric_limits<Real>::epsilon();
        EXPECT_EQ(scaled.region, unit.region);
        EXPECT_NEAR(scaled.distance / scale, unit.distance, eps);
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(scaled.barycentric[i], unit.barycentric[i], eps);
            EXPECT_NEAR(scaled.normal[i], unit.normal[i], eps);
        }
    }
}

// A point far from a unit triangle: the distance keeps its relative accuracy.
TYPED_TEST(PointTriangleTest, FarPoints) {
    using Real = TypeParam;
    std::mt19937 rng(5);
    for (int query = 0; query < 50; ++query) {
        const auto a = random_point<Real>(rng, 1, 1);
        const auto b = random_point<Real>(rng, 1, 1);
        const auto c = random_point<Real>(rng, 1, 1);
        const auto p = random_point<Real>(rng, 1, 1e3);
        const auto prox = point_triangle_proximity(p, a, b, c);
        expect_valid(prox, p, a, b, c);
    }
}

// Slivers: the third corner at heights 1e-1 … 1e-15 of the longest edge above a point of it, with
// points near the face and around it. The distance keeps its accuracy at every height.
TYPED_TEST(PointTriangleTest, Slivers) {
    using Real = TypeParam;
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int exponent = 1; exponent <= 15; ++exponent) {
        SCOPED_TRACE("height 1e-" + std::to_string(exponent));
        const double height = std::pow(10.0, -exponent);
        for (int query = 0; query < 60; ++query) {
            const Vec3<double> a = random_point<double>(rng, 1, 1);
            const Vec3<double> b = random_point<double>(rng, 1, 1);
            const Vec3<double> across = cross(b - a, random_point<double>(rng, 1, 1));
            const Vec3<double> c =
                a + (b - a) * unit(rng) + across * (height * norm(b - a) / norm(across));
            // On the face (barycentric point, with a small offset off the plane) or anywhere.
            double v = unit(rng);
            double w = unit(rng);
            if (v + w > 1) {
                v = 1 - v;
                w = 1 - w;
            }
            const Vec3<double> p =
                query % 2 == 0 ? a + (b - a) * v + (c - a) * w + random_point<double>(rng, 1e-3, 1)
                               : random_point<double>(rng, 1, 1);
            const auto pr = vec3_cast<Real>(p);
            const auto ar = vec3_cast<Real>(a);
            const auto br = vec3_cast<Real>(b);
            const auto cr = vec3_cast<Real>(c);
            expect_valid(point_triangle_proximity(pr, ar, br, cr), pr, ar, br, cr);
        }
    }
}

// Zero-area triangles: collinear corners, coincident corners, and a nearly collinear one, with
// query points around and on them.
TYPED_TEST(PointTriangleTest, DegenerateTriangles) {
    using Real = TypeParam;
    struct Triangle {
        const char* name;
        Vec3<Real> a, b, c;
    };
    const Triangle triangles[] = {
        {"collinear, c between", vec<Real>(0, 0, 0), vec<Real>(2, 0, 0), vec<Real>(0.5, 0, 0)},
        {"collinear, c beyond", vec<Real>(0, 0, 0), vec<Real>(1, 1, 1), vec<Real>(3, 3, 3)},
        {"a = b", vec<Real>(1, 0, 0), vec<Real>(1, 0, 0), vec<Real>(0, 1, 0)},
        {"b = c", vec<Real>(1, 0, 0), vec<Real>(0, 1, 0), vec<Real>(0, 1, 0)},
        {"c = a", vec<Real>(0, 1, 0), vec<Real>(1, 0, 0), vec<Real>(0, 1, 0)},
        {"all coincident", vec<Real>(0.5, 0.5, 0.5), vec<Real>(0.5, 0.5, 0.5),
         vec<Real>(0.5, 0.5, 0.5)},
        {"nearly collinear", vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(0.5, 1e-12, 0)},
        {"skinny but valid", vec<Real>(0, 0, 0), vec<Real>(1, 0, 0), vec<Real>(0.5, 1e-3, 0)},
    };
    std::mt19937 rng(3);
    for (const Triangle& triangle : triangles) {
        SCOPED_TRACE(triangle.name);
        const Vec3<Real> a = triangle.a;
        const Vec3<Real> b = triangle.b;
        const Vec3<Real> c = triangle.c;
        std::vector<Vec3<Real>> points = {
            a, b, c, (a + b) * Real(0.5), (b + c) * Real(0.5), vec<Real>(0.3, 0.1, 0)};
        for (int i = 0; i < 40; ++i) {
            points.push_back(random_point<Real>(rng, 3, 1));
        }
        for (const Vec3<Real> p : points) {
            const auto prox = point_triangle_proximity(p, a, b, c);
            expect_valid(prox, p, a, b, c);
            expect_matches_sampling(prox, p, a, b, c, 32);
        }
        // On the triangle: distance 0 and still a unit normal.
        const auto on_corner = point_triangle_proximity(a, a, b, c);
        EXPECT_EQ(on_corner.distance, Real(0));
        EXPECT_NEAR(norm(on_corner.normal), Real(1), 8 * std::numeric_limits<Real>::epsilon());
    }

    // Collinear: the closest edge wins, with its vertex region at an endpoint.
    const auto a = vec<Real>(0, 0, 0);
    const auto b = vec<Real>(2, 0, 0);
    const auto c = vec<Real>(0.5, 0, 0);
    const auto beyond_b = point_triangle_proximity(vec<Real>(3, 1, 0), a, b, c);
    EXPECT_EQ(beyond_b.region, Region::VERTEX_B);
    EXPECT_NEAR(beyond_b.distance, std::sqrt(Real(2)), 4 * std::numeric_limits<Real>::epsilon());
    const auto above_middle = point_triangle_proximity(vec<Real>(1, 0, 2), a, b, c);
    EXPECT_EQ(above_middle.region, Region::EDGE_AB);
    EXPECT_NEAR(above_middle.distance, Real(2), 4 * std::numeric_limits<Real>::epsilon());
    EXPECT_NEAR(above_middle.normal.z, Real(1), 4 * std::numeric_limits<Real>::epsilon());
    // All coincident: vertex a, the distance to that point.
    const auto to_point = point_triangle_proximity(vec<Real>(0, 3, 4), a, a, a);
    EXPECT_EQ(to_point.region, Region::VERTEX_A);
    EXPECT_EQ(to_point.distance, Real(5));
    // Degenerate at distance 0: the normal is perpendicular to the (collinear) edges.
    const auto on_segment = point_triangle_proximity(vec<Real>(1, 0, 0), a, b, c);
    EXPECT_EQ(on_segment.distance, Real(0));
    EXPECT_NEAR(on_segment.normal.x, Real(0), 4 * std::numeric_limits<Real>::epsilon());
}

}  // namespace
}  // namespace pliant::collision
