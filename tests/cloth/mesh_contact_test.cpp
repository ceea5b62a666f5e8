// Deforming mesh obstacles in the cloth solver (mesh_contact.hpp, MeshObstacle::move_to / sweep,
// ClothModel::add_animated_mesh_obstacle / add_attached_pins): no tunnelling through a fast thin
// body, friction relative to the surface's own motion, pins that follow a deforming surface,
// bounded pushes from an obstacle that jumps, threads and resume.
#include "pliant/cloth/mesh_contact.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pliant/cloth/mesh_animation.hpp"
#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/obstacle_intersections.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

using geometry::TriangleMeshD;

// The frames of `mesh` moved by f(p, k) for k = 0 .. num_frames - 1.
template <typename Move>
std::shared_ptr<const MeshAnimation> animate(const TriangleMeshD& mesh, int num_frames, double fps,
                                             bool loop, Move&& move) {
    std::vector<std::vector<Vec3d>> frames;
    for (int k = 0; k < num_frames; ++k) {
        frames.emplace_back();
        for (const Vec3d& p : mesh.positions) {
            frames.back().push_back(move(p, k));
        }
    }
    return std::make_shared<const MeshAnimation>(std::move(frames), fps, loop);
}

ClothMaterial material(double friction = 0.0) {
    ClothMaterial m;
    m.thickness = 0.005;
    m.static_friction = friction;
    m.kinetic_friction = friction;
    return m;
}

TEST(MeshObstacle, SweepFindsAPointThatAMovingTriangleSweepsOver) {
    MeshObstacle plate(geometry::make_box({-1.0, -1.0, -0.102}, {1.0, 1.0, -0.1}));
    ASSERT_GT(plate.enclosed_volume().value(), 0.0);
    std::vector<Vec3d> up(plate.mesh().positions);
    for (Vec3d& p : up) {
        p.z += 0.2;  // top face from z = -0.1 to z = 0.1, past a point at z = 0
    }
    plate.move_to(up);
    EXPECT_NEAR(plate.max_vertex_step(), 0.2, 1e-15);
    const Vec3d x{0.1, 0.2, 0.0};
    // Where the plate is now, the point is below it and outside: static contact sees nothing.
    EXPECT_GT(plate.surface_distance(x, 1.0)->distance, 0.09);
    const auto hit = plate.sweep(x, x);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->toi, 0.5, 1e-5);  // the top face reaches z = 0 halfway
    const auto& tri = plate.mesh().triangles[static_cast<std::size_t>(hit->triangle)];
    const Vec3d met =
        plate.mesh().positions[static_cast<std::size_t>(tri[0])] * hit->barycentric.x +
        plate.mesh().positions[static_cast<std::size_t>(tri[1])] * hit->barycentric.y +
        plate.mesh().positions[static_cast<std::size_t>(tri[2])] * hit->barycentric.z;
    EXPECT_NEAR(met.x, 0.1, 1e-6);
    EXPECT_NEAR(met.y, 0.2, 1e-6);
    EXPECT_NEAR(met.z, 0.1, 1e-12);  // on the top face at the step's end
    // A point beside the plate's path, or leaving it from behind, is not reported.
    EXPECT_FALSE(plate.sweep({3.0, 0.0, 0.0}, {3.0, 0.0, 0.0}));
    EXPECT_FALSE(plate.sweep({0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}).has_value() &&
                 plate.sweep({0.0, 0.0, -0.101}, {0.0, 0.0, -0.101}).has_value());
    EXPECT_THROW(plate.move_to(std::vector<Vec3d>(3)), InvalidInput);
}

// A 2 mm plate rising at 40 m/s (40 mm per 1 ms substep) through a sheet at rest.
struct RisingPlate {
    TriangleMeshD plate = geometry::make_box({-1.0, -1.0, -0.102}, {1.0, 1.0, -0.1});
    std::shared_ptr<const MeshAnimation> animation =
        animate(plate, 2, 100.0, false, [](Vec3d p, int k) {
            return p + Vec3d{0, 0, 0.4 * k};
        });
    double top_at_end = 0.3;
};

