// XPBDStepper with Offset Geometric Contact (xpbd_stepper.hpp, "With OGC contact";
// ogc_contact.hpp): the bounds keep colliding cloth intersection-free with no proximity pass, a
// sheet at rest detects rarely, and the results are bitwise the same for any thread count and
// after a saved state is loaded.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "cloth/ogc_moving_pins.hpp"
#include "cloth/solver_checks.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

// colliding_sheets() with XPBD and OGC contact.
std::unique_ptr<ClothSolver> colliding_sheets(int n) {
    auto solver = test::colliding_sheets(n);
    solver->use_xpbd_ogc(OgcOptions{});
    return solver;
}

TEST(XPBDOgc, SheetsPushedTogetherNeverIntersect) {
    auto solver = colliding_sheets(16);
    ASSERT_NE(solver->stepper().ogc(), nullptr);
    std::int64_t near = 0;
    for (int f = 0; f < 12; ++f) {
        const ClothStepStats stats = solver->step(1.0 / 24.0, 16);
        ASSERT_TRUE(stats.has_ogc);
        near = std::max(near, stats.ogc_pairs);
        // The bounds alone kept them apart: the CCD audit put nothing back, and no pair of
        // triangles intersects.
        EXPECT_EQ(stats.self.reverted_vertices, 0) << "frame " << f;
        EXPECT_EQ(stats.self.contacts, 0) << "frame " << f;  // no proximity projection
        ASSERT_EQ(collision::count_intersecting_pairs(solver->positions(), solver->triangles()), 0)
            << "frame " << f;
    }
    EXPECT_GT(near, 0);  // the upper one rests on the lower one, within the query radius
    // Resting: the upper sheet lies about a contact radius above the lower one.
    const std::size_t top = solver->positions().size() - 1;
    EXPECT_GT(solver->positions()[top].z, 0.005 + 0.5 * 0.005);
}

TEST(XPBDOgc, SettledSheetDetectsRarely) {
    ClothSolver solver(test::flat_sheet(16, 1.0, 0.02), ClothMaterial{});
    solver.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    solver.enable_self_collision(true);
    solver.use_xpbd_ogc(OgcOptions{});
    const int substeps = 20;
    std::int64_t early = 0;
    std::int64_t late = 0;
    for (int f = 0; f < 48; ++f) {
        const ClothStepStats stats = solver.step(1.0 / 24.0, substeps);
        (f < 24 ? early : late) += stats.ogc_detections;
    }
    // Resting on the plane for the last 24 frames: at most about one detection per frame, not
    // one per substep.
    EXPECT_LE(late, 24);
    EXPECT_GE(early, 1);
}

// Pins that move the cloth faster than the ball lets a free vertex move in a substep, beside
// too few neighbours for the share rule: detections where the pins leave their sets and catch-up
// detections for the neighbours their balls hold back keep the sheet as little stretched as the
// proximity path keeps it, and free of intersections.
TEST(XPBDOgc, FollowsPinsFasterThanItsBall) {
    auto proximity = test::sheet_on_turning_pins([](ClothSolver&) {});
    const test::MovingPinsRun reference = test::run_moving_pins(*proximity, 24, 16);
    auto solver =
        test::sheet_on_turning_pins([](ClothSolver& s) { s.use_xpbd_ogc(test::small_ball_ogc()); });
    ASSERT_NE(solver->stepper().ogc(), nullptr);
    const test::MovingPinsRun run = test::run_moving_pins(*solver, 24, 16);
    test::expect_follows_pins(reference, run, 24);
}

TEST(XPBDOgc, MovingPinsBitwiseIdenticalForOneAndTwoThreads) {
    const auto make = [] {
        return test::sheet_on_turning_pins(
            [](ClothSolver& s) { s.use_xpbd_ogc(test::small_ball_ogc()); });
    };
    EXPECT_EQ(test::positions_after_8_frames(make, 1, 8),
              test::positions_after_8_frames(make, 2, 8));
}

TEST(XPBDOgc, BitwiseIdenticalForOneAndTwoThreads) {
    const auto make = [] {
        return colliding_sheets(12);
    };
    EXPECT_EQ(test::positions_after_8_frames(make, 1, 12),
              test::positions_after_8_frames(make, 2, 12));
}

