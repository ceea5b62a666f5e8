#include "pliant/cloth/edge_strain.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

struct Sheet {
    std::vector<Vec3d> positions;
    std::vector<geometry::Triangle> triangles;
};

Sheet sheet(int n) {
    const geometry::TriangleMesh mesh = geometry::make_grid_sheet(n, n, 1.0f, 1.0f);
    Sheet s;
    for (const Vec3f& p : mesh.positions) {
        s.positions.push_back(vec3_cast<double>(p));
    }
    s.triangles = mesh.triangles;
    return s;
}

TEST(EdgeStrain, RestShapeIsUnstrainedAndUniformScalingStrainsEveryEdgeEqually) {
    const Sheet s = sheet(8);
    const EdgeStrain strain(s.positions, s.triangles);
    // 8 x 8 quads, each split by a diagonal: 2·8·9 axis edges + 64 diagonals.
    EXPECT_EQ(strain.num_edges(), 2u * 8u * 9u + 64u);
    const StrainStats rest = strain.measure(s.positions);
    EXPECT_EQ(rest.max, 0.0);
    EXPECT_EQ(rest.over_10_percent, 0);

    std::vector<Vec3d> scaled = s.positions;
    for (Vec3d& p : scaled) {
        p = p * 1.25;
    }
    const StrainStats stretched = strain.measure(scaled);
    EXPECT_NEAR(stretched.p90, 0.25, 1e-12);
    EXPECT_NEAR(stretched.p99, 0.25, 1e-12);
    EXPECT_NEAR(stretched.max, 0.25, 1e-12);
    EXPECT_EQ(stretched.over_10_percent, static_cast<std::int64_t>(strain.num_edges()));
    EXPECT_EQ(stretched.over_100_percent, 0);

    // Compression is not reported as stretch.
    for (Vec3d& p : scaled) {
        p = p * 0.5;
    }
    const StrainStats compressed = strain.measure(scaled);
    EXPECT_EQ(compressed.max, 0.0);
    EXPECT_EQ(compressed.p99, 0.0);
}

TEST(EdgeStrain, PercentilesMatchABruteForceOverRandomDisplacements) {
    const Sheet s = sheet(12);
    const EdgeStrain strain(s.positions, s.triangles);
    std::mt19937 rng(11);
    std::normal_distribution<double> jitter(0.0, 0.02);
    std::vector<Vec3d> moved = s.positions;
    for (Vec3d& p : moved) {
        p += Vec3d{jitter(rng), jitter(rng), jitter(rng)};
    }
    // Brute force: every (a, b) pair that shares a triangle, once.
    std::set<std::pair<int, int>> edges;
    for (const geometry::Triangle& t : s.triangles) {
        for (int k = 0; k < 3; ++k) {
            edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
        }
    }
    std::vector<double> values;
    for (const auto& [a, b] : edges) {
        values.push_back(norm(moved[b] - moved[a]) / norm(s.positions[b] - s.positions[a]) - 1.0);
    }
    std::sort(values.begin(), values.end());
    const auto rank = [&](double q) {
        return values[static_cast<std::size_t>(std::ceil(q * values.size())) - 1];
    };
    const StrainStats stats = strain.measure(moved);
    EXPECT_EQ(strain.num_edges(), edges.size());
    EXPECT_DOUBLE_EQ(stats.max, values.back());
    EXPECT_DOUBLE_EQ(stats.p99, rank(0.99));
    EXPECT_DOUBLE_EQ(stats.p90, rank(0.90));
    EXPECT_EQ(stats.over_10_percent,
              std::count_if(values.begin(), values.end(), [](double v) { return v > 0.1; }));
    EXPECT_GT(stats.over_10_percent, 0);  // the jitter is large enough for the count to matter
}

TEST(EdgeStrain, OneVertexPulledFarStretchesItsEdgesBeyondDouble) {
    const Sheet s = sheet(4);
    const EdgeStrain strain(s.positions, s.triangles);
    std::vector<Vec3d> moved = s.positions;
    moved[12] += Vec3d{0.0, 0.0, 1.0};  // an interior vertex, 1 m up; the edges are 0.25 m or so
    const StrainStats stats = strain.measure(moved);
    std::set<std::pair<int, int>> incident;  // the edges at vertex 12: only those stretch
    for (const geometry::Triangle& t : s.triangles) {
        for (int k = 0; k < 3; ++k) {
            if (t[k] == 12 || t[(k + 1) % 3] == 12) {
                incident.insert(std::minmax(t[k], t[(k + 1) % 3]));
            }
        }
    }
    EXPECT_GE(incident.size(), 4u);
    EXPECT_GT(stats.max, 1.0);
    EXPECT_EQ(stats.over_100_percent, static_cast<std::int64_t>(incident.size()));
}

TEST(EdgeStrain, ZeroLengthEdgesAreSkippedAndWrongSizesAreRefused) {
    // Two triangles, one of them with a repeated position (a zero-length edge).
    const std::vector<Vec3d> rest = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}};
    const std::vector<geometry::Triangle> triangles = {{0, 1, 2}, {1, 3, 2}};
    const EdgeStrain strain(rest, triangles);
    EXPECT_EQ(strain.num_edges(), 4u);  // 5 unique edges, (1, 3) of length 0
    EXPECT_THROW(strain.measure(std::vector<Vec3d>(3)), InvalidInput);
    const StrainStats stats = strain.measure(rest);
    EXPECT_TRUE(std::isfinite(stats.max));
}

}  // namespace
}  // namespace pliant::cloth
