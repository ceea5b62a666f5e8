#include "pliant/collision/intersecting_pairs.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "pliant/collision/incidence.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/triangle_intersection.hpp"
#include "support/random_meshes.hpp"

namespace pliant::collision {
namespace {

using Pairs = std::vector<std::array<std::int32_t, 2>>;

// Reference: every pair i < j in order, no BVH, no boxes.
Pairs brute_force(std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles) {
    Pairs pairs;
    const auto at = [&](std::int32_t v) {
        return positions[static_cast<std::size_t>(v)];
    };
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        for (std::size_t j = i + 1; j < triangles.size(); ++j) {
            const geometry::Triangle& a = triangles[i];
            const geometry::Triangle& b = triangles[j];
            if (!share_vertex(a, b) &&
                geometry::triangles_intersect(at(a[0]), at(a[1]), at(a[2]), at(b[0]), at(b[1]),
                                              at(b[2]))) {
                pairs.push_back({static_cast<std::int32_t>(i), static_cast<std::int32_t>(j)});
            }
        }
    }
    return pairs;
}

std::vector<Vec3d> to_double(const std::vector<Vec3f>& positions) {
    std::vector<Vec3d> out;
    for (const Vec3f& p : positions) {
        out.push_back(vec3_cast<double>(p));
    }
    return out;
}

// Checks the fast paths against brute force and returns the count.
std::int64_t expect_matches_brute_force(const std::vector<Vec3d>& positions,
                                        const std::vector<geometry::Triangle>& triangles) {
    const Pairs expected = brute_force(positions, triangles);
    EXPECT_EQ(find_intersecting_pairs(positions, triangles), expected);
    const std::int64_t count = count_intersecting_pairs(positions, triangles);
    EXPECT_EQ(count, static_cast<std::int64_t>(expected.size()));
    return count;
}

// A sheet of nx × ny quads over [-0.5, 0.5]² bent along x into the curve (s³ - s, s²),
// s = 3x, which crosses itself at s = ±1: the sheet passes through itself along a line.
geometry::TriangleMeshD self_crossing_sheet(int nx, int ny) {
    const geometry::TriangleMesh flat = geometry::make_grid_sheet(nx, ny, 1.0f, 1.0f);
    geometry::TriangleMeshD mesh = geometry::convert_precision<double>(flat);
    for (Vec3d& p : mesh.positions) {
        const double s = 3.0 * p.x;
        p = {s * s * s - s, p.y, s * s};
    }
    return mesh;
}

TEST(IntersectingPairs, RandomSoupsMatchBruteForce) {
    for (const std::uint32_t seed : {1u, 2u, 3u}) {
        const geometry::TriangleMesh soup = test::random_triangle_soup(400, 0.2f, seed);
        EXPECT_GT(expect_matches_brute_force(to_double(soup.positions), soup.triangles), 0)
            << "seed " << seed;
    }
}

TEST(IntersectingPairs, FlatSheetHasNone) {
    // Edge length 1/8: every coordinate and every map below is exact in double.
    const geometry::TriangleMeshD sheet =
        geometry::convert_precision<double>(geometry::make_grid_sheet(16, 8, 2.0f, 1.0f));
    EXPECT_EQ(expect_matches_brute_force(sheet.positions, sheet.triangles), 0);
    // Tilted into a general plane and translated far from the origin, still exactly flat: every
    // candidate pair is coplanar and decided by the exact path.
    std::vector<Vec3d> tilted = sheet.positions;
    for (Vec3d& p : tilted) {
        p = Vec3d{p.x + 0.5 * p.y, p.y, 0.25 * p.x - p.y} + Vec3d{4096.0, -1024.0, 512.0};
    }
    EXPECT_EQ(expect_matches_brute_force(tilted, sheet.triangles), 0);
    // The crumpled jittered sheet of the broad-phase tests has none either.
    const geometry::TriangleMesh crumpled = test::jittered_sheet(20, 16, 0.3f, 0.02f, 4);
    EXPECT_EQ(expect_matches_brute_force(to_double(crumpled.positions), crumpled.triangles), 0);
}

TEST(IntersectingPairs, SheetFoldedThroughItselfHasSome) {
    const geometry::TriangleMeshD mesh = self_crossing_sheet(40, 10);
    EXPECT_GT(expect_matches_brute_force(mesh.positions, mesh.triangles), 10);
}

TEST(IntersectingPairs, SharedVertexPairsAreNotCounted) {
    // Two triangles crossing each other through a shared vertex 0: not counted.
    const std::vector<Vec3d> positions = {
        {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, -1}, {0.2, 0.2, 1}};
    const std::vector<geometry::Triangle> shared = {{0, 1, 2}, {0, 3, 4}};
    EXPECT_EQ(count_intersecting_pairs(positions, shared), 0);
    // The same geometry with vertex 0 duplicated: counted once.
    std::vector<Vec3d> split = positions;
    split.push_back(positions[0]);
    const std::vector<geometry::Triangle> separate = {{0, 1, 2}, {5, 3, 4}};
    EXPECT_EQ(expect_matches_brute_force(split, separate), 1);
    // Triangles sharing an edge and folded onto each other: not counted.
    const std::vector<Vec3d> folded = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
    EXPECT_EQ(
        count_intersecting_pairs(folded, std::vector<geometry::Triangle>{{0, 1, 2}, {0, 1, 3}}), 0);
}

TEST(IntersectingPairs, TouchingAndDegenerateTrianglesCount) {
    // A vertex resting exactly on another triangle, a zero-area triangle lying across it.
    const std::vector<Vec3d> positions = {
        {0, 0, 0}, {1, 0, 0},    {0, 1, 0},   {0.25, 0.25, 0}, {0, 0, 1},
        {1, 0, 1}, {-1, 0.5, 0}, {2, 0.5, 0}, {0.5, 0.5, 0},   {0.25, 0.25, 0x1p-40}};
    const std::vector<geometry::Triangle> triangles = {
        {0, 1, 2},  // P
        {3, 4, 5},  // touches P's interior at vertex 3
        {6, 7, 8},  // a segment through P (and through nothing else)
        {9, 4, 5},  // lifted by ≈ 1e-12: misses P
    };
    const Pairs pairs = find_intersecting_pairs(positions, triangles);
    EXPECT_EQ(pairs, (Pairs{{0, 1}, {0, 2}}));
    EXPECT_EQ(expect_matches_brute_force(positions, triangles), 2);
}

TEST(IntersectingPairs, ThreadsDoNotMatter) {
    const geometry::TriangleMeshD mesh = self_crossing_sheet(90, 40);  // 7,200 triangles
    const auto run = [&](int threads) {
        set_num_threads(threads);
        return std::pair{find_intersecting_pairs(mesh.positions, mesh.triangles),
                         count_intersecting_pairs(mesh.positions, mesh.triangles)};
    };
    const auto one = run(1);
    const auto two = run(2);
    set_num_threads(0);
    EXPECT_EQ(one.first, two.first);
    EXPECT_EQ(one.second, two.second);
    EXPECT_EQ(one.second, static_cast<std::int64_t>(one.first.size()));
    EXPECT_GT(one.second, 100);
}

TEST(IntersectingPairs, FloatPositionsMatchDouble) {
    const geometry::TriangleMesh soup = test::random_triangle_soup(300, 0.2f, 9);
    const std::vector<Vec3d> positions = to_double(soup.positions);
    EXPECT_EQ(find_intersecting_pairs(std::span<const Vec3f>(soup.positions), soup.triangles),
              find_intersecting_pairs(positions, soup.triangles));
    EXPECT_EQ(count_intersecting_pairs(std::span<const Vec3f>(soup.positions), soup.triangles),
              count_intersecting_pairs(positions, soup.triangles));
}

TEST(IntersectingPairs, EmptyAndSingleTriangle) {
    EXPECT_EQ(count_intersecting_pairs(std::span<const Vec3d>(), {}), 0);
    const std::vector<Vec3d> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_EQ(count_intersecting_pairs(positions, std::vector<geometry::Triangle>{{0, 1, 2}}), 0);
    EXPECT_TRUE(
        find_intersecting_pairs(positions, std::vector<geometry::Triangle>{{0, 1, 2}}).empty());
}

// Reference for two meshes: every (i, j), no BVH, no boxes.
std::int64_t brute_force_between(std::span<const Vec3d> pa, std::span<const geometry::Triangle> ta,
                                 std::span<const Vec3d> pb,
                                 std::span<const geometry::Triangle> tb) {
    std::int64_t count = 0;
    for (const geometry::Triangle& a : ta) {
        for (const geometry::Triangle& b : tb) {
            const auto at = [](std::span<const Vec3d> p, std::int32_t v) {
                return p[static_cast<std::size_t>(v)];
            };
            count += geometry::triangles_intersect(at(pa, a[0]), at(pa, a[1]), at(pa, a[2]),
                                                   at(pb, b[0]), at(pb, b[1]), at(pb, b[2]))
                         ? 1
                         : 0;
        }
    }
    return count;
}

TEST(IntersectingPairsBetween, RandomSoupsMatchBruteForceForAnyThreads) {
    for (const std::uint32_t seed : {4u, 5u}) {
        const geometry::TriangleMesh a = test::random_triangle_soup(300, 0.2f, seed);
        const geometry::TriangleMesh b = test::random_triangle_soup(200, 0.2f, seed + 10);
        const std::vector<Vec3d> pa = to_double(a.positions);
        const std::vector<Vec3d> pb = to_double(b.positions);
        const std::int64_t expected = brute_force_between(pa, a.triangles, pb, b.triangles);
        EXPECT_GT(expected, 0) << "seed " << seed;
        set_num_threads(1);
        const std::int64_t one = count_intersecting_pairs(pa, a.triangles, pb, b.triangles);
        set_num_threads(2);
        const std::int64_t two = count_intersecting_pairs(pa, a.triangles, pb, b.triangles);
        set_num_threads(0);
        EXPECT_EQ(one, expected) << "seed " << seed;
        EXPECT_EQ(two, expected) << "seed " << seed;
        // Swapping the meshes counts the same pairs.
        EXPECT_EQ(count_intersecting_pairs(pb, b.triangles, pa, a.triangles), expected);
    }
}

TEST(IntersectingPairsBetween, EdgeThroughAThinPartBetweenVerticesOutside) {
    // A "finger": a thin vertical triangle; a cloth quad whose four vertices are all outside it
    // and whose diagonal edge crosses it.
    const std::vector<Vec3d> finger = {{0, -0.001, -1}, {0, 0.001, -1}, {0, 0, 1}};
    const std::vector<geometry::Triangle> finger_triangles = {{0, 1, 2}};
    std::vector<Vec3d> cloth = {{-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0.5, 0.5, 0}, {-0.5, 0.5, 0}};
    const std::vector<geometry::Triangle> quad = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_EQ(count_intersecting_pairs(cloth, quad, finger, finger_triangles), 2);
    // Lifted above the tip: none; touching the tip exactly: counted.
    for (Vec3d& p : cloth) {
        p.z = 1.0 + 0x1p-40;
    }
    EXPECT_EQ(count_intersecting_pairs(cloth, quad, finger, finger_triangles), 0);
    for (Vec3d& p : cloth) {
        p.z = 1.0;
    }
    EXPECT_EQ(count_intersecting_pairs(cloth, quad, finger, finger_triangles),
              brute_force_between(cloth, quad, finger, finger_triangles));
    EXPECT_GT(count_intersecting_pairs(cloth, quad, finger, finger_triangles), 0);
    // Empty meshes.
    EXPECT_EQ(count_intersecting_pairs(cloth, quad, finger, {}), 0);
    EXPECT_EQ(count_intersecting_pairs({}, {}, finger, finger_triangles), 0);
}

TEST(IntersectingPairsBetween, RejectsBadInputNamingTheMesh) {
    const std::vector<Vec3d> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<geometry::Triangle> good = {{0, 1, 2}};
    const std::vector<geometry::Triangle> bad = {{0, 1, 3}};
    const auto message = [&](auto&& call) {
        try {
            call();
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message([&] { count_intersecting_pairs(positions, good, positions, bad); })
                  .find("count_intersecting_pairs: mesh b: triangles: triangle 0 corner 2 has "
                        "vertex index 3"),
              std::string::npos);
    std::vector<Vec3d> nan = positions;
    nan[1].x = NAN;
    EXPECT_NE(message([&] {
                  count_intersecting_pairs(nan, good, positions, good);
              }).find("mesh a: positions[1] coordinate x is nan"),
              std::string::npos);
}

void expect_invalid(const std::vector<Vec3d>& positions,
                    const std::vector<geometry::Triangle>& triangles, const std::string& needle) {
    try {
        count_intersecting_pairs(positions, triangles);
        FAIL() << "expected InvalidInput containing " << needle;
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_THROW(find_intersecting_pairs(positions, triangles), InvalidInput);
}

TEST(IntersectingPairs, RejectsBadInput) {
    const std::vector<Vec3d> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    expect_invalid(positions, {{0, 1, 2}, {0, 1, 7}},
                   "count_intersecting_pairs: triangles: triangle 1 corner 2 has vertex index 7, "
                   "expected 0 <= index < 4");
    expect_invalid(positions, {{0, -1, 2}}, "vertex index -1");
    expect_invalid(positions, {{0, 1, 1}}, "repeats a vertex");
    std::vector<Vec3d> bad = positions;
    bad[2].y = NAN;
    expect_invalid(bad, {{0, 1, 2}}, "positions[2] coordinate y is nan");
    bad[2].y = INFINITY;
    expect_invalid(bad, {{0, 1, 2}}, "positions[2] coordinate y is inf");
    bad[2].y = 1e300;
    expect_invalid(bad, {{0, 1, 2}}, "exact predicates' domain");
    bad[2].y = 1e-300;
    expect_invalid(bad, {{0, 1, 2}}, "positions[2] coordinate y is 1e-300");
}

}  // namespace
}  // namespace pliant::collision