TEST(MeshContact, AFastThinObstacleDoesNotTunnelThroughTheCloth) {
    const RisingPlate rising;
    const TriangleMeshD sheet = test::flat_sheet(4, 0.2, 0.0);
    ClothSolver solver(sheet, material());
    solver.set_gravity({0.0, 0.0, 0.0});
    solver.add_animated_mesh_obstacle(MeshObstacle(rising.plate), rising.animation);
    const ClothStepStats stats = solver.step(0.01, 10);  // frame 1 of the plate: top at 0.3
    EXPECT_GT(stats.obstacle_swept_contacts, 0);
    EXPECT_NEAR(stats.obstacle_max_step, 0.04, 1e-9);
    for (const Vec3d& p : solver.positions()) {
        EXPECT_GE(p.z, rising.top_at_end + 0.99 * 0.005);
    }

    // The baseline: static contact only (push out of the plate where it is at each substep's
    // end, within twice the thickness) leaves the cloth below the plate: it passed through.
    MeshObstacle plate(rising.plate);
    std::vector<Vec3d> cloth(sheet.positions);
    std::vector<Vec3d> placed(rising.plate.positions.size());
    for (int s = 1; s <= 10; ++s) {
        rising.animation->positions_at(s * 0.001, placed);
        plate.set_positions(placed);
        for (Vec3d& x : cloth) {
            push_out(plate, x, 0.005, 0.01);
        }
    }
    for (const Vec3d& p : cloth) {
        EXPECT_LT(p.z, rising.top_at_end - 0.002);  // below the plate's bottom face
    }
}

// Friction carries cloth resting on a slab whose vertices move along x at 0.5 m/s.
double drift_on_moving_slab(double friction) {
    const TriangleMeshD slab = geometry::make_box({-1.0, -1.0, -0.2}, {1.0, 1.0, 0.0});
    const auto sliding = animate(slab, 2, 1.0, false, [](Vec3d p, int k) {
        return p + Vec3d{0.5 * k, 0, 0};
    });
    const TriangleMeshD sheet = test::flat_sheet(4, 0.2, 0.005);
    ClothSolver solver(sheet, material(friction));
    solver.add_animated_mesh_obstacle(MeshObstacle(slab), sliding);
    for (int frame = 0; frame < 24; ++frame) {
        solver.step(1.0 / 24.0, 20);
    }
    double x = 0.0;
    for (const Vec3d& p : solver.positions()) {
        x += p.x;
    }
    return x / static_cast<double>(solver.positions().size());
}

// A closed blade (a triangular prism, 2 mm thick at its base, its ridge along y at x = x_ridge)
// with its base at z = base and its ridge at base + height.
TriangleMeshD blade(double x_ridge, double base, double height) {
    constexpr double W = 0.001;  // half the base's width
    TriangleMeshD mesh;
    for (const double y : {-0.3, 0.3}) {
        mesh.positions.push_back({x_ridge - W, y, base});
        mesh.positions.push_back({x_ridge + W, y, base});
        mesh.positions.push_back({x_ridge, y, base + height});
    }
    mesh.triangles = {{0, 1, 2}, {3, 5, 4}, {0, 3, 4}, {0, 4, 1},
                      {0, 2, 5}, {0, 5, 3}, {1, 4, 5}, {1, 5, 2}};
    return mesh;
}

double orient(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    return dot(b - a, cross(c - a, d - a));
}

// Segment pq crosses triangle abc (strictly: p and q on opposite sides of its plane, the line
// through p and q inside its three edges).
bool crosses(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const double sp = orient(a, b, c, p);
    const double sq = orient(a, b, c, q);
    if (!(sp * sq < 0.0)) {
        return false;
    }
    const double e0 = orient(p, q, a, b);
    const double e1 = orient(p, q, b, c);
    const double e2 = orient(p, q, c, a);
    return (e0 > 0.0 && e1 > 0.0 && e2 > 0.0) || (e0 < 0.0 && e1 < 0.0 && e2 < 0.0);
}

