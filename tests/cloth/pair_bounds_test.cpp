#include "pliant/cloth/detail/pair_bounds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"

namespace pliant::cloth::detail {
namespace {

double exact_distance(bool edge_edge, const Vec3d (&p)[4]) {
    return edge_edge ? collision::segment_segment_proximity(p[0], p[1], p[2], p[3]).distance
                     : collision::point_triangle_proximity(p[0], p[1], p[2], p[3]).distance;
}

template <bool EDGE_EDGE>
void expect_lower_bounds(const Vec3d (&p)[4], double& tightest_axis_ratio) {
    const double exact = exact_distance(EDGE_EDGE, p);
    const double tolerance = 1e-12 * (1.0 + exact);
    const double box = box_gap<EDGE_EDGE>(p[0], p[1], p[2], p[3]);
    const double axis = centroid_axis_gap<EDGE_EDGE>(p[0], p[1], p[2], p[3]);
    ASSERT_TRUE(std::isfinite(box) && std::isfinite(axis));
    EXPECT_GE(box, 0.0);
    EXPECT_GE(axis, 0.0);
    EXPECT_LE(box, exact + tolerance) << "edge_edge " << EDGE_EDGE;
    EXPECT_LE(axis, exact + tolerance) << "edge_edge " << EDGE_EDGE;
    if (exact > 0.0) {
        tightest_axis_ratio = std::max(tightest_axis_ratio, axis / exact);
    }
}

// Random pairs at every scale of separation, from overlapping to far apart, including
// degenerate features (coincident vertices, collinear triangles, parallel edges): neither bound
// ever exceeds the exact distance, and the axis bound is often tight (it is exact for a vertex
// facing a triangle's centroid).
TEST(PairBounds, NeverExceedTheExactDistance) {
    std::mt19937 rng(20261124);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> shape(0, 5);
    double tightest_vf = 0.0;
    double tightest_ee = 0.0;
    for (int trial = 0; trial < 20000; ++trial) {
        const double spread = std::pow(10.0, 2.0 * unit(rng));
        const Vec3d offset{spread * unit(rng), spread * unit(rng), spread * unit(rng)};
        Vec3d p[4];
        for (int k = 0; k < 4; ++k) {
            p[k] = Vec3d{unit(rng), unit(rng), unit(rng)} + (k == 0 ? Vec3d{} : offset);
        }
        switch (shape(rng)) {
            case 0:
                p[2] = p[1];  // coincident vertices: a degenerate triangle or a shared position
                break;
            case 1:
                p[3] = p[1] + (p[2] - p[1]) * 2.0;  // collinear
                break;
            case 2:
                p[3] = p[2] + (p[1] - p[0]);  // parallel edges
                break;
            case 3:
                for (Vec3d& q : p) {
                    q.z = 0.0;  // coplanar (a flat sheet)
                }
                break;
            default:
                break;
        }
        expect_lower_bounds<false>(p, tightest_vf);
        expect_lower_bounds<true>(p, tightest_ee);
    }
    EXPECT_GT(tightest_vf, 0.999);
    EXPECT_GT(tightest_ee, 0.999);
}

// Neighbouring features of a sheet lying diagonally to the axes: their boxes overlap (box_gap 0)
// while the centroids' line separates them by their distance.
TEST(PairBounds, CentroidAxisSeparatesDiagonalNeighbours) {
    const double e = 0.015;
    // The vertex (0, 0) against the triangle across the diagonal (e, 0), (e, e), (0, e): distance
    // e / √2 to the diagonal.
    const Vec3d vf[4] = {{0.0, 0.0, 0.0}, {e, 0.0, 0.0}, {e, e, 0.0}, {0.0, e, 0.0}};
    EXPECT_EQ(box_gap<false>(vf[0], vf[1], vf[2], vf[3]), 0.0);
    EXPECT_NEAR(centroid_axis_gap<false>(vf[0], vf[1], vf[2], vf[3]), e / std::sqrt(2.0), 1e-15);
    // Two parallel diagonals of neighbouring quads, e / √2 apart.
    const Vec3d ee[4] = {{e, 0.0, 0.0}, {0.0, e, 0.0}, {2.0 * e, 0.0, 0.0}, {0.0, 2.0 * e, 0.0}};
    EXPECT_EQ(box_gap<true>(ee[0], ee[1], ee[2], ee[3]), 0.0);
    EXPECT_NEAR(centroid_axis_gap<true>(ee[0], ee[1], ee[2], ee[3]), e / std::sqrt(2.0), 1e-15);
    // Rotating the sheet does not change the axis bound (it uses no coordinate axes).
    const double c = std::cos(0.7);
    const double s = std::sin(0.7);
    Vec3d turned[4];
    for (int k = 0; k < 4; ++k) {
        turned[k] = {c * vf[k].x - s * vf[k].z, vf[k].y, s * vf[k].x + c * vf[k].z};
    }
    EXPECT_NEAR(centroid_axis_gap<false>(turned[0], turned[1], turned[2], turned[3]),
                e / std::sqrt(2.0), 1e-15);
}

// The point-set overloads on two triangles (the triangle-pair filter): never above the
// triangles' distance, the least of their 6 vertex-face and 9 edge-edge distances.
TEST(PairBounds, TrianglePairBoundsNeverExceedTheTrianglesDistance) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    double tightest = 0.0;
    for (int trial = 0; trial < 5000; ++trial) {
        const double spread = std::pow(10.0, 2.0 * unit(rng));
        const Vec3d offset{spread * unit(rng), spread * unit(rng), spread * unit(rng)};
        Vec3d a[3];
        Vec3d b[3];
        for (int k = 0; k < 3; ++k) {
            a[k] = {unit(rng), unit(rng), unit(rng)};
            b[k] = Vec3d{unit(rng), unit(rng), unit(rng)} + offset;
        }
        double exact = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
            exact = std::min(exact,
                             collision::point_triangle_proximity(a[k], b[0], b[1], b[2]).distance);
            exact = std::min(exact,
                             collision::point_triangle_proximity(b[k], a[0], a[1], a[2]).distance);
            for (int l = 0; l < 3; ++l) {
                exact = std::min(exact, collision::segment_segment_proximity(a[k], a[(k + 1) % 3],
                                                                             b[l], b[(l + 1) % 3])
                                            .distance);
            }
        }
        const double tolerance = 1e-12 * (1.0 + exact);
        const double box = box_gap(a, b);
        const double axis = centroid_axis_gap(a, b);
        EXPECT_LE(box, exact + tolerance);
        EXPECT_LE(axis, exact + tolerance);
        if (exact > 0.0) {
            tightest = std::max(tightest, std::max(box, axis) / exact);
        }
    }
    EXPECT_GT(tightest, 0.9);
}

TEST(PairBounds, LargestPairDifferenceIsTheBruteForceMaximum) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int trial = 0; trial < 1000; ++trial) {
        Vec3d d[4];
        for (Vec3d& q : d) {
            q = {unit(rng), unit(rng), unit(rng)};
        }
        for (const int num_first : {1, 2}) {
            double largest = 0.0;
            for (int i = 0; i < num_first; ++i) {
                for (int j = num_first; j < 4; ++j) {
                    largest = std::max(largest, norm(d[i] - d[j]));
                }
            }
            const double got = num_first == 2
                                   ? largest_pair_difference<true>(d[0], d[1], d[2], d[3])
                                   : largest_pair_difference<false>(d[0], d[1], d[2], d[3]);
            EXPECT_NEAR(got, largest, 1e-15);
        }
    }
}

}  // namespace
}  // namespace pliant::cloth::detail
