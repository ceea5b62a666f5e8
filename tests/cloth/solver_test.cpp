#include "pliant/cloth/solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

geometry::TriangleMeshD sheet(int n, double size, double z) {
    return test::flat_sheet(n, size, z);
}

double max_edge_strain(const ClothSolver& solver, const geometry::TriangleMeshD& rest) {
    double worst = 0.0;
    for (const geometry::Triangle& t : rest.triangles) {
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)]);
            const double rest_length = norm(rest.positions[a] - rest.positions[b]);
            const double length = norm(solver.positions()[a] - solver.positions()[b]);
            worst = std::max(worst, std::fabs(length / rest_length - 1.0));
        }
    }
    return worst;
}

TEST(ClothSolver, FreeFallFollowsTheSubstepIntegrator) {
    // No damping, nothing to hit: every vertex falls as symplectic Euler with step h predicts,
    // x(n h) = x0 + g h² n (n + 1) / 2, and the constraints stay satisfied.
    ClothMaterial material;
    material.damping = 0.0;
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 2.0);
    ClothSolver solver(mesh, material);
    const int substeps = 10;
    const int frames = 5;
    for (int f = 0; f < frames; ++f) {
        solver.step(0.04, substeps);
    }
    const double h = 0.04 / substeps;
    const double n = frames * substeps;
    const double expected = 2.0 - 9.81 * h * h * n * (n + 1.0) / 2.0;
    for (const Vec3d& p : solver.positions()) {
        EXPECT_NEAR(p.z, expected, 1e-9);
    }
    EXPECT_LT(max_edge_strain(solver, mesh), 1e-9);
}

TEST(ClothSolver, PinnedSheetHangsWithoutStretchingAndComesToRest) {
    // 1 m sheet pinned along one edge (y = +0.5), hanging for 3 s.
    const geometry::TriangleMeshD mesh = sheet(16, 1.0, 1.0);
    std::vector<std::int32_t> pinned;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.positions.size()); ++v) {
        if (mesh.positions[static_cast<std::size_t>(v)].y > 0.499) {
            pinned.push_back(v);
        }
    }
    ASSERT_EQ(pinned.size(), 17u);
    ClothMaterial material;
    material.damping = 5.0;
    ClothSolver solver(mesh, material, pinned);
    for (int f = 0; f < 72; ++f) {
        solver.step(1.0 / 24.0, 20);
    }
    for (const std::int32_t v : pinned) {
        EXPECT_EQ(solver.positions()[static_cast<std::size_t>(v)],
                  mesh.positions[static_cast<std::size_t>(v)]);
    }
    double lowest = std::numeric_limits<double>::infinity();
    double fastest = 0.0;
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        ASSERT_TRUE(std::isfinite(solver.positions()[v].z));
        lowest = std::min(lowest, solver.positions()[v].z);
        fastest = std::max(fastest, norm(solver.velocities()[v]));
    }
    EXPECT_LT(lowest, 0.1);    // it hangs down by about its length
    EXPECT_GT(lowest, -0.05);  // and not further
    EXPECT_LT(fastest, 0.05);  // at rest
    EXPECT_LT(max_edge_strain(solver, mesh), 0.02);
}