// Cloth edges that cross a triangle of `obstacle`.
int crossing_edges(std::span<const Vec3d> cloth, const geometry::MeshTopology& topology,
                   const TriangleMeshD& obstacle) {
    int count = 0;
    for (const geometry::Edge& e : topology.edges) {
        for (const geometry::Triangle& t : obstacle.triangles) {
            if (crosses(cloth[static_cast<std::size_t>(e[0])],
                        cloth[static_cast<std::size_t>(e[1])],
                        obstacle.positions[static_cast<std::size_t>(t[0])],
                        obstacle.positions[static_cast<std::size_t>(t[1])],
                        obstacle.positions[static_cast<std::size_t>(t[2])])) {
                ++count;
                break;
            }
        }
    }
    return count;
}

// A blade rising through a sheet between two columns of its vertices (5 cm apart, the blade at
// 2.5 cm from each, 5 times the thickness): no vertex comes near it, so vertex-face contact
// alone lets it pass through the sheet's edges; the edge pass lifts the sheet over its ridge.
TEST(MeshContact, ABladeBetweenTheVerticesIsCaughtByTheEdges) {
    const TriangleMeshD sheet = test::flat_sheet(4, 0.2, 0.0);  // x, y in {-0.1, -0.05, ..., 0.1}
    const TriangleMeshD low = blade(0.025, -0.25, 0.2);         // ridge 5 cm below the sheet
    const auto rising = animate(low, 2, 100.0, false, [](Vec3d p, int k) {
        return p + Vec3d{0, 0, 0.15 * k};  // ridge 10 cm above the sheet at 0.01 s
    });
    ClothSolver solver(sheet, material());
    solver.set_gravity({0.0, 0.0, 0.0});
    solver.add_animated_mesh_obstacle(MeshObstacle(low), rising);
    EXPECT_GT(solver.step(0.01, 10).obstacle_edge_contacts, 0);
    TriangleMeshD high = low;
    rising->positions_at(0.01, high.positions);
    const geometry::MeshTopology& topology = solver.model().topology();
    EXPECT_EQ(crossing_edges(solver.positions(), topology, high), 0);
    double top = -1.0;
    for (const Vec3d& p : solver.positions()) {
        top = std::max(top, p.z);
    }
    EXPECT_GT(top, 0.1);  // carried up on the ridge

    // The baseline: vertex-face contact alone (the same substeps, vertices pushed out of the
    // blade where it is, within its swept path) leaves the blade through the sheet.
    MeshObstacle moving(low);
    std::vector<Vec3d> cloth(sheet.positions);
    std::vector<Vec3d> placed(low.positions.size());
    for (int s = 1; s <= 10; ++s) {
        rising->positions_at(s * 0.001, placed);
        moving.move_to(placed);
        for (Vec3d& x : cloth) {
            if (const auto hit = moving.sweep(x, x)) {
                x.z = 1.0;  // never happens: the blade passes 2.5 cm from every vertex
            }
            push_out(moving, x, 0.005, 0.02);
        }
    }
    EXPECT_EQ(cloth, sheet.positions);
    EXPECT_GT(crossing_edges(cloth, topology, high), 0);

    // A finer sheet (many edges per thread): the same bits for 1 and 4 threads.
    const auto run = [&](int threads) {
        set_num_threads(threads);
        ClothSolver fine(test::flat_sheet(40, 0.2, 0.0), material());
        fine.set_gravity({0.0, 0.0, 0.0});
        const TriangleMeshD between = blade(0.0275, -0.25, 0.2);  // 2.5 mm from two columns
        fine.add_animated_mesh_obstacle(MeshObstacle(between),
                                        animate(between, 2, 100.0, false, [](Vec3d p, int k) {
                                            return p + Vec3d{0, 0, 0.15 * k};
                                        }));
        EXPECT_GT(fine.step(0.01, 10).obstacle_edge_contacts, 0);
        set_num_threads(0);
        return std::vector<Vec3d>(fine.positions().begin(), fine.positions().end());
    };
    const std::vector<Vec3d> one = run(1);
    const std::vector<Vec3d> four = run(4);
    ASSERT_EQ(one.size(), four.size());
    EXPECT_EQ(0, std::memcmp(one.data(), four.data(), one.size() * sizeof(Vec3d)));
}

