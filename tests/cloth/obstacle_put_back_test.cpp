// ObstaclePutBack (obstacle_put_back.hpp): cloth triangles a pass left in an obstacle go to a
// fallback clear of it, checked with count_obstacle_intersections (exact) and against the
// fallback's own formula: the substep's start turned with a rigidly moving obstacle, or the
// positions before a push.
#include "pliant/cloth/obstacle_put_back.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/obstacle_intersections.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

// A 20 cm × 20 cm sheet standing in the plane x = 0.26, 1 cm outside the +x face of a box
// 0.5 m × 0.5 m × 0.4 m on z = 0 that turns about z, 10° per 0.1 s.
ClothModel sheet_beside_a_turning_box() {
    geometry::TriangleMeshD sheet = test::flat_sheet(8, 0.2, 0.0);
    for (Vec3d& p : sheet.positions) {
        p = Vec3d{0.26, p.x, 0.2 + p.y};  // the grid's x → y, y → z
    }
    ClothModel model(sheet, ClothMaterial{});
    Motion turning;
    turning.keyframes = {Keyframe{0.0, {}, {}}, Keyframe{1.0, {}, {0.0, 0.0, 100.0}}};
    model.add_mesh_obstacle(std::make_shared<const MeshObstacle>(
                                geometry::make_box({-0.25, -0.25, 0.0}, {0.25, 0.25, 0.4})),
                            turning);
    return model;
}

TEST(ObstaclePutBack, TrianglesATurningBoxEnteredAreCarriedOutWithIt) {
    std::vector<Vec3d> one_thread;
    for (const int threads : {1, 2}) {
        set_num_threads(threads);
        ClothModel model = sheet_beside_a_turning_box();
        EXPECT_EQ(count_obstacle_intersections(model), 0);
        const std::vector<Vec3d> start(model.positions().begin(), model.positions().end());
        // The box turns 10° under the sheet, which a pass left where it was: the box's corner
        // at y < 0 comes out through it.
        model.begin_step(0.1);
        model.move_obstacles(0.1);
        const std::int64_t entered = count_obstacle_intersections(model);
        EXPECT_GT(entered, 0);
        // Every vertex counts as moved by the pass (changed_from differs everywhere).
        std::vector<Vec3d> before(start);
        for (Vec3d& p : before) {
            p.x += 1.0;
        }
        ObstaclePutBack put_back;
        put_back.seed(model.positions(), before);
        const std::int64_t moved = put_back.run(model, start, ObstaclePutBack::Fallback::carried);
        EXPECT_EQ(count_obstacle_intersections(model), 0) << threads << " threads";
        EXPECT_GT(moved, 0);
        EXPECT_EQ(put_back.stuck(), 0);
        EXPECT_EQ(static_cast<std::size_t>(moved), put_back.moved().size());
        // The moved vertices are where the 10° turn about z takes their start; the others stay.
        const Pose& pose = model.mesh_obstacles()[0].state.pose;
        const Pose& previous = model.mesh_obstacles()[0].state.previous_pose;
        std::vector<bool> is_moved(start.size(), false);
        for (const std::int32_t v : put_back.moved()) {
            is_moved[static_cast<std::size_t>(v)] = true;
        }
        int on_the_far_side = 0;
        for (std::size_t v = 0; v < start.size(); ++v) {
            const Vec3d& x = model.positions()[v];
            if (is_moved[v]) {
                const Vec3d turned = pose.apply(previous.apply_inverse(start[v]));
                EXPECT_NEAR(x.x, turned.x, 1e-12);
                EXPECT_NEAR(x.y, turned.y, 1e-12);
                EXPECT_NEAR(x.z, turned.z, 1e-12);
            } else {
                EXPECT_EQ(x, start[v]);
                on_the_far_side += start[v].y > 0.05 ? 1 : 0;
            }
        }
        // The half of the sheet the corner does not reach is left alone.
        EXPECT_GT(on_the_far_side, 9);
        // The same bits on 1 and 2 threads.
        if (threads == 1) {
            one_thread.assign(model.positions().begin(), model.positions().end());
        } else {
            EXPECT_EQ(std::memcmp(one_thread.data(), model.positions().data(),
                                  one_thread.size() * sizeof(Vec3d)),
                      0);
        }
    }
    set_num_threads(0);
}

