#include "pliant/cloth/self_collision_candidates.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace pliant::cloth {
namespace {

// Two separate triangles, the second `gap` metres above the first (z up).
std::vector<Vec3d> two_triangles(double gap) {
    return {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0},
            {0.2, 0.2, gap}, {0.6, 0.2, gap}, {0.2, 0.6, gap}};
}
const std::vector<geometry::Triangle> TRIANGLES{{0, 1, 2}, {3, 4, 5}};
constexpr double THICKNESS = 0.01;
constexpr double WINDOW = 0.01;

TEST(SelfCollisionCandidates, KeepsThePairsThatCanComeWithinTheThickness) {
    const std::vector<Vec3d> still(6, Vec3d{0.0, 0.0, 0.0});
    SelfCollisionCandidates near(TRIANGLES, 6, THICKNESS);
    EXPECT_FALSE(near.has_paths());
    SelfCollisionStats stats;
    near.prepare(two_triangles(0.5 * THICKNESS), still, 0.0, WINDOW, stats);
    EXPECT_TRUE(near.has_paths());
    EXPECT_EQ(stats.gathers, 1);
    ASSERT_FALSE(near.candidates().empty());
    EXPECT_EQ(stats.candidate_pairs, static_cast<std::int64_t>(near.candidates().size()));
    for (const SelfCollisionCandidates::Candidate& c : near.candidates()) {
        // Every candidate joins a vertex of one triangle to the other, and none is farther apart
        // than the thickness plus the slacks allow at rest.
        const SelfCollisionCandidates::FeatureVertices f =
            SelfCollisionCandidates::feature_vertices(c);
        EXPECT_NE(f.v[0] < 3, f.v[3] < 3);
        EXPECT_LT(c.distance, THICKNESS + 2.0 * 0.2 * THICKNESS);
        EXPECT_LT(SelfCollisionCandidates::bound(c, std::vector<double>(6, 0.0), 0.0), THICKNESS);
    }

    SelfCollisionCandidates far(TRIANGLES, 6, THICKNESS);
    far.prepare(two_triangles(1.0), still, 0.0, WINDOW, stats);
    EXPECT_TRUE(far.candidates().empty());
}

TEST(SelfCollisionCandidates, RenewsOnlyThePathsOfVerticesThatLeaveTheirSlack) {
    const std::vector<Vec3d> still(6, Vec3d{0.0, 0.0, 0.0});
    SelfCollisionCandidates candidates(TRIANGLES, 6, THICKNESS);
    SelfCollisionStats stats;
    std::vector<Vec3d> x = two_triangles(0.5 * THICKNESS);
    candidates.prepare(x, still, 0.0, WINDOW, stats);
    // At rest every vertex stays on its path: no broad phase.
    candidates.prepare(x, still, WINDOW, WINDOW, stats);
    EXPECT_EQ(stats.gathers, 1);
    EXPECT_EQ(stats.path_updates, 0);
    EXPECT_EQ(stats.new_paths, 0);
    // One vertex moves by more than its slack (0.2 thickness): only it gets a new path, by a
    // partial broad phase.
    x[4].x += 0.3 * THICKNESS;
    const Vec3d shift = candidates.shift_of(x);
    EXPECT_FALSE(candidates.within_path(x[4], shift, 2.0 * WINDOW, 4, 0.5 * THICKNESS));
    EXPECT_TRUE(candidates.within_path(x[3], shift, 2.0 * WINDOW, 3, 0.5 * THICKNESS));
    candidates.prepare(x, still, 2.0 * WINDOW, WINDOW, stats);
    EXPECT_EQ(stats.gathers, 1);
    EXPECT_EQ(stats.path_updates, 1);
    EXPECT_EQ(stats.new_paths, 1);
    EXPECT_EQ(candidates.deviation(x[4], candidates.shift_of(x), 2.0 * WINDOW, 4), 0.0);
    EXPECT_FALSE(candidates.candidates().empty());
}

}  // namespace
}  // namespace pliant::cloth