// A closed spike (a pyramid on a 4 mm square base, 20 cm high) with its apex at `apex`.
TriangleMeshD spike(const Vec3d& apex) {
    constexpr double W = 0.002;
    TriangleMeshD mesh;
    mesh.positions = {apex + Vec3d{-W, -W, -0.2}, apex + Vec3d{W, -W, -0.2},
                      apex + Vec3d{W, W, -0.2}, apex + Vec3d{-W, W, -0.2}, apex};
    mesh.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
    return mesh;
}

// The centroid of the sheet's triangle nearest (0.025, 0.025): 1.4 cm from its edges.
Vec3d centroid_near_quad_centre(const TriangleMeshD& sheet) {
    Vec3d best{1e9, 1e9, 1e9};
    for (const geometry::Triangle& t : sheet.triangles) {
        const Vec3d c = (sheet.positions[static_cast<std::size_t>(t[0])] +
                         sheet.positions[static_cast<std::size_t>(t[1])] +
                         sheet.positions[static_cast<std::size_t>(t[2])]) *
                        (1.0 / 3.0);
        if (norm(c - Vec3d{0.025, 0.025, c.z}) < norm(best - Vec3d{0.025, 0.025, best.z})) {
            best = c;
        }
    }
    return best;
}

TEST(MeshObstacle, SweepTriangleFindsASurfaceVertexEnteringIt) {
    const Vec3d a{0.0, 0.0, 0.0};
    const Vec3d b{0.06, 0.0, 0.0};
    const Vec3d c{0.0, 0.06, 0.0};
    const Vec3d centre{0.02, 0.02, 0.0};
    MeshObstacle rising(spike(centre + Vec3d{0, 0, -0.05}));
    TriangleMeshD up = rising.mesh();
    for (Vec3d& p : up.positions) {
        p.z += 0.1;  // the apex from 5 cm below the triangle to 5 cm above it
    }
    rising.move_to(up.positions);
    const auto hit = rising.sweep_triangle(a, b, c, a, b, c);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->vertex, 4);
    EXPECT_NEAR(hit->toi, 0.5, 1e-5);
    EXPECT_NEAR(hit->barycentric.y, 1.0 / 3.0, 1e-6);
    EXPECT_NEAR(hit->barycentric.z, 1.0 / 3.0, 1e-6);
    // The same meeting seen from a triangle that falls onto the apex while it rises less.
    const Vec3d down{0.0, 0.0, -0.2};
    EXPECT_TRUE(rising.sweep_triangle(a - down, b - down, c - down, a + down, b + down, c + down));
    // Not: a triangle that moves up faster than the apex (leaving it), one beside its path, one
    // under the spike's whole path.
    const Vec3d up_fast{0.0, 0.0, 0.3};
    EXPECT_FALSE(rising.sweep_triangle(a, b, c, a + up_fast, b + up_fast, c + up_fast));
    const Vec3d aside{0.3, 0.0, 0.0};
    EXPECT_FALSE(
        rising.sweep_triangle(a + aside, b + aside, c + aside, a + aside, b + aside, c + aside));
    const Vec3d below{0.0, 0.0, -0.3};
    EXPECT_FALSE(
        rising.sweep_triangle(a + below, b + below, c + below, a + below, b + below, c + below));
}

