#include "pliant/cloth/ccd_fail_safe.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "pliant/collision/intersecting_pairs.hpp"

namespace pliant::cloth {
namespace {

const std::vector<geometry::Triangle> TRIANGLES{{0, 1, 2}, {3, 4, 5}};
const std::vector<Vec3d> START{{0, 0, 0},       {1, 0, 0},       {0, 1, 0},
                               {0.2, 0.2, 0.5}, {0.6, 0.2, 0.5}, {0.2, 0.6, 0.5}};

TEST(CCDFailSafe, PutsBackOnlyTheVerticesOfPairsThatMayTouch) {
    // The top triangle moves straight through the bottom one over the window: its vertices and
    // the bottom's go back to their start with zero velocity, and the end is intersection-free.
    std::vector<Vec3d> end = START;
    for (int v = 3; v < 6; ++v) {
        end[static_cast<std::size_t>(v)].z = -0.5;
    }
    std::vector<Vec3d> velocities(6, Vec3d{0.0, 0.0, -12.0});
    SelfCollisionCandidates candidates(TRIANGLES, 6, 0.01);
    CCDFailSafe fail_safe;
    SelfCollisionStats stats;
    fail_safe.enforce(candidates, START, end, velocities, 0.0, 1.0 / 12.0, stats);
    EXPECT_GT(stats.ccd_hits, 0);
    EXPECT_GE(stats.enforce_rounds, 1);
    EXPECT_EQ(collision::count_intersecting_pairs(end, TRIANGLES), 0);
    for (int v = 3; v < 6; ++v) {
        EXPECT_EQ(end[static_cast<std::size_t>(v)], START[static_cast<std::size_t>(v)]);
        EXPECT_EQ(velocities[static_cast<std::size_t>(v)], (Vec3d{0.0, 0.0, 0.0}));
        // Escaped (no paths yet): it needs a path at the next prepare().
        EXPECT_TRUE(candidates.needs_path(static_cast<std::size_t>(v)));
    }

    // A motion that stays clear (the top triangle slides sideways, 0.5 m up): nothing moves back.
    std::vector<Vec3d> slide = START;
    for (int v = 3; v < 6; ++v) {
        slide[static_cast<std::size_t>(v)].x += 0.3;
    }
    const std::vector<Vec3d> expected = slide;
    std::vector<Vec3d> sliding(6, Vec3d{3.6, 0.0, 0.0});
    SelfCollisionStats clear;
    fail_safe.enforce(candidates, START, slide, sliding, 0.0, 1.0 / 12.0, clear);
    EXPECT_EQ(clear.ccd_hits, 0);
    EXPECT_EQ(clear.reverted_vertices, 0);
    EXPECT_EQ(slide, expected);
}

}  // namespace
}  // namespace pliant::cloth