TEST(ClothSolver, DrapesOverASphereAndKeepsTheThickness) {
    // A 1.2 m sheet dropped 0.3 m onto a sphere of radius 0.3 m, then onto the ground; with
    // either bending model.
    for (const BendingModel bending : {BendingModel::dihedral, BendingModel::isometric}) {
        const geometry::TriangleMeshD mesh = sheet(24, 1.2, 0.6);
        ClothMaterial material;
        material.bending = bending;
        ClothSolver solver(mesh, material);
        const SphereObstacle sphere{{0.0, 0.0, 0.0}, 0.3};
        solver.add_obstacle(sphere);
        solver.add_obstacle(PlaneObstacle{{0.0, 0.0, -0.3}, {0.0, 0.0, 1.0}});
        ClothStepStats stats;
        for (int f = 0; f < 48; ++f) {
            stats = solver.step(1.0 / 24.0, 40);
        }
        EXPECT_GT(stats.obstacle_contacts, 0);
        const double margin = material.thickness * (1.0 - 1e-9);
        for (const Vec3d& p : solver.positions()) {
            EXPECT_GE(norm(p - sphere.center) - sphere.radius, margin);
            EXPECT_GE(p.z + 0.3, margin);
        }
        // The centre vertex rests on top of the sphere. (The symmetric balance there is unstable:
        // after 2 s the sheet has begun to slide off, the centre 0.12 m (dihedral) or 0.08 m
        // (isometric) from the top, 24 or 10 mm lower.)
        const Vec3d& centre = solver.positions()[mesh.positions.size() / 2];
        EXPECT_NEAR(centre.z, sphere.radius + material.thickness, 0.03);
        EXPECT_LT(std::hypot(centre.x, centre.y), 0.15);
        // The stretch chains (the default) keep every edge within 2 % of its length (1.2 %
        // measured; single edges, one sweep per substep: 7 % at these 40 substeps).
        EXPECT_LT(max_edge_strain(solver, mesh), 0.02);
    }
}

TEST(ClothSolver, BitwiseIdenticalForOneAndTwoThreads) {
    // With either stretch solver (stretch chains also below, at 100 × 100 quads, where each
    // family spans many packets).
    const geometry::TriangleMeshD mesh = sheet(20, 1.0, 0.5);
    for (const StretchSolver stretch_solver : {StretchSolver::edges, StretchSolver::chains}) {
        ClothMaterial material;
        material.stretch_solver = stretch_solver;
        const auto run = [&](int threads) {
            set_num_threads(threads);
            ClothSolver solver(mesh, material);
            solver.add_obstacle(SphereObstacle{{0.1, 0.0, 0.0}, 0.25});
            for (int f = 0; f < 12; ++f) {
                solver.step(1.0 / 24.0, 10);
            }
            set_num_threads(0);
            return std::vector<Vec3d>(solver.positions().begin(), solver.positions().end());
        };
        EXPECT_EQ(run(1), run(2));
    }
}

TEST(ClothSolver, IsometricBendingIsBitwiseIdenticalForOneAndTwoThreads) {
    // 100 × 100 quads: each bending colour spans several parallel chunks, and each family of the
    // stretch chains (the default) many packets.
    const geometry::TriangleMeshD mesh = sheet(100, 1.0, 0.5);
    ClothMaterial material;
    material.bending = BendingModel::isometric;
    material.stretch_solver = StretchSolver::chains;
    const auto run = [&](int threads) {
        set_num_threads(threads);
        ClothSolver solver(mesh, material);
        EXPECT_EQ(solver.num_isometric_bending_constraints(), solver.num_bending_constraints());
        EXPECT_GT(solver.num_stretch_chains(), 0u);
        solver.add_obstacle(SphereObstacle{{0.1, 0.0, 0.0}, 0.25});
        for (int f = 0; f < 6; ++f) {
            solver.step(1.0 / 24.0, 10);
        }
        set_num_threads(0);
        return std::vector<Vec3d>(solver.positions().begin(), solver.positions().end());
    };
    const std::vector<Vec3d> one = run(1);
    EXPECT_EQ(one, run(2));
    EXPECT_LT(one[mesh.positions.size() / 2].z, 0.5);  // it moved
}

TEST(ClothSolver, SetVelocitiesStartsABallisticMotion) {
    // No damping, no gravity, nothing to hit: a sheet given one velocity translates rigidly.
    ClothMaterial material;
    material.damping = 0.0;
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 2.0);
    ClothSolver solver(mesh, material);
    solver.set_gravity({0.0, 0.0, 0.0});
    const Vec3d velocity{0.5, -1.0, 2.0};
    solver.set_velocities(std::vector<Vec3d>(mesh.positions.size(), velocity));
    solver.step(0.1, 10);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3d expected = mesh.positions[v] + velocity * 0.1;
        EXPECT_NEAR(solver.positions()[v].x, expected.x, 1e-12);
        EXPECT_NEAR(solver.positions()[v].y, expected.y, 1e-12);
        EXPECT_NEAR(solver.positions()[v].z, expected.z, 1e-12);
    }
    EXPECT_THROW(solver.set_velocities(std::vector<Vec3d>(3, velocity)), InvalidInput);
    std::vector<Vec3d> bad(mesh.positions.size(), velocity);
    bad[2].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(solver.set_velocities(bad), InvalidInput);
}

