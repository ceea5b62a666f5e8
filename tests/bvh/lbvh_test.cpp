#include "pliant/bvh/lbvh.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "pliant/bvh/traversal.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "support/brute_force.hpp"
#include "support/random_meshes.hpp"

namespace pliant::bvh {
namespace {

std::vector<test::Pair> self_pairs(const LBVH& tree) {
    std::vector<PrimitivePair> pairs;
    SelfOverlapCollector collector;
    collector.collect(
        tree, [](std::uint32_t, std::uint32_t) { return true; }, pairs);
    std::vector<test::Pair> out;
    for (const PrimitivePair& p : pairs) {
        out.emplace_back(p.first, p.second);
    }
    return out;
}

std::vector<test::Pair> cross_pairs(const LBVH& a, const LBVH& b) {
    ChunkedBuffer<test::Pair> buffer;
    buffer.reset(num_overlap_chunks(a));
    for_each_overlap(a, b, [&](std::int64_t chunk, std::uint32_t i, std::uint32_t j) {
        buffer.chunk(chunk).emplace_back(i, j);
    });
    std::vector<test::Pair> pairs;
    buffer.gather(pairs);
    return pairs;
}

void expect_self_pairs_match_brute_force(std::span<const AABB> boxes) {
    LBVH tree;
    tree.build(boxes);
    tree.validate(boxes);
    const auto pairs = self_pairs(tree);
    const auto normal = test::normalized(pairs);
    EXPECT_EQ(std::adjacent_find(normal.begin(), normal.end()), normal.end()) << "duplicate pair";
    EXPECT_EQ(normal, test::brute_force_self_overlaps(boxes));
}

TEST(LBVH, RandomSoupsMatchBruteForce) {
    for (const int n : {2, 3, 10, 100, 2000}) {
        for (const float size : {0.01f, 0.1f, 0.5f}) {
            SCOPED_TRACE(testing::Message() << "n=" << n << " size=" << size);
            const auto mesh = test::random_triangle_soup(n, size, static_cast<std::uint32_t>(n));
            expect_self_pairs_match_brute_force(test::triangle_boxes(mesh));
        }
    }
}

TEST(LBVH, JitteredSheetMatchesBruteForce) {
    const auto mesh = test::jittered_sheet(40, 30, 0.3f, 0.05f, 11);
    expect_self_pairs_match_brute_force(test::triangle_boxes(mesh, 0.002f));
}

TEST(LBVH, IdenticalBoxesGiveABalancedTreeAndEveryPair) {
    const std::vector<AABB> boxes(513, AABB{{0, 0, 0}, {1, 1, 1}});
    LBVH tree;
    tree.build(boxes);
    tree.validate(boxes);
    // Equal Morton codes: the position tie-break must keep the tree shallow, not a chain.
    // A balanced binary tree over 513 leaves has depth 10 (a chain would have 512); the 4-wide
    // tree is no deeper.
    EXPECT_LE(tree.depth(), 10);
    EXPECT_EQ(self_pairs(tree).size(), 513u * 512u / 2u);
}

TEST(LBVH, EqualMortonCodesFromTinyBoxes) {
    // Boxes far smaller than one 1024³ Morton cell of the scene: many share a code.
    auto boxes = test::random_boxes(3000, 1e-4f, 5);
    boxes.push_back({{100, 100, 100}, {101, 101, 101}});  // stretches the scene bounds
    expect_self_pairs_match_brute_force(boxes);
}

TEST(LBVH, FlatAndDegenerateBoxes) {
    std::vector<AABB> boxes;
    for (int i = 0; i < 300; ++i) {  // points on a line, some coincident
        const Vec3f p{static_cast<float>(i / 2) * 0.01f, 0.0f, 0.0f};
        boxes.push_back(AABB::of_point(p));
    }
    expect_self_pairs_match_brute_force(boxes);
}

TEST(LBVH, ZeroAndOnePrimitive) {
    LBVH tree;
    tree.build({});
    tree.validate({});
    EXPECT_FALSE(tree.has_nodes());
    EXPECT_TRUE(self_pairs(tree).empty());
    EXPECT_TRUE(tree.bounds().is_empty());
    const std::vector<AABB> one{{{0, 0, 0}, {1, 1, 1}}};
    tree.build(one);
    tree.validate(one);
    EXPECT_TRUE(self_pairs(tree).empty());
    EXPECT_EQ(tree.bounds(), one[0]);
    tree.refit(one);
    LBVH other;
    other.build(test::random_boxes(50, 0.3f, 1));
    EXPECT_EQ(test::normalized(cross_pairs(tree, other)).size(),
              test::brute_force_overlaps(one, test::random_boxes(50, 0.3f, 1)).size());
    EXPECT_EQ(cross_pairs(other, tree).size(), cross_pairs(tree, other).size());
}

TEST(LBVH, RebuildingWithOtherSizesKeepsNothingStale) {
    LBVH tree;
    for (const int n : {5000, 0, 1, 3, 20000, 2, 0, 700}) {
        const auto boxes = test::random_boxes(n, 0.05f, static_cast<std::uint32_t>(n + 1));
        tree.build(boxes);
        tree.refit(boxes);
        tree.validate(boxes);
        EXPECT_EQ(test::normalized(self_pairs(tree)), test::brute_force_self_overlaps(boxes)) << n;
    }
}

TEST(LBVH, RejectsBadBoxes) {
    std::vector<AABB> boxes = test::random_boxes(10, 0.1f, 2);
    boxes[4].lo.y = NAN;
    LBVH tree;
    try {
        tree.build(boxes);
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("box 4"), std::string::npos) << e.what();
    }
    boxes[4] = AABB{};  // empty
    EXPECT_THROW(tree.build(boxes), InvalidInput);
    boxes.pop_back();
    tree.build(test::random_boxes(10, 0.1f, 2));
    EXPECT_THROW(tree.refit(boxes), InvalidInput);  // 9 boxes for 10 primitives
}

TEST(LBVH, RefitTracksMotionAndMatchesRebuild) {
    auto mesh = test::jittered_sheet(30, 30, 0.2f, 0.0f, 3);
    LBVH tree;
    tree.build(test::triangle_boxes(mesh, 0.001f));
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-0.02f, 0.02f);
    for (int step = 0; step < 5; ++step) {
        for (Vec3f& p : mesh.positions) {
            p += Vec3f{u(rng), u(rng), 0.5f * std::sin(10.0f * p.x + static_cast<float>(step))};
        }
        const auto boxes = test::triangle_boxes(mesh, 0.001f);
        tree.refit(boxes);
        tree.validate(boxes);
        EXPECT_EQ(test::normalized(self_pairs(tree)), test::brute_force_self_overlaps(boxes));
    }
}

