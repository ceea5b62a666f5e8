#include "pliant/cloth/untangle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

geometry::TriangleMeshD sheet(int quads, double size) {
    return geometry::convert_precision<double>(geometry::make_grid_sheet(
        quads, quads, static_cast<float>(size), static_cast<float>(size)));
}

// `part` with every vertex mapped by `place`, appended to `mesh` as another piece of it.
template <typename Place>
void append(geometry::TriangleMeshD& mesh, const geometry::TriangleMeshD& part, Place&& place) {
    const auto offset = static_cast<std::int32_t>(mesh.positions.size());
    for (const Vec3d& p : part.positions) {
        mesh.positions.push_back(place(p));
    }
    for (const geometry::Triangle& t : part.triangles) {
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
}

// Untangles `mesh` (every vertex free) and expects more than `at_least` pairs at the start, none
// at the end (by the result and by an independent count) and at least one region move.
UntangleResult expect_untangled_by_a_region_move(geometry::TriangleMeshD& mesh,
                                                 std::int64_t at_least) {
    const std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    const UntangleResult result = untangle(mesh.positions, mesh.triangles, inverse_masses);
    EXPECT_GT(result.initial_pairs, at_least);
    EXPECT_EQ(result.final_pairs, 0);
    EXPECT_EQ(collision::count_intersecting_pairs(mesh.positions, mesh.triangles), 0);
    EXPECT_GE(result.region_moves, 1);
    return result;
}

// Two 1 m sheets of 24 × 24 quads, 2 cm apart, one mesh; the upper one has a smooth dent
// `depth` deep (a cosine bump of radius 0.25 m) that pokes through the lower one: a closed
// contour.
geometry::TriangleMeshD dent_through_sheet(double depth) {
    geometry::TriangleMeshD mesh = sheet(24, 1.0);
    append(mesh, sheet(24, 1.0), [&](Vec3d p) {
        const double r = std::sqrt(p.x * p.x + p.y * p.y);
        p.z = 0.02 - (r < 0.25 ? depth * 0.5 * (1.0 + std::cos(M_PI * r / 0.25)) : 0.0);
        return p;
    });
    return mesh;
}

double largest_move(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
    double m = 0.0;
    for (std::size_t v = 0; v < a.size(); ++v) {
        m = std::max(m, norm(a[v] - b[v]));
    }
    return m;
}

TEST(Untangle, ADentThroughAnotherSheetComesOut) {
    geometry::TriangleMeshD mesh = dent_through_sheet(0.06);
    const std::vector<Vec3d> start = mesh.positions;
    const std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    ASSERT_GT(collision::count_intersecting_pairs(mesh.positions, mesh.triangles), 20);
    const UntangleResult result = untangle(mesh.positions, mesh.triangles, inverse_masses);
    EXPECT_GT(result.initial_pairs, 20);
    EXPECT_EQ(result.final_pairs, 0);
    EXPECT_EQ(collision::count_intersecting_pairs(mesh.positions, mesh.triangles), 0);
    EXPECT_GT(result.iterations, 0);
    // The dent pokes 4 cm through: getting out takes about that much motion, not a scramble.
    EXPECT_NEAR(result.max_displacement, largest_move(mesh.positions, start), 1e-12);
    EXPECT_LT(result.max_displacement, 0.1);
    for (const Vec3d& p : mesh.positions) {
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
    // The sheets moved apart rather than crumpled: every edge within 5 % of its length.
    for (const geometry::Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)]);
            const double before = norm(start[b] - start[a]);
            ASSERT_NEAR(norm(mesh.positions[b] - mesh.positions[a]), before, 0.05 * before);
        }
    }
}

TEST(Untangle, PinnedVerticesStayAndTheRestMoves) {
    geometry::TriangleMeshD mesh = dent_through_sheet(0.06);
    const std::vector<Vec3d> start = mesh.positions;
    // The whole lower sheet is pinned: only the dented sheet can move out.
    std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    const std::size_t lower = mesh.positions.size() / 2;
    std::fill(inverse_masses.begin(), inverse_masses.begin() + static_cast<std::ptrdiff_t>(lower),
              0.0);
    const UntangleResult result = untangle(mesh.positions, mesh.triangles, inverse_masses);
    EXPECT_EQ(result.final_pairs, 0);
    for (std::size_t v = 0; v < lower; ++v) {
        ASSERT_EQ(mesh.positions[v].x, start[v].x);
        ASSERT_EQ(mesh.positions[v].y, start[v].y);
        ASSERT_EQ(mesh.positions[v].z, start[v].z);
    }
}