TEST(ClothSolver, RejectsBadInput) {
    const geometry::TriangleMeshD mesh = sheet(2, 1.0, 0.0);
    ClothMaterial negative;
    negative.areal_density = -1.0;
    EXPECT_THROW(ClothSolver(mesh, negative), InvalidInput);
    ClothMaterial nan_thickness;
    nan_thickness.thickness = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ClothSolver(mesh, nan_thickness), InvalidInput);
    const std::vector<std::int32_t> bad_pin{100};
    EXPECT_THROW(ClothSolver(mesh, ClothMaterial{}, bad_pin), InvalidInput);
    geometry::TriangleMeshD nan_mesh = mesh;
    nan_mesh.positions[0].x = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ClothSolver(nan_mesh, ClothMaterial{}), InvalidInput);
    ClothSolver solver(mesh, ClothMaterial{});
    EXPECT_THROW(solver.step(0.0, 10), InvalidInput);
    EXPECT_THROW(solver.step(0.01, 0), InvalidInput);
    EXPECT_THROW(solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, -1.0}), InvalidInput);
}

TEST(ClothSolver, EverythingPinnedStaysPutAndHugeStepsStayFinite) {
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 0.0);
    std::vector<std::int32_t> all(mesh.positions.size());
    for (std::size_t v = 0; v < all.size(); ++v) {
        all[v] = static_cast<std::int32_t>(v);
    }
    ClothSolver pinned(mesh, ClothMaterial{}, all);
    pinned.step(10.0, 1);
    EXPECT_EQ(std::vector<Vec3d>(pinned.positions().begin(), pinned.positions().end()),
              mesh.positions);
    // One 10-second substep onto a sphere: no NaN.
    ClothSolver free(mesh, ClothMaterial{});
    free.add_obstacle(SphereObstacle{{0.0, 0.0, -1.0}, 0.5});
    free.step(10.0, 1);
    for (const Vec3d& p : free.positions()) {
        EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
}

// Self-collision with a thickness of more than 4 median edge lengths is refused (every triangle
// would be within reach of hundreds of others); 4 is accepted. A 20 × 20 grid of 10 cm: edges of
// 5 mm (sides) and 7.1 mm (diagonals), median 5 mm.
TEST(ClothSolver, ThicknessAboveFourEdgeLengthsIsRefused) {
    const geometry::TriangleMeshD mesh = sheet(20, 0.1, 0.0);
    ClothMaterial thick;
    thick.thickness = 0.0201;
    ClothSolver refused(mesh, thick);
    try {
        refused.enable_self_collision(true);
        ADD_FAILURE() << "a thickness of 4.02 edge lengths was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("4.0 times the median edge length (0.005 m)"),
                  std::string::npos)
            << e.what();
    }
    ClothMaterial limit;
    limit.thickness = 0.0199;
    ClothSolver accepted(mesh, limit);
    EXPECT_NO_THROW(accepted.enable_self_collision(true));
    EXPECT_NO_THROW(refused.enable_self_collision(false));  // without it, any thickness
}

