// XPBDStepper with Offset Geometric Contact (xpbd_stepper.hpp, "With OGC contact";
// ogc_contact.hpp): the bounds keep colliding cloth intersection-free with no proximity pass, a
// sheet at rest detects rarely, and the results are bitwise the same for any thread count and
// after a saved state is loaded.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

// Two sheets 2 cm apart over a plane (the lower one at the thickness above it), the upper one
// thrown down at 2 m/s onto the lower one, with gravity; XPBD with OGC contact.
std::unique_ptr<ClothSolver> colliding_sheets(int n) {
    geometry::TriangleMeshD mesh = test::flat_sheet(n, 0.5, 0.005);
    const geometry::TriangleMeshD upper = test::flat_sheet(n, 0.5, 0.025);
    const auto offset = static_cast<std::int32_t>(mesh.positions.size());
    for (const Vec3d& p : upper.positions) {
        mesh.positions.push_back(p + Vec3d{0.013, 0.007, 0.0});
    }
    for (const geometry::Triangle& t : upper.triangles) {
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    auto solver = std::make_unique<ClothSolver>(mesh, ClothMaterial{});
    solver->add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    std::vector<Vec3d> velocities(mesh.positions.size());
    for (std::size_t v = static_cast<std::size_t>(offset); v < velocities.size(); ++v) {
        velocities[v] = {0.0, 0.0, -2.0};
    }
    solver->set_velocities(velocities);
    solver->enable_self_collision(true);
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

TEST(XPBDOgc, BitwiseIdenticalForOneAndTwoThreads) {
    const auto run = [&](int threads) {
        set_num_threads(threads);
        auto solver = colliding_sheets(12);
        for (int f = 0; f < 8; ++f) {
            solver->step(1.0 / 24.0, 12);
        }
        set_num_threads(0);
        return std::vector<Vec3d>(solver->positions().begin(), solver->positions().end());
    };
    EXPECT_EQ(run(1), run(2));
}

TEST(XPBDOgc, SavedStateContinuesBitForBit) {
    auto a = colliding_sheets(10);
    for (int f = 0; f < 4; ++f) {
        a->step(1.0 / 24.0, 12);
    }
    ByteWriter out;
    a->save_state(out);
    auto b = colliding_sheets(10);
    ByteReader in(out.bytes(), "state");
    b->load_state(in);
    for (int f = 0; f < 6; ++f) {
        a->step(1.0 / 24.0, 12);
        b->step(1.0 / 24.0, 12);
    }
    for (std::size_t v = 0; v < a->positions().size(); ++v) {
        ASSERT_EQ(a->positions()[v], b->positions()[v]) << v;
        ASSERT_EQ(a->velocities()[v], b->velocities()[v]) << v;
    }
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