// The box of scenes/stress/box.obj: 0.5 m × 0.5 m × 0.4 m on z = 0, with that file's
// triangulation, in which the corner (-0.25, 0.25, 0.4) (vertex 7) has one triangle of the top,
// two of the +y side and one of the -x side.
TriangleMeshD stress_box() {
    TriangleMeshD box;
    box.positions = {{-0.25, -0.25, 0.0}, {0.25, -0.25, 0.0},  {0.25, 0.25, 0.0},
                     {-0.25, 0.25, 0.0},  {-0.25, -0.25, 0.4}, {0.25, -0.25, 0.4},
                     {0.25, 0.25, 0.4},   {-0.25, 0.25, 0.4}};
    box.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                     {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    return box;
}

// A triangle of the turning-box stress scene (scenes/stress/turning_box.json, frame 42, in the
// box's frame) sliding over the box's corner: it moves 6 mm, mostly along the surface, and the
// corner comes 1 mm through it. Along the corner's pseudo-normal the motion is a fraction of a
// millimetre, and against it with the pseudo-normal of this triangulation; through the triangle
// it is 1.8 mm.
TEST(MeshObstacle, SweepTriangleCatchesACornerTheClothSlidesOnto) {
    const MeshObstacle box(stress_box());
    const Vec3d a0{-0.26264820940495326, 0.25823020814275033, 0.38873889409615831};
    const Vec3d b0{-0.25601794506848202, 0.22897631505080218, 0.4073574022342949};
    const Vec3d c0{-0.24154539198334873, 0.25134943331296045, 0.40481446048211767};
    const Vec3d a1{-0.25940639383069175, 0.26323416587179066, 0.38704388081320951};
    const Vec3d b1{-0.2525520500617518, 0.2346168802830314, 0.40686381069146488};
    const Vec3d c1{-0.23955829252362429, 0.25520962485320164, 0.39997764558924653};
    ASSERT_FALSE(box.meets_triangle(a0, b0, c0));
    ASSERT_TRUE(box.meets_triangle(a1, b1, c1));
    const auto hit = box.sweep_triangle(a0, b0, c0, a1, b1, c1);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->vertex, 7);
    // The same motion backwards takes the triangle off the corner: not entering.
    EXPECT_FALSE(box.sweep_triangle(a1, b1, c1, a0, b0, c0));
}

// A cloth edge sliding 1 cm along itself across the box's top +y edge while it passes 2 mm
// through it: its motion points outward along the edge's pseudo-normal, yet it ends cutting the
// box's corner off.
TEST(MeshObstacle, SweepEdgeCatchesAnEdgeSlidingThroughAnEdge) {
    const MeshObstacle box(stress_box());
    const Vec3d on_edge{0.0, 0.25, 0.4};
    const Vec3d along = Vec3d{0.0, 1.0, -0.3} * (1.0 / std::sqrt(1.09));   // the cloth edge
    const Vec3d through = Vec3d{0.0, 0.3, 1.0} * (1.0 / std::sqrt(1.09));  // normal to both
    const Vec3d p0 = on_edge + through * 0.001 - along * 0.02;
    const Vec3d q0 = on_edge + through * 0.001 + along * 0.02;
    const Vec3d move = along * 0.01 - through * 0.002;
    const Vec3d p1 = p0 + move;
    const Vec3d q1 = q0 + move;
    ASSERT_GT(dot(move, Vec3d{0.0, 1.0, 1.0}), 0.0);
    // The end's point 1 mm inside the edge is inside the box.
    const Vec3d cut = on_edge - through * 0.001;
    ASSERT_NEAR(norm(cross(cut - p1, q1 - p1)), 0.0, 1e-15);
    ASSERT_TRUE(cut.y < 0.25 && cut.z < 0.4);
    const auto hit = box.sweep_edge(p0, q0, p1, q1);
    ASSERT_TRUE(hit);
    const geometry::Edge& edge = box.edges()[static_cast<std::size_t>(hit->edge)];
    for (const std::int32_t v : edge) {
        EXPECT_EQ(box.mesh().positions[static_cast<std::size_t>(v)].y, 0.25);
        EXPECT_EQ(box.mesh().positions[static_cast<std::size_t>(v)].z, 0.4);
    }
    EXPECT_FALSE(box.sweep_edge(p1, q1, p0, q0));
}