// A horizontal sheet falling through still air reaches the terminal speed of a flat plate,
// ½ ρ C_d A v² = m g, so v = sqrt(2 ρ_A g / (ρ C_d)) with ρ_A the areal density (m / A):
// sqrt(2 · 0.15 · 9.81 / 1.2) = 1.566 m/s for the default material. Wind blowing upward at that
// speed holds it still.
TEST(ClothSolver, AirDragGivesTheFlatPlateTerminalSpeed) {
    const geometry::TriangleMeshD mesh = sheet(8, 1.0, 0.0);
    const double expected = std::sqrt(2.0 * 0.15 * 9.81 / 1.2);
    Air air;
    air.density = 1.2;
    air.drag_coefficient = 1.0;
    ClothSolver falling(mesh, ClothMaterial{});
    falling.set_air(air);
    for (int f = 0; f < 48; ++f) {
        falling.step(1.0 / 24.0, 20);
    }
    // Damping (0.5/s) slows it a little more: v = terminal speed of drag + damping.
    // Solve ½ ρ C_d v² / ρ_A + damping v = g for v.
    const double a = 0.5 * 1.2 / 0.15;
    const double with_damping = (-0.5 + std::sqrt(0.25 + 4.0 * a * 9.81)) / (2.0 * a);
    for (const Vec3d& v : falling.velocities()) {
        EXPECT_NEAR(-v.z, with_damping, 1e-3 * with_damping);
    }
    EXPECT_LT(with_damping, expected);
    EXPECT_GT(with_damping, 0.9 * expected);

    ClothMaterial no_damping;
    no_damping.damping = 0.0;
    ClothSolver hovering(mesh, no_damping);
    air.wind = {0.0, 0.0, expected};
    hovering.set_air(air);
    for (int f = 0; f < 24; ++f) {
        hovering.step(1.0 / 24.0, 20);
    }
    for (const Vec3d& v : hovering.velocities()) {
        EXPECT_NEAR(v.z, 0.0, 1e-9);
    }
    air.gust_period = 0.0;
    EXPECT_THROW(hovering.set_air(air), InvalidInput);

    // A gale of 1000 m/s in air a thousand times denser than air: explicit drag would reverse the
    // sheet's velocity and blow up; capped, the sheet at most reaches the wind's speed.
    Air gale;
    gale.density = 1200.0;
    gale.wind = {0.0, 0.0, 1000.0};
    ClothSolver blown(mesh, no_damping);
    blown.set_gravity({0.0, 0.0, 0.0});
    blown.set_air(gale);
    for (int f = 0; f < 4; ++f) {
        blown.step(1.0 / 24.0, 5);
    }
    for (const Vec3d& v : blown.velocities()) {
        EXPECT_TRUE(is_finite(v));
        EXPECT_GT(v.z, 0.0);
        EXPECT_LE(v.z, 1000.0 * (1.0 + 1e-9));
    }
}