// A sheet 2 cm above a sphere; a push takes one vertex into it.
TEST(ObstaclePutBack, APushIntoAnObstacleIsUndoneAndOthersStay) {
    ClothModel model(test::flat_sheet(4, 0.2, 0.12), ClothMaterial{});
    model.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.1});
    const std::vector<Vec3d> before(model.positions().begin(), model.positions().end());
    const std::span<Vec3d> x = model.mutable_positions();
    // Vertex 12 is the sheet's centre, vertex 0 a corner.
    ASSERT_EQ(x[12], (Vec3d{0.0, 0.0, 0.12}));
    x[12].z = 0.05;  // into the sphere
    x[0].z += 0.01;  // a push that meets nothing
    EXPECT_GT(count_obstacle_intersections(model), 0);
    ObstaclePutBack put_back;
    put_back.seed(model.positions(), before);
    EXPECT_EQ(put_back.run(model, before, ObstaclePutBack::Fallback::reference), 1);
    ASSERT_EQ(put_back.moved().size(), 1U);
    EXPECT_EQ(put_back.moved()[0], 12);
    EXPECT_EQ(model.positions()[12], before[12]);
    EXPECT_EQ(model.positions()[0].z, before[0].z + 0.01);
    EXPECT_EQ(count_obstacle_intersections(model), 0);
    EXPECT_EQ(put_back.stuck(), 0);
}

// Where the fallback meets the obstacle too (the cloth began inside it), nothing moves: the
// triangles are reported stuck.
TEST(ObstaclePutBack, AFallbackInsideTheObstacleLeavesTheTriangleStuck) {
    ClothModel model(test::flat_sheet(4, 0.2, 0.05), ClothMaterial{});
    model.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.1});
    const std::vector<Vec3d> before(model.positions().begin(), model.positions().end());
    model.mutable_positions()[6].z -= 0.01;
    ObstaclePutBack put_back;
    put_back.seed(model.positions(), before);
    EXPECT_EQ(put_back.run(model, before, ObstaclePutBack::Fallback::reference), 0);
    EXPECT_GT(put_back.stuck(), 0);
    EXPECT_EQ(model.positions()[6].z, before[6].z - 0.01);
}

// The turn carries the sheet's vertices 4.5–4.9 cm: with max_carry 1 cm (an obstacle that jumps,
// as far as the passes may push) nothing is carried, the triangles are reported stuck.
TEST(ObstaclePutBack, NoCarryFartherThanMaxCarry) {
    ClothModel model = sheet_beside_a_turning_box();
    const std::vector<Vec3d> start(model.positions().begin(), model.positions().end());
    model.begin_step(0.1);
    model.move_obstacles(0.1);
    std::vector<Vec3d> before(start);
    for (Vec3d& p : before) {
        p.x += 1.0;
    }
    ObstaclePutBack put_back;
    put_back.seed(model.positions(), before);
    EXPECT_EQ(put_back.run(model, start, ObstaclePutBack::Fallback::carried, 0.01), 0);
    EXPECT_GT(put_back.stuck(), 0);
    EXPECT_GT(count_obstacle_intersections(model), 0);
}

// Cloth that began a substep wholly inside a closed mesh (given there, or lagging behind a surface
// that jumped) with one vertex pushed out through the surface: carrying it back inside would
// meet nothing (meets_triangle sees the surface only), but it is refused, so the cloth keeps
// coming out.
TEST(ObstaclePutBack, NoFallbackInsideAClosedMesh) {
    ClothModel model(test::flat_sheet(4, 0.1, 0.2), ClothMaterial{});
    model.add_mesh_obstacle(std::make_shared<const MeshObstacle>(
        geometry::make_box({-0.25, -0.25, 0.0}, {0.25, 0.25, 0.4})));
    const std::vector<Vec3d> start(model.positions().begin(), model.positions().end());
    model.mutable_positions()[12].z = 0.45;  // the centre pushed out through the top
    EXPECT_GT(count_obstacle_intersections(model), 0);
    ObstaclePutBack put_back;
    put_back.seed(model.positions(), start);
    EXPECT_EQ(put_back.run(model, start, ObstaclePutBack::Fallback::carried), 0);
    EXPECT_GT(put_back.stuck(), 0);
    EXPECT_EQ(model.positions()[12].z, 0.45);
}

}  // namespace
}  // namespace pliant::cloth