TEST(Untangle, ClothThatFellThroughItselfIsUntangled) {
    // Without self-collision, a 40 × 40 sheet dropped on a sphere, its stretch solved edge by
    // edge, folds through itself (see self_collision_test.cpp); the untangled state then
    // simulates on without intersections.
    geometry::TriangleMeshD mesh = sheet(40, 2.0);
    for (Vec3d& p : mesh.positions) {
        p.z = 1.2;
    }
    ClothMaterial single_edges;
    single_edges.stretch_solver = StretchSolver::edges;
    ClothSolver plain(mesh, single_edges);
    plain.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.5});
    // The first frame with intersections (around frame 17).
    for (int f = 0;
         f < 40 && collision::count_intersecting_pairs(plain.positions(), plain.triangles()) == 0;
         ++f) {
        plain.step(1.0 / 24.0, 20);
    }
    geometry::TriangleMeshD tangled{{plain.positions().begin(), plain.positions().end()},
                                    mesh.triangles};
    const std::int64_t before =
        collision::count_intersecting_pairs(tangled.positions, tangled.triangles);
    ASSERT_GT(before, 0);
    const std::vector<double> inverse_masses(tangled.positions.size(), 1.0);
    const UntangleResult result = untangle(tangled.positions, tangled.triangles, inverse_masses);
    EXPECT_EQ(result.initial_pairs, before);
    EXPECT_EQ(result.final_pairs, 0);
    EXPECT_EQ(collision::count_intersecting_pairs(tangled.positions, tangled.triangles), 0);

    // From there the solver with self-collision keeps it apart.
    ClothSolver solver(tangled, ClothMaterial{});
    solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.5});
    solver.enable_self_collision(true);
    for (int f = 0; f < 6; ++f) {
        solver.step(1.0 / 24.0, 20);
        ASSERT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0)
            << "frame " << f;
    }
}

TEST(Untangle, NeverLeavesMorePairsThanItFound) {
    // Two sheets crossing like an X from edge to edge: the contour runs across both, and
    // shortening it need not remove it; within 40 iterations (before any region move), the
    // result is no worse than the start.
    geometry::TriangleMeshD mesh = sheet(12, 1.0);
    // The second sheet stands in the x-z plane.
    append(mesh, sheet(12, 1.0), [](const Vec3d& p) { return Vec3d{p.x, 0.0, p.y}; });
    // Tilt both slightly so that no triangle is exactly coplanar with an edge.
    for (Vec3d& p : mesh.positions) {
        p.z += 0.013 * p.x + 0.007 * p.y;
    }
    const std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    UntangleOptions options;
    options.max_iterations = 40;
    const UntangleResult result = untangle(mesh.positions, mesh.triangles, inverse_masses, options);
    EXPECT_GT(result.initial_pairs, 0);
    EXPECT_LE(result.final_pairs, result.initial_pairs);
    EXPECT_EQ(collision::count_intersecting_pairs(mesh.positions, mesh.triangles),
              result.final_pairs);
    EXPECT_LE(result.iterations, 40);
    // With the default budget, the stall gets a region move: the standing sheet moves up out of
    // the lying one, by the depth of its lower half (0.5 m).
    const UntangleResult full = untangle(mesh.positions, mesh.triangles, inverse_masses);
    EXPECT_EQ(full.final_pairs, 0);
    EXPECT_GE(full.region_moves, 1);
    EXPECT_EQ(collision::count_intersecting_pairs(mesh.positions, mesh.triangles), 0);
}

// Every edge of `mesh` within `tolerance` (relative) of its length in `start`.
void expect_edge_lengths_kept(const geometry::TriangleMeshD& mesh, const std::vector<Vec3d>& start,
                              double tolerance) {
    for (const geometry::Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)]);
            const double before = norm(start[b] - start[a]);
            ASSERT_NEAR(norm(mesh.positions[b] - mesh.positions[a]), before, tolerance * before);
        }
    }
}