// Pins that turn about z follow the keyframed path exactly (two turns in two seconds).
TEST(ClothSolver, MovingPinsFollowTheirMotion) {
    const geometry::TriangleMeshD mesh = sheet(6, 1.0, 1.0);
    ClothSolver solver(mesh, ClothMaterial{});
    Motion motion;
    motion.pivot = {0.0, 0.0, 1.0};
    motion.keyframes = {Keyframe{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                        Keyframe{2.0, {0.0, 0.0, 0.5}, {0.0, 0.0, 720.0}}};
    const std::vector<std::int32_t> corner{0};
    solver.add_moving_pins(corner, motion);
    const Vec3d start = mesh.positions[0];
    for (int f = 1; f <= 36; ++f) {
        solver.step(1.0 / 24.0, 5);
        const double t = f / 24.0;
        const double angle = 2.0 * std::numbers::pi * t;  // 720° over 2 s
        const Vec3d expected{std::cos(angle) * start.x - std::sin(angle) * start.y,
                             std::sin(angle) * start.x + std::cos(angle) * start.y,
                             start.z + 0.25 * t};
        EXPECT_NEAR(norm(solver.positions()[0] - expected), 0.0, 1e-12) << "frame " << f;
    }
    EXPECT_EQ(solver.inverse_masses()[0], 0.0);
    Motion backwards = motion;
    backwards.keyframes[1].time = -1.0;
    EXPECT_THROW(solver.add_moving_pins(corner, backwards), InvalidInput);
    const std::vector<std::int32_t> out_of_range{1000};
    EXPECT_THROW(solver.add_moving_pins(out_of_range, motion), InvalidInput);
}

// A grabbed vertex follows the straight line to its target over one step and stays there; the
// sheet follows it; releasing gives the vertex its mass back; grabbing a pinned vertex moves it
// and leaves it pinned where it was left.
TEST(ClothSolver, GrabMovesAVertexAndReleaseRestoresIt) {
    const geometry::TriangleMeshD mesh = sheet(8, 1.0, 1.0);
    ClothMaterial material;
    material.damping = 2.0;
    const std::vector<std::int32_t> pinned{80};  // the corner (+x, +y)
    ClothSolver solver(mesh, material, pinned);
    solver.set_gravity({0.0, 0.0, 0.0});
    EXPECT_EQ(solver.grabbed_vertex(), -1);
    const std::int32_t centre = 40;
    const double mass_inverse = solver.inverse_masses()[40];
    ASSERT_GT(mass_inverse, 0.0);
    const Vec3d start = mesh.positions[40];
    const Vec3d target = start + Vec3d{0.0, 0.0, 0.3};
    solver.grab(centre, target);
    EXPECT_EQ(solver.grabbed_vertex(), centre);
    EXPECT_EQ(solver.inverse_masses()[40], 0.0);
    solver.step(1.0 / 24.0, 10);
    EXPECT_NEAR(norm(solver.positions()[40] - target), 0.0, 1e-12);
    // The path's velocity: 0.3 m in 1/24 s.
    EXPECT_NEAR(solver.velocities()[40].z, 0.3 * 24.0 * (1.0 - 2.0 / 240.0), 1e-9);
    for (int f = 0; f < 12; ++f) {
        solver.step(1.0 / 24.0, 10);
    }
    EXPECT_NEAR(norm(solver.positions()[40] - target), 0.0, 1e-12);
    EXPECT_GT(solver.positions()[31].z, 1.05);  // a neighbour was pulled up
    // Moving the target; then release.
    const Vec3d second = target + Vec3d{0.1, 0.0, 0.0};
    solver.grab(centre, second);
    solver.step(1.0 / 24.0, 10);
    EXPECT_NEAR(norm(solver.positions()[40] - second), 0.0, 1e-12);
    solver.release_grab();
    EXPECT_EQ(solver.grabbed_vertex(), -1);
    EXPECT_EQ(solver.inverse_masses()[40], mass_inverse);
    solver.step(1.0 / 24.0, 10);
    EXPECT_GT(norm(solver.positions()[40] - second), 1e-4);  // free again: the sheet pulls it
    solver.release_grab();                                   // no grab: no-op

    // A pinned vertex: moved by the grab, pinned again where it was left.
    const Vec3d moved = mesh.positions[80] + Vec3d{0.0, 0.2, 0.0};
    solver.grab(80, moved);
    solver.step(1.0 / 24.0, 10);
    solver.grab(40, solver.positions()[40]);  // another vertex: releases 80
    EXPECT_EQ(solver.inverse_masses()[80], 0.0);
    solver.release_grab();
    for (int f = 0; f < 5; ++f) {
        solver.step(1.0 / 24.0, 10);
    }
    EXPECT_NEAR(norm(solver.positions()[80] - moved), 0.0, 1e-12);

    EXPECT_THROW(solver.grab(81, target), InvalidInput);
    EXPECT_THROW(solver.grab(-1, target), InvalidInput);
    EXPECT_THROW(solver.grab(3, {0.0, std::numeric_limits<double>::quiet_NaN(), 0.0}),
                 InvalidInput);
}

// A sheet resting on a box that slides sideways at 0.2 m/s is carried along by friction
// (static friction holds: the box's acceleration is zero after the start), and left behind
// without friction. Boxes that would rotate are refused.
TEST(ClothSolver, MovingObstacleCarriesTheClothByFriction) {
    const auto run = [](double friction) {
        const geometry::TriangleMeshD mesh = sheet(8, 0.4, 0.005);
        ClothMaterial material;
        material.static_friction = friction;
        material.kinetic_friction = friction;
        ClothSolver solver(mesh, material);
        Motion slide;
        slide.keyframes = {Keyframe{0.0, {0.0, 0.0, 0.0}, {}}, Keyframe{10.0, {2.0, 0.0, 0.0}, {}}};
        solver.add_obstacle(BoxObstacle{{-1.0, -1.0, -1.0}, {1.0, 1.0, 0.0}}, slide);
        for (int f = 0; f < 24; ++f) {
            solver.step(1.0 / 24.0, 10);
        }
        double mean_x = 0.0;
        for (const Vec3d& p : solver.positions()) {
            mean_x += p.x;
        }
        return mean_x / static_cast<double>(solver.positions().size());
    };
    EXPECT_NEAR(run(0.5), 0.2, 0.02);  // carried 0.2 m in one second
    EXPECT_NEAR(run(0.0), 0.0, 1e-9);  // frictionless: stays
    ClothSolver solver(sheet(2, 1.0, 0.0), ClothMaterial{});
    Motion spin;
    spin.keyframes = {Keyframe{0.0, {}, {0.0, 0.0, 10.0}}};
    EXPECT_THROW(solver.add_obstacle(BoxObstacle{}, spin), InvalidInput);
}

// A sheet dropped on a tessellated sphere (a mesh obstacle) rests on it like on the analytic
// sphere: every vertex at least thickness from the mesh, i.e. beyond r·cos(π/segments) +
// thickness from the centre, and its edges hang as low as over the analytic sphere. A mesh box
// sliding sideways carries the cloth by friction, like the analytic box.
TEST(ClothSolver, MeshObstaclesHoldAndCarryTheCloth) {
    const double radius = 0.3;
    const int segments = 48;
    // Single-edge stretch: the comparison's 1 cm was measured with it (the sheet still swings
    // after 1 s; with chains the two lowest points differ by 1.3 cm).
    ClothMaterial material;
    material.stretch_solver = StretchSolver::edges;
    ClothSolver draped(sheet(16, 0.8, 0.4), material);
    draped.add_mesh_obstacle(std::make_shared<const MeshObstacle>(
        geometry::make_uv_sphere({0.0, 0.0, 0.0}, radius, segments)));
    for (int f = 0; f < 24; ++f) {
        draped.step(1.0 / 24.0, 20);
    }
    const double inscribed = radius * std::cos(std::numbers::pi / segments);
    double lowest = 1.0;
    for (const Vec3d& p : draped.positions()) {
        EXPECT_GT(norm(p), inscribed + 0.9 * ClothMaterial{}.thickness);
        lowest = std::min(lowest, p.z);
    }
    // It draped over the sides as over the analytic sphere.
    ClothSolver analytic(sheet(16, 0.8, 0.4), material);
    analytic.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, radius});
    for (int f = 0; f < 24; ++f) {
        analytic.step(1.0 / 24.0, 20);
    }
    double analytic_lowest = 1.0;
    for (const Vec3d& p : analytic.positions()) {
        analytic_lowest = std::min(analytic_lowest, p.z);
    }
    EXPECT_LT(lowest, 0.2);
    EXPECT_NEAR(lowest, analytic_lowest, 0.01);

    ClothMaterial rough;
    rough.static_friction = 0.5;
    rough.kinetic_friction = 0.5;
    ClothSolver carried(sheet(8, 0.4, 0.005), rough);
    Motion slide;
    slide.keyframes = {Keyframe{0.0, {0.0, 0.0, 0.0}, {}}, Keyframe{10.0, {2.0, 0.0, 0.0}, {}}};
    carried.add_mesh_obstacle(std::make_shared<const MeshObstacle>(
                                  geometry::make_box({-1.0, -1.0, -1.0}, {1.0, 1.0, 0.0})),
                              slide);
    for (int f = 0; f < 24; ++f) {
        carried.step(1.0 / 24.0, 10);
    }
    double mean_x = 0.0;
    for (const Vec3d& p : carried.positions()) {
        mean_x += p.x;
    }
    EXPECT_NEAR(mean_x / static_cast<double>(carried.positions().size()), 0.2, 0.02);
    EXPECT_THROW(carried.add_mesh_obstacle(nullptr), InvalidInput);
}