TEST(LBVH, PairTraversalMatchesBruteForce) {
    const auto a = test::random_boxes(700, 0.05f, 21);
    const auto b = test::random_boxes(400, 0.08f, 22);
    LBVH ta, tb;
    ta.build(a);
    tb.build(b);
    auto pairs = cross_pairs(ta, tb);
    std::sort(pairs.begin(), pairs.end());
    EXPECT_EQ(pairs, test::brute_force_overlaps(a, b));
}

// Euclidean distance from p to a box (0 inside), in double.
double box_distance(const Vec3d& p, const AABB& box) {
    const Vec3d lo = vec3_cast<double>(box.lo);
    const Vec3d hi = vec3_cast<double>(box.hi);
    const Vec3d gap = max(max(lo - p, p - hi), Vec3d{0.0, 0.0, 0.0});
    return norm(gap);
}

TEST(LBVH, NearestQueryMatchesBruteForce) {
    // Nearest box to random points, with the query's radius shrinking to the best distance found:
    // the least (distance, index) must equal brute force, and within a finite radius nothing is
    // found exactly when brute force finds nothing.
    for (const int n : {1, 2, 7, 300, 5000}) {
        const auto boxes = test::random_boxes(n, 0.01f, static_cast<std::uint32_t>(n + 40));
        LBVH tree;
        tree.build(boxes);
        std::mt19937 rng(static_cast<std::uint32_t>(n));
        std::uniform_real_distribution<double> u(-0.3, 1.3);
        std::int64_t visited = 0;
        for (int q = 0; q < 200; ++q) {
            const Vec3d p{u(rng), u(rng), u(rng)};
            double expected = INFINITY;
            std::uint32_t expected_index = 0;
            for (std::size_t i = 0; i < boxes.size(); ++i) {
                const double d = box_distance(p, boxes[i]);
                if (d < expected) {
                    expected = d;
                    expected_index = static_cast<std::uint32_t>(i);
                }
            }
            for (const double radius : {double{INFINITY}, 0.05, 0.0}) {
                double best = radius;
                std::uint32_t best_index = UINT32_MAX;
                query_wide_nearest(tree.nodes().data(), p, radius,
                                   [&](std::int32_t leaf, const AABB& box) {
                                       const std::uint32_t i = tree.primitives()[leaf];
                                       EXPECT_EQ(box, boxes[i]);
                                       const double d = box_distance(p, box);
                                       ++visited;
                                       if (d < best || (d == best && i < best_index)) {
                                           best = d;
                                           best_index = i;
                                       }
                                       return best;
                                   });
                SCOPED_TRACE(testing::Message() << "n=" << n << " q=" << q << " r=" << radius);
                if (expected <= radius) {
                    EXPECT_EQ(best, expected);
                    EXPECT_EQ(best_index, expected_index);
                } else {
                    EXPECT_EQ(best_index, UINT32_MAX);
                }
            }
        }
        if (n == 5000) {
            // Pruning works: far fewer leaves visited than 3 queries × 200 points × n.
            EXPECT_LT(visited, 200 * 3 * n / 50);
        }
    }
}