TEST(Untangle, SeparateSheetsCrossingFromEdgeToEdgeComeApart) {
    // Two 1 m sheets of 24 x 24 quads crossing like an X: the second is tilted by 20 degrees
    // about x (and shifted off the first's grid lines), so the contour runs straight across both
    // from edge to edge. Contour minimization alone left 95 of 188 pairs after 400 iterations;
    // the piece move takes one whole sheet along the other's normal, out of it.
    geometry::TriangleMeshD mesh = sheet(24, 1.0);
    const auto offset = static_cast<std::int32_t>(mesh.positions.size());
    const double c = std::cos(20.0 * M_PI / 180.0);
    const double s = std::sin(20.0 * M_PI / 180.0);
    append(mesh, sheet(24, 1.0), [&](const Vec3d& p) {
        return Vec3d{p.x + 0.0123, c * p.y + 0.0171, s * p.y};
    });
    const std::vector<Vec3d> start = mesh.positions;
    const UntangleResult result = expect_untangled_by_a_region_move(mesh, 40);
    // A sheet moved by about its depth through the other (sin 20 degrees x 0.5 m = 0.17 m),
    // keeping its shape.
    EXPECT_LT(result.max_displacement, 0.25);
    expect_edge_lengths_kept(mesh, start, 0.05);

    // With a vertex of one sheet pinned (the piece that moves otherwise), the other one moves.
    for (const std::size_t pinned : {std::size_t{0}, static_cast<std::size_t>(offset)}) {
        mesh.positions = start;
        std::vector<double> masses(mesh.positions.size(), 1.0);
        masses[pinned] = 0.0;
        const UntangleResult again = untangle(mesh.positions, mesh.triangles, masses);
        EXPECT_EQ(again.final_pairs, 0) << pinned;
        EXPECT_GE(again.region_moves, 1) << pinned;
        EXPECT_EQ(norm(mesh.positions[pinned] - start[pinned]), 0.0) << pinned;
    }
}

// A strip 0.5 m wide: flat for 1 m, a half-turn fold of radius 0.15 m widening it to 0.6 m,
// then back over itself falling 0.6 m per metre, through the flat part along a line across
// it: the contour cuts the flat part's first half metre off from the rest (the region that
// flips), while on the wider part it ends inside.
geometry::TriangleMeshD strip_folded_through_itself() {
    const int across = 12;
    const int along = 64;
    const double fold = M_PI * 0.15;
    const double length = 2.0 + fold;
    geometry::TriangleMeshD mesh = geometry::convert_precision<double>(
        geometry::make_grid_sheet(across, along, 0.5f, static_cast<float>(length)));
    for (Vec3d& p : mesh.positions) {
        const double y = p.y + 0.5 * length;  // 0 .. length along the strip
        if (y <= 1.0) {
            p = {p.x, y, 0.0};
        } else if (y <= 1.0 + fold) {
            const double phi = (y - 1.0) / 0.15;
            p = {p.x * (1.0 + 0.2 * phi / M_PI), 1.0 + 0.15 * std::sin(phi),
                 0.15 - 0.15 * std::cos(phi)};
        } else {
            const double back = y - 1.0 - fold;
            p = {p.x * 1.2 + 0.0071, 1.0 - back, 0.3 - 0.6 * back};
        }
    }
    return mesh;
}