// Cloth given inside an obstacle comes out without being thrown: the push out of a penetration
// a substep begins with is not turned into velocity. A sheet 0.3 m deep behind a plane (whose
// free side is below) and a sheet 4 mm under a mesh ground both come out, and then move as
// gravity has them (before: thrown at 288 m/s and 8.6 m/s).
TEST(ClothSolver, ClothGivenInsideAnObstacleComesOutWithoutBeingThrown) {
    const double h = 1.0 / 24.0 / 20.0;
    const auto fastest = [](const ClothSolver& solver) {
        double speed = 0.0;
        for (const Vec3d& v : solver.velocities()) {
            speed = std::max(speed, norm(v));
        }
        return speed;
    };
    ClothSolver behind(sheet(8, 1.0, 0.3), ClothMaterial{});
    behind.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, -1.0}});
    behind.step(1.0 / 24.0, 20);
    for (const Vec3d& p : behind.positions()) {
        ASSERT_LE(p.z, -ClothMaterial{}.thickness + 1e-12);
    }
    // Out in the first substep, and falling freely all along (damping takes a little).
    EXPECT_LE(fastest(behind), 9.81 * 20.0 * h);
    EXPECT_GT(fastest(behind), 0.95 * 9.81 * 20.0 * h);

    geometry::TriangleMeshD ground;
    ground.positions = {{-1.0, -1.0, 0.0}, {1.0, -1.0, 0.0}, {1.0, 1.0, 0.0}, {-1.0, 1.0, 0.0}};
    ground.triangles = {{0, 1, 2}, {0, 2, 3}};
    ClothSolver under(sheet(8, 0.5, -0.004), ClothMaterial{});
    under.add_mesh_obstacle(std::make_shared<const MeshObstacle>(ground));
    under.step(1.0 / 24.0, 20);
    for (const Vec3d& p : under.positions()) {
        ASSERT_NEAR(p.z, ClothMaterial{}.thickness, 1e-9);  // resting on the ground
    }
    EXPECT_LT(fastest(under), 0.01);
}