TEST(LBVH, QueryBoxAroundContainsTheDoubleBox) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-140, 120);
    for (int i = 0; i < 20000; ++i) {
        const Vec3d p{std::ldexp(mantissa(rng), exponent(rng)),
                      std::ldexp(mantissa(rng), exponent(rng)), i % 7 == 0 ? 0.0 : mantissa(rng)};
        const double r = i % 5 == 0 ? 0.0 : std::ldexp(std::abs(mantissa(rng)), exponent(rng));
        const AABB box = query_box_around(p, r);
        for (int a = 0; a < 3; ++a) {
            ASSERT_LE(static_cast<double>(box.lo[a]), p[a] - r) << i;
            ASSERT_GE(static_cast<double>(box.hi[a]), p[a] + r) << i;
        }
    }
    const AABB everything = query_box_around({1.0, 2.0, 3.0}, INFINITY);
    EXPECT_EQ(everything.lo.x, -INFINITY);
    EXPECT_EQ(everything.hi.z, INFINITY);
}

TEST(LBVH, NearestQueryKeepsLeavesAtTheRadiusAndSurvivesRounding) {
    // Boxes touching the query box's boundary (closed intervals) are visited; coordinates that
    // are not floats are rounded outward, so a box at exactly the radius from a double point is
    // not lost.
    const std::vector<AABB> boxes{AABB::of_point({1.0f, 0.0f, 0.0f}),
                                  AABB::of_point({0.0f, 0.1f, 0.0f}),
                                  AABB::of_point({0.0f, 0.0f, -3.0f})};
    LBVH tree;
    tree.build(boxes);
    const Vec3d p{0.0, 0.1 - 0.25, 0.0};  // 0.1 - 0.25 is not a float
    int found = 0;
    query_wide_nearest(tree.nodes().data(), p, 0.25 + static_cast<double>(0.1f) - 0.1,
                       [&](std::int32_t leaf, const AABB&) {
                           found |= 1 << tree.primitives()[leaf];
                           return INFINITY;  // larger than the radius: ignored
                       });
    EXPECT_EQ(found, 2);
    found = 0;
    query_wide_nearest(tree.nodes().data(), Vec3d{0.0, 0.0, 0.0}, NAN,
                       [&](std::int32_t, const AABB&) {
                           ++found;
                           return 0.0;
                       });
    EXPECT_EQ(found, 0);
}

TEST(LBVH, BitwiseIdenticalForOneAndManyThreads) {
    const auto mesh = test::jittered_sheet(120, 100, 0.3f, 0.05f, 4);
    const auto boxes = test::triangle_boxes(mesh, 0.004f);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        LBVH tree;
        tree.build(boxes);
        tree.refit(boxes);
        return std::make_pair(std::vector<WideNode>(tree.nodes().begin(), tree.nodes().end()),
                              self_pairs(tree));
    };
    const auto one = run(1);
    const auto many = run(4);
    set_num_threads(0);
    ASSERT_EQ(one.first.size(), many.first.size());
    EXPECT_EQ(std::memcmp(one.first.data(), many.first.data(), one.first.size() * sizeof(WideNode)),
              0);
    EXPECT_EQ(one.second, many.second);  // same pairs in the same order
    EXPECT_GT(one.second.size(), 100000u);
}

TEST(LBVH, ScaleInvariance) {
    for (const float scale : {1e-6f, 1e6f}) {
        auto mesh = test::jittered_sheet(25, 25, 0.3f, 0.1f, 8);
        for (Vec3f& p : mesh.positions) {
            p *= scale;
        }
        expect_self_pairs_match_brute_force(test::triangle_boxes(mesh));
    }
}

}  // namespace
}  // namespace pliant::bvh