TEST(Untangle, ASheetFoldedThroughItselfFromEdgeToEdgeComesApart) {
    geometry::TriangleMeshD mesh = strip_folded_through_itself();
    expect_untangled_by_a_region_move(mesh, 20);
    for (const Vec3d& p : mesh.positions) {
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
}

TEST(Untangle, ASquareThroughBothLayersOfAFoldComesOut) {
    // A 1 m wide strip folded over on itself (two layers 5 cm apart, joined by a half-turn: one
    // piece, its layers' normals opposite) and a free 0.3 m square standing through both layers:
    // the square's walls meet triangles of both layers, whose normals cancel (no plane is taken
    // from them; the moves come from planes of one layer, or of the square).
    const double radius = 0.025;
    const double fold = M_PI * radius;
    const double length = 2.0 + fold;
    geometry::TriangleMeshD mesh = geometry::convert_precision<double>(
        geometry::make_grid_sheet(16, 40, 1.0f, static_cast<float>(length)));
    for (Vec3d& p : mesh.positions) {
        const double y = p.y + 0.5 * length;  // 0 .. length along the strip
        if (y <= 1.0) {
            p = {p.x, y - 0.5, 0.0};
        } else if (y <= 1.0 + fold) {
            const double phi = (y - 1.0) / radius;
            p = {p.x, 0.5 + radius * std::sin(phi), radius - radius * std::cos(phi)};
        } else {
            p = {p.x, 0.5 - (y - 1.0 - fold), 2.0 * radius};
        }
    }
    append(mesh, sheet(6, 0.3), [](const Vec3d& p) {
        return Vec3d{p.x + 0.0113, 0.0137, p.y + 0.025};
    });
    expect_untangled_by_a_region_move(mesh, 20);
}

// A start untangled once and given to a new solver with set_positions simulates bitwise as the
// solver that untangled it (the viewer's reset reuses its start so).
TEST(Untangle, AKeptStartSimulatesAsTheSolverThatUntangledIt) {
    const geometry::TriangleMeshD mesh = dent_through_sheet(0.06);
    const std::vector<std::int32_t> pinned{0, 24};
    auto make = [&] {
        auto solver = std::make_unique<ClothSolver>(mesh, ClothMaterial{}, pinned);
        solver->enable_self_collision(true);
        return solver;
    };
    const std::unique_ptr<ClothSolver> untangled = make();
    ASSERT_EQ(untangled->untangle().final_pairs, 0);
    const std::unique_ptr<ClothSolver> kept = make();
    kept->step(1.0 / 24.0, 10);  // self-collision state of positions that are then gone
    kept->set_velocities(std::vector<Vec3d>(mesh.positions.size(), Vec3d{}));
    kept->set_positions(untangled->positions());
    for (int frame = 0; frame < 3; ++frame) {
        untangled->step(1.0 / 24.0, 10);
        kept->step(1.0 / 24.0, 10);
    }
    ASSERT_EQ(kept->positions().size(), untangled->positions().size());
    EXPECT_EQ(std::memcmp(kept->positions().data(), untangled->positions().data(),
                          kept->positions().size() * sizeof(Vec3d)),
              0);
    EXPECT_EQ(collision::count_intersecting_pairs(kept->positions(), kept->triangles()), 0);

    std::vector<Vec3d> moved(mesh.positions.begin(), mesh.positions.end());
    const std::unique_ptr<ClothSolver> fresh = make();
    EXPECT_THROW(fresh->set_positions(std::span(moved).first(10)), InvalidInput);
    moved[7].z = std::nan("");
    EXPECT_THROW(fresh->set_positions(moved), InvalidInput);
    moved[7] = mesh.positions[7];
    moved[24].x += 1e-9;  // a pinned vertex
    EXPECT_THROW(fresh->set_positions(moved), InvalidInput);
    moved[24] = mesh.positions[24];
    moved[25].x += 1e-9;  // a free one
    EXPECT_NO_THROW(fresh->set_positions(moved));
}

// Region moves keep out of obstacles. Two 1 m sheets of 12 x 12 quads cross 0.2 m above the
// ground: one flat at 0.22 m, the other tilted by 20 degrees, its lowest edge 1 cm above the
// ground. The shortest move sinks the tilted sheet 0.24 m, most of it into the ground (which
// the simulation then cannot push out through the other sheet: 5,000 CCD hits in every frame,
// edges stretched to 4 times their length); the solver, which knows the ground, lifts the flat
// one instead.
TEST(Untangle, RegionMovesKeepOutOfObstacles) {
    geometry::TriangleMeshD mesh = sheet(12, 1.0);
    for (Vec3d& p : mesh.positions) {
        p.z = 0.22;
    }
    const double c = std::cos(M_PI / 9.0);
    const double s = std::sin(M_PI / 9.0);
    append(mesh, sheet(12, 1.0), [&](const Vec3d& p) {
        return Vec3d{p.x + 0.0123, p.y * c + 0.0171, p.y * s + 0.18};
    });
    const auto lowest = [](std::span<const Vec3d> x) {
        double z = std::numeric_limits<double>::infinity();
        for (const Vec3d& p : x) {
            z = std::min(z, p.z);
        }
        return z;
    };
    ASSERT_GT(lowest(mesh.positions), 0.005);

    geometry::TriangleMeshD unaware = mesh;  // untangled without obstacles
    expect_untangled_by_a_region_move(unaware, 20);
    EXPECT_LT(lowest(unaware.positions), -0.1);

    // The ground as a plane, as a triangle mesh (a 4 m square facing up), and as that mesh at
    // rest 1 m lower, moved up by its motion; a small plate far away blocks nothing.
    const auto square = [](double half, const Vec3d& centre) {
        geometry::TriangleMeshD m;
        for (const auto& [dx, dy] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
            m.positions.push_back(centre + Vec3d{dx * half, dy * half, 0.0});
        }
        m.triangles = {{0, 1, 2}, {0, 2, 3}};
        return std::make_shared<const MeshObstacle>(std::move(m));
    };
    Motion lift;
    lift.keyframes = {Keyframe{0.0, {0.0, 0.0, 1.0}}};
    enum class Ground { Plane, Mesh, MovedMesh, FarPlate };
    for (const Ground ground : {Ground::Plane, Ground::Mesh, Ground::MovedMesh, Ground::FarPlate}) {
        ClothSolver solver(mesh, ClothMaterial{});
        if (ground == Ground::Plane) {
            solver.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
        } else if (ground == Ground::Mesh) {
            solver.add_mesh_obstacle(square(2.0, {0.0, 0.0, 0.0}));
        } else if (ground == Ground::MovedMesh) {
            solver.add_mesh_obstacle(square(2.0, {0.0, 0.0, -1.0}), lift);
        } else {
            solver.add_mesh_obstacle(square(0.1, {5.0, 5.0, 0.0}));
        }
        const UntangleResult result = solver.untangle();
        const int g = static_cast<int>(ground);
        EXPECT_EQ(result.final_pairs, 0) << g;
        EXPECT_GE(result.region_moves, 1) << g;
        if (ground == Ground::FarPlate) {
            EXPECT_LT(lowest(solver.positions()), -0.1);  // it sinks, as without obstacles
        } else {
            EXPECT_GT(lowest(solver.positions()), 0.0) << g;
        }
        EXPECT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0);
    }
}