// A spike rising into a sheet inside one of its triangles, 1.4 cm from its edges and farther
// from its vertices: neither the vertices' nor the edges' contact sees it; the face pass lifts
// the triangle onto the tip.
TEST(MeshContact, ASpikeInsideAClothTriangleIsCaughtByTheFaces) {
    const TriangleMeshD sheet = test::flat_sheet(4, 0.2, 0.0);
    const Vec3d centre = centroid_near_quad_centre(sheet);
    const TriangleMeshD low = spike(centre + Vec3d{0, 0, -0.05});  // tip 5 cm below the sheet
    const auto rising = animate(low, 2, 100.0, false, [](Vec3d p, int k) {
        return p + Vec3d{0, 0, 0.15 * k};  // tip 10 cm above the sheet at 0.01 s
    });
    TriangleMeshD high = low;
    rising->positions_at(0.01, high.positions);
    // The sheet left where it is would have the spike through it.
    EXPECT_GT(collision::count_intersecting_pairs(sheet.positions, sheet.triangles, high.positions,
                                                  high.triangles),
              0);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        ClothSolver solver(sheet, material());
        solver.set_gravity({0.0, 0.0, 0.0});
        solver.add_animated_mesh_obstacle(MeshObstacle(low), rising);
        const ClothStepStats stats = solver.step(0.01, 10);
        set_num_threads(0);
        EXPECT_EQ(stats.obstacle_swept_contacts, 0);
        EXPECT_EQ(stats.obstacle_edge_contacts, 0);
        EXPECT_GT(stats.obstacle_face_contacts, 0);
        EXPECT_EQ(count_obstacle_intersections(solver.model()), 0);
        EXPECT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles(),
                                                      high.positions, high.triangles),
                  0);
        double top = -1.0;
        for (const Vec3d& p : solver.positions()) {
            top = std::max(top, p.z);
        }
        EXPECT_GT(top, 0.05);  // carried up on the tip
        return std::vector<Vec3d>(solver.positions().begin(), solver.positions().end());
    };
    const std::vector<Vec3d> one = run(1);
    const std::vector<Vec3d> two = run(2);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3d)));
}

TEST(MeshContact, FrictionDragsTheClothWithTheSurfacesOwnMotion) {
    const double with = drift_on_moving_slab(1.0);
    const double without = drift_on_moving_slab(0.0);
    EXPECT_GT(with, 0.4);  // the slab moved 0.5 m
    EXPECT_LT(with, 0.55);
    EXPECT_LT(std::abs(without), 0.02);
}