TEST(XPBDOgc, SavedStateContinuesBitForBit) {
    test::expect_saved_state_continues_bit_for_bit([] { return colliding_sheets(10); }, 4, 12);
}

// colliding_sheets() with the wide query radius (OgcOptions::wide_query_factor 2.5).
std::unique_ptr<ClothSolver> colliding_sheets_wide(int n) {
    auto solver = test::colliding_sheets(n);
    OgcOptions options;
    options.wide_query_factor = 2.5;
    solver->use_xpbd_ogc(options);
    return solver;
}

// The upper sheet lands at 2 m/s, 7 mm per substep against a 2.5 mm ball: the truncations ask
// for a detection every substep or two, so the wide radius takes over; with its 3.75 mm ball
// the impact needs fewer detections, and the sheets stay apart.
TEST(XPBDOgc, WideRadiusTakesTheImpactWithFewerDetections) {
    const auto run = [](std::unique_ptr<ClothSolver> solver, std::int64_t& wide) {
        std::int64_t detections = 0;
        wide = 0;
        for (int f = 0; f < 6; ++f) {
            const ClothStepStats stats = solver->step(1.0 / 24.0, 12);
            detections += stats.ogc_detections;
            wide += stats.ogc_wide_detections;
            EXPECT_EQ(stats.self.reverted_vertices, 0) << "frame " << f;
            EXPECT_EQ(collision::count_intersecting_pairs(solver->positions(), solver->triangles()),
                      0)
                << "frame " << f;
        }
        return detections;
    };
    std::int64_t wide_off = 0;
    std::int64_t wide_on = 0;
    const std::int64_t base = run(colliding_sheets(16), wide_off);
    const std::int64_t wide = run(colliding_sheets_wide(16), wide_on);
    EXPECT_EQ(wide_off, 0);
    EXPECT_GT(wide_on, 0);
    EXPECT_LT(wide, base);
}

TEST(XPBDOgc, WideRadiusBitwiseIdenticalForOneAndTwoThreads) {
    const auto make = [] {
        return colliding_sheets_wide(12);
    };
    EXPECT_EQ(test::positions_after_8_frames(make, 1, 12),
              test::positions_after_8_frames(make, 2, 12));
}

TEST(XPBDOgc, WideRadiusSavedStateContinuesBitForBit) {
    test::expect_saved_state_continues_bit_for_bit([] { return colliding_sheets_wide(10); }, 1, 12);
}

// Choosing the contact does not switch self-collision on: a scene with "self_collision": false
// and "contact": "ogc" has no self-contact at all (the sheets fall through each other).
TEST(XPBDOgc, ContactChoiceKeepsSelfCollisionOff) {
    auto solver = test::colliding_sheets(8);
    solver->enable_self_collision(false);
    solver->use_xpbd_ogc(OgcOptions{});
    EXPECT_FALSE(solver->stepper().has_self_collision());
    EXPECT_EQ(solver->stepper().ogc(), nullptr);
    EXPECT_FALSE(solver->step(1.0 / 24.0, 4).has_ogc);
    solver->enable_self_collision(true);
    EXPECT_NE(solver->stepper().ogc(), nullptr);
}

TEST(XPBDOgc, RejectsBadOptionsAndAStateWithoutOgc) {
    ClothSolver solver(test::flat_sheet(6, 1.0, 0.02), ClothMaterial{});
    solver.enable_self_collision(true);
    OgcOptions bad;
    bad.bound_share = 0.5;
    EXPECT_THROW(solver.use_xpbd_ogc(bad), InvalidInput);
    EXPECT_EQ(solver.stepper().ogc(), nullptr);
    // A state saved with the proximity path does not load into a stepper with OGC.
    ByteWriter out;
    solver.save_state(out);
    solver.use_xpbd_ogc(OgcOptions{});
    ByteReader in(out.bytes(), "state");
    EXPECT_THROW(solver.load_state(in), InvalidInput);
}

}  // namespace
}  // namespace pliant::cloth