// The folded strip's cut-off flat part folds down through the other layer, its far edge to
// 0.5 m below the flat part (under the other layer). With a box there (clear of the input) the
// fold is not made, and as it is the only region the contour cuts off, the strip stays tangled:
// untangling reports the pairs it leaves rather than folding cloth into the box.
TEST(Untangle, ARegionThatWouldFoldIntoAnObstacleStays) {
    const geometry::TriangleMeshD mesh = strip_folded_through_itself();
    const BoxObstacle box{{-1.0, 0.5, -0.7}, {1.0, 0.75, -0.3}};
    const auto inside_box = [&](std::span<const Vec3d> x) {
        return std::count_if(x.begin(), x.end(), [&](const Vec3d& p) {
            return surface_distance(Obstacle{box}, p).distance < 0.0;
        });
    };
    ASSERT_EQ(inside_box(mesh.positions), 0);

    geometry::TriangleMeshD unaware = mesh;  // untangled without obstacles
    expect_untangled_by_a_region_move(unaware, 20);
    EXPECT_GT(inside_box(unaware.positions), 10);

    ClothSolver solver(mesh, ClothMaterial{});
    solver.add_obstacle(box);
    const UntangleResult aware = solver.untangle();
    EXPECT_EQ(aware.region_moves, 0);
    EXPECT_GT(aware.final_pairs, 0);
    EXPECT_LE(aware.final_pairs, aware.initial_pairs);
    EXPECT_EQ(inside_box(solver.positions()), 0);
    EXPECT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()),
              aware.final_pairs);
}

TEST(Untangle, IntersectionFreeInputIsLeftAlone) {
    geometry::TriangleMeshD mesh = sheet(10, 1.0);
    const std::vector<Vec3d> start = mesh.positions;
    const std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    const UntangleResult result = untangle(mesh.positions, mesh.triangles, inverse_masses);
    EXPECT_EQ(result.initial_pairs, 0);
    EXPECT_EQ(result.final_pairs, 0);
    EXPECT_EQ(result.iterations, 0);
    EXPECT_EQ(largest_move(mesh.positions, start), 0.0);
}

TEST(Untangle, BadInputIsAnError) {
    geometry::TriangleMeshD mesh = dent_through_sheet(0.06);
    std::vector<double> inverse_masses(mesh.positions.size(), 1.0);
    std::vector<double> short_masses(3, 1.0);
    EXPECT_THROW(untangle(mesh.positions, mesh.triangles, short_masses), InvalidInput);
    UntangleOptions negative;
    negative.step = -1.0;
    EXPECT_THROW(untangle(mesh.positions, mesh.triangles, inverse_masses, negative), InvalidInput);
    negative = {};
    negative.max_iterations = -1;
    EXPECT_THROW(untangle(mesh.positions, mesh.triangles, inverse_masses, negative), InvalidInput);
    geometry::TriangleMeshD broken = mesh;
    broken.positions[5].y = std::nan("");
    EXPECT_THROW(untangle(broken.positions, broken.triangles, inverse_masses), InvalidInput);
    broken = mesh;
    broken.triangles[3][1] = static_cast<std::int32_t>(broken.positions.size());
    EXPECT_THROW(untangle(broken.positions, broken.triangles, inverse_masses), InvalidInput);
}

}  // namespace
}  // namespace pliant::cloth