TEST(MeshContact, AttachedPinsFollowADeformingBody) {
    // A box that grows by half and rises 0.3 m over 1 s; a sheet 1 cm above its top face.
    const TriangleMeshD body = geometry::make_box({-0.2, -0.2, -0.2}, {0.2, 0.2, 0.2});
    const auto growing = animate(body, 2, 1.0, false, [](Vec3d p, int k) {
        return k == 0 ? p : p * 1.5 + Vec3d{0.0, 0.0, 0.3};
    });
    const TriangleMeshD sheet = test::flat_sheet(4, 0.2, 0.21);
    ClothSolver solver(sheet, material());
    const std::size_t index = solver.add_animated_mesh_obstacle(MeshObstacle(body), growing);
    const std::vector<std::int32_t> attached{0, 1, 2, 3, 4};
    solver.add_attached_pins(attached, index, 0.02);
    for (int frame = 0; frame < 12; ++frame) {
        solver.step(1.0 / 24.0, 10);
    }
    // At t = 0.5 s the body is scaled by 1.25 and raised 0.15 m: its top face at z = 0.4.
    for (const std::int32_t v : attached) {
        const Vec3d& rest = sheet.positions[static_cast<std::size_t>(v)];
        const Vec3d& now = solver.positions()[static_cast<std::size_t>(v)];
        EXPECT_NEAR(now.x, 1.25 * rest.x, 1e-12) << v;
        EXPECT_NEAR(now.y, 1.25 * rest.y, 1e-12) << v;
        EXPECT_NEAR(now.z, 0.4 + 0.01, 1e-12) << v;
    }
    EXPECT_EQ(solver.model().pin_lag().vertices, 0);
    // Too far from the surface, or a wrong obstacle: errors naming them.
    ClothSolver far(test::flat_sheet(4, 0.2, 0.5), material());
    far.add_animated_mesh_obstacle(MeshObstacle(body), growing);
    try {
        far.add_attached_pins(attached, 0, 0.02);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 0"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("expected at most 0.02 m"), std::string::npos);
    }
    EXPECT_THROW(far.add_attached_pins(attached, 1, 0.02), InvalidInput);
}

TEST(MeshContact, AnObstacleThatJumpsPushesClothOutAtABoundedSpeed) {
    // A slab under resting cloth jumps 0.3 m within one frame (15 mm per substep, three
    // thicknesses), then stays.
    const TriangleMeshD slab = geometry::make_box({-1.0, -1.0, -0.4}, {1.0, 1.0, 0.0});
    const auto jump = animate(slab, 2, 24.0, false, [](Vec3d p, int k) {
        return p + Vec3d{0, 0, 0.3 * k};
    });
    ClothSolver solver(test::flat_sheet(8, 0.2, 0.004), material(0.5));
    solver.add_animated_mesh_obstacle(MeshObstacle(slab), jump);
    solver.enable_self_collision(true);
    // One substep: the slab rises 15 mm under cloth resting 4 mm above it; the cloth, at rest,
    // is pushed at most the 1 mm it was within the thickness plus the thickness and a half
    // (7.5 mm), and lags behind the surface.
    const double h = 1.0 / 480.0;
    std::vector<Vec3d> before(solver.positions().begin(), solver.positions().end());
    const ClothStepStats first = solver.step(h, 1);
    EXPECT_NEAR(first.obstacle_max_step, 0.015, 1e-9);
    EXPECT_GT(first.obstacle_max_lag, 0.0);
    EXPECT_GT(first.obstacles_lagging, 0);
    double moved = 0.0;
    for (std::size_t v = 0; v < before.size(); ++v) {
        moved = std::max(moved, norm(solver.positions()[v] - before[v]));
    }
    EXPECT_LE(moved, 0.0085 + 9.81 * h * h + 1e-12);
    EXPECT_GT(moved, 0.008);
    // The rest of the jump's frame: the cloth keeps up with the surface within a few substeps.
    for (int s = 1; s < 20; ++s) {
        solver.step(h, 1);
    }
    // The slab holds still from then on: the cloth comes out on top and stops lagging.
    ClothStepStats last;
    for (int frame = 0; frame < 24; ++frame) {
        last = solver.step(1.0 / 24.0, 20);
    }
    EXPECT_EQ(last.obstacles_lagging, 0);
    for (const Vec3d& p : solver.positions()) {
        EXPECT_GT(p.z, 0.3);
    }
}

// A sheet falling onto a turning, bending body (a box whose top leans as it deforms), with
// self-collision and friction: the result after `frames` frames.
std::unique_ptr<ClothSolver> bending_body_scene() {
    const TriangleMeshD body = geometry::make_box({-0.3, -0.3, -0.5}, {0.3, 0.3, 0.0});
    const auto bending = animate(body, 4, 12.0, true, [](Vec3d p, int k) {
        const double lean = 0.05 * std::sin(k * 1.5707963267948966);
        return p + Vec3d{lean * (p.z + 0.5), 0.0, 0.0};
    });
    auto solver = std::make_unique<ClothSolver>(test::flat_sheet(12, 0.5, 0.05), material(0.3));
    solver->add_animated_mesh_obstacle(MeshObstacle(body), bending);
    solver->enable_self_collision(true);
    return solver;
}

