#include "pliant/cloth/xpbd_stepper.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

geometry::TriangleMeshD sheet(int n, double size, double z) {
    return test::flat_sheet(n, size, z);
}

TEST(XPBDStepper, FreeFallOfAModelFollowsTheSubstepIntegrator) {
    ClothMaterial material;
    material.damping = 0.0;
    ClothModel model(sheet(4, 1.0, 2.0), material);
    XPBDStepper stepper(model);
    EXPECT_EQ(stepper.num_stretch_constraints(), model.topology().num_edges());
    const int substeps = 10;
    const int frames = 5;
    for (int f = 0; f < frames; ++f) {
        stepper.step(model, 0.04, substeps);
    }
    EXPECT_DOUBLE_EQ(model.time(), 0.2);
    const double h = 0.04 / substeps;
    const double n = frames * substeps;
    const double expected = 2.0 - 9.81 * h * h * n * (n + 1.0) / 2.0;
    for (const Vec3d& p : model.positions()) {
        EXPECT_NEAR(p.z, expected, 1e-9);
    }
}

TEST(XPBDStepper, ModelAndStepperGiveTheSolversBits) {
    // ClothSolver is a model and a stepper: driving the two parts directly, with self-collision,
    // an obstacle, a grab and positions replaced between steps, gives the same bits.
    const geometry::TriangleMeshD mesh = sheet(16, 1.0, 0.3);
    ClothSolver solver(mesh, ClothMaterial{});
    ClothModel model(mesh, ClothMaterial{});
    XPBDStepper stepper(model);
    solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.25});
    model.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.25});
    solver.enable_self_collision(true);
    stepper.enable_self_collision(model, true);
    EXPECT_TRUE(stepper.has_self_collision());
    for (int f = 0; f < 8; ++f) {
        if (f == 2) {
            solver.grab(0, {-0.5, -0.5, 0.5});
            model.grab(0, {-0.5, -0.5, 0.5});
        }
        if (f == 5) {
            solver.release_grab();
            model.release_grab();
            std::vector<Vec3d> x(model.positions().begin(), model.positions().end());
            solver.set_positions(x);
            model.set_positions(x);
        }
        const ClothStepStats a = solver.step(1.0 / 24.0, 8);
        const ClothStepStats b = stepper.step(model, 1.0 / 24.0, 8);
        EXPECT_EQ(a.obstacle_contacts, b.obstacle_contacts);
        EXPECT_EQ(a.self.contacts, b.self.contacts);
        EXPECT_EQ(a.self.gathers, b.self.gathers);
    }
    ASSERT_EQ(solver.positions().size(), model.positions().size());
    for (std::size_t v = 0; v < model.positions().size(); ++v) {
        ASSERT_EQ(solver.positions()[v], model.positions()[v]) << "vertex " << v;
        ASSERT_EQ(solver.velocities()[v], model.velocities()[v]) << "vertex " << v;
    }
    EXPECT_EQ(&solver.model().positions()[0], &solver.positions()[0]);
    EXPECT_EQ(solver.stepper().num_stretch_chains(), solver.num_stretch_chains());
}

TEST(XPBDStepper, RejectsAModelOfAnotherSize) {
    const ClothModel small(sheet(2, 1.0, 0.0), ClothMaterial{});
    ClothModel large(sheet(3, 1.0, 0.0), ClothMaterial{});
    XPBDStepper stepper(small);
    try {
        stepper.step(large, 0.01, 1);
        FAIL() << "stepped a model of another size";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("the model has 16 vertices and 18 triangles, the "
                                             "stepper was built for 9 and 8"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_EQ(large.time(), 0.0);
}

}  // namespace
}  // namespace pliant::cloth