// A small sheet lying on a pinned sheet, with gravity tilted by atan(0.2) = 11.3°: cloth-cloth
// static friction 0.3 > 0.2 holds it, without friction it slides off.
TEST(ClothSolver, SelfFrictionHoldsASheetOnATiltedSheet) {
    const auto run = [](double friction) {
        geometry::TriangleMeshD mesh = sheet(16, 0.6, 0.0);
        const geometry::TriangleMeshD top = sheet(6, 0.2, 0.005);
        const auto offset = static_cast<std::int32_t>(mesh.positions.size());
        std::vector<std::int32_t> pinned;
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
            pinned.push_back(static_cast<std::int32_t>(v));
        }
        mesh.positions.insert(mesh.positions.end(), top.positions.begin(), top.positions.end());
        for (const geometry::Triangle& t : top.triangles) {
            mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
        ClothMaterial material;
        material.self_static_friction = friction;
        material.self_kinetic_friction = friction;
        ClothSolver solver(mesh, material, pinned);
        solver.set_gravity({-0.2 * 9.81, 0.0, -9.81});
        solver.enable_self_collision(true);
        for (int f = 0; f < 12; ++f) {
            solver.step(1.0 / 24.0, 20);
        }
        double mean_x = 0.0;
        for (std::size_t v = static_cast<std::size_t>(offset); v < mesh.positions.size(); ++v) {
            mean_x += solver.positions()[v].x;
        }
        return mean_x / static_cast<double>(top.positions.size());
    };
    EXPECT_GT(run(0.3), -0.005);  // held (starts at 0)
    EXPECT_LT(run(0.0), -0.1);    // ½ · 1.96 m/s² · (0.5 s)² = 0.245 m
}

}  // namespace
}  // namespace pliant::cloth