// `frames` frames of the solvers `make` builds: the same bits for 1 and 4 threads, and for a
// solver saved after half of them and loaded into a new one.
void expect_threads_and_resume_bitwise(const std::function<std::unique_ptr<ClothSolver>()>& make,
                                       int frames) {
    const auto run = [&](int threads) {
        set_num_threads(threads);
        auto solver = make();
        for (int frame = 0; frame < frames; ++frame) {
            solver->step(1.0 / 24.0, 10);
        }
        set_num_threads(0);
        return std::vector<Vec3d>(solver->positions().begin(), solver->positions().end());
    };
    const std::vector<Vec3d> one = run(1);
    const std::vector<Vec3d> four = run(4);
    ASSERT_EQ(one.size(), four.size());
    EXPECT_EQ(0, std::memcmp(one.data(), four.data(), one.size() * sizeof(Vec3d)));

    auto first = make();
    for (int frame = 0; frame < frames / 2; ++frame) {
        first->step(1.0 / 24.0, 10);
    }
    ByteWriter out;
    first->save_state(out);
    auto resumed = make();
    ByteReader in(out.bytes(), "state");
    resumed->load_state(in);
    for (int frame = frames / 2; frame < frames; ++frame) {
        resumed->step(1.0 / 24.0, 10);
    }
    const std::span<const Vec3d> again = resumed->positions();
    ASSERT_EQ(again.size(), one.size());
    EXPECT_EQ(0, std::memcmp(again.data(), one.data(), one.size() * sizeof(Vec3d)));
}

TEST(MeshContact, ThreadsAndResumeGiveTheSameBits) {
    expect_threads_and_resume_bitwise(bending_body_scene, 6);
}

// The VBD stepper runs the same swept vertex and edge passes after its block descent: the fast
// plate and the blade of the tests above stay on their side of the cloth, and the deforming body
// gives the same bits for 1 and 4 threads and after a resume.
TEST(MeshContact, TheVbdStepperSweepsVerticesAndEdgesToo) {
    const RisingPlate rising;
    ClothSolver plate_solver(test::flat_sheet(4, 0.2, 0.0), material());
    plate_solver.use_vbd({});
    plate_solver.set_gravity({0.0, 0.0, 0.0});
    plate_solver.add_animated_mesh_obstacle(MeshObstacle(rising.plate), rising.animation);
    EXPECT_GT(plate_solver.step(0.01, 10).obstacle_swept_contacts, 0);
    for (const Vec3d& p : plate_solver.positions()) {
        EXPECT_GE(p.z, rising.top_at_end + 0.99 * 0.005);
    }

    const TriangleMeshD low = blade(0.025, -0.25, 0.2);
    const auto rising_blade = animate(low, 2, 100.0, false, [](Vec3d p, int k) {
        return p + Vec3d{0, 0, 0.15 * k};
    });
    ClothSolver blade_solver(test::flat_sheet(4, 0.2, 0.0), material());
    blade_solver.use_vbd({});
    blade_solver.set_gravity({0.0, 0.0, 0.0});
    blade_solver.add_animated_mesh_obstacle(MeshObstacle(low), rising_blade);
    EXPECT_GT(blade_solver.step(0.01, 10).obstacle_edge_contacts, 0);
    TriangleMeshD high = low;
    rising_blade->positions_at(0.01, high.positions);
    EXPECT_EQ(crossing_edges(blade_solver.positions(), blade_solver.model().topology(), high), 0);

    expect_threads_and_resume_bitwise(
        [] {
            auto solver = bending_body_scene();
            solver->use_vbd({});
            return solver;
        },
        4);
}

}  // namespace
}  // namespace pliant::cloth
