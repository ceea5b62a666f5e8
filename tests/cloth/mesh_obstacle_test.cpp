#include "pliant/cloth/mesh_obstacle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <span>
#include <string>

#include "pliant/collision/point_triangle.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

using geometry::Triangle;
using geometry::TriangleMeshD;

// An icosahedron subdivided `levels` times, projected onto the sphere (20·4^levels triangles,
// counter-clockwise seen from outside).
TriangleMeshD icosphere(int levels, double radius, const Vec3d& center) {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> p{{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                         {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
    std::vector<Triangle> t{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (Vec3d& v : p) {
        v = v * (1.0 / norm(v));
    }
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<int, int>, int> midpoints;
        const auto midpoint = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            const auto [it, inserted] = midpoints.try_emplace(key, static_cast<int>(p.size()));
            if (inserted) {
                const Vec3d m = p[static_cast<std::size_t>(a)] + p[static_cast<std::size_t>(b)];
                p.push_back(m * (1.0 / norm(m)));
            }
            return it->second;
        };
        std::vector<Triangle> finer;
        for (const Triangle& tri : t) {
            const int ab = midpoint(tri[0], tri[1]);
            const int bc = midpoint(tri[1], tri[2]);
            const int ca = midpoint(tri[2], tri[0]);
            finer.push_back({tri[0], ab, ca});
            finer.push_back({ab, tri[1], bc});
            finer.push_back({ca, bc, tri[2]});
            finer.push_back({ab, bc, ca});
        }
        t = std::move(finer);
    }
    TriangleMeshD mesh;
    for (const Vec3d& v : p) {
        mesh.positions.push_back(center + v * radius);
    }
    mesh.triangles = std::move(t);
    return mesh;
}

// The closed surface of a union of unit voxels (filled(i, j, k) on an n³ grid), scaled by `scale`
// and moved by `offset`; each boundary square split into two triangles along a diagonal that
// alternates with position, so corners meet different numbers of triangles per face. Concave
// edges and corners wherever the shape is notched. Outward counter-clockwise.
template <typename Filled>
TriangleMeshD voxel_surface(int n, Filled&& filled, double scale, const Vec3d& offset) {
    TriangleMeshD mesh;
    std::map<std::array<int, 3>, int> vertex_ids;
    const auto vertex = [&](std::array<int, 3> c) {
        const auto [it, inserted] =
            vertex_ids.try_emplace(c, static_cast<int>(mesh.positions.size()));
        if (inserted) {
            mesh.positions.push_back(offset + Vec3d{c[0] * scale, c[1] * scale, c[2] * scale});
        }
        return it->second;
    };
    const auto inside = [&](int i, int j, int k) {
        return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n && filled(i, j, k);
    };
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            for (int k = 0; k < n; ++k) {
                if (!inside(i, j, k)) {
                    continue;
                }
                for (int axis = 0; axis < 3; ++axis) {
                    for (const int side : {-1, 1}) {
                        std::array<int, 3> cell{i, j, k};
                        std::array<int, 3> neighbour = cell;
                        neighbour[static_cast<std::size_t>(axis)] += side;
                        if (inside(neighbour[0], neighbour[1], neighbour[2])) {
                            continue;
                        }
                        const auto u = static_cast<std::size_t>((axis + 1) % 3);
                        const auto w = static_cast<std::size_t>((axis + 2) % 3);
                        std::array<int, 3> base = cell;
                        base[static_cast<std::size_t>(axis)] += side > 0 ? 1 : 0;
                        std::array<std::array<int, 3>, 4> c{base, base, base, base};
                        c[1][u] += 1;
                        c[2][u] += 1;
                        c[2][w] += 1;
                        c[3][w] += 1;
                        if (side < 0) {
                            std::swap(c[1], c[3]);
                        }
                        const int q[4] = {vertex(c[0]), vertex(c[1]), vertex(c[2]), vertex(c[3])};
                        if ((i + j + k + axis) % 2 == 0) {
                            mesh.triangles.push_back({q[0], q[1], q[2]});
                            mesh.triangles.push_back({q[0], q[2], q[3]});
                        } else {
                            mesh.triangles.push_back({q[0], q[1], q[3]});
                            mesh.triangles.push_back({q[1], q[2], q[3]});
                        }
                    }
                }
            }
        }
    }
    return mesh;
}

// A 3×3×3 block with a corner voxel and a voxel from the middle of a top edge removed.
TriangleMeshD notched_block(double scale, const Vec3d& offset) {
    return voxel_surface(
        3,
        [](int i, int j, int k) {
            return !(i == 2 && j == 2 && k == 2) && !(i == 1 && j == 0 && k == 2);
        },
        scale, offset);
}

TriangleMeshD unit_cube() {
    return voxel_surface(1, [](int, int, int) { return true; }, 1.0, {0.0, 0.0, 0.0});
}

const Vec3d& corner(const TriangleMeshD& mesh, std::size_t t, int k) {
    return mesh.positions[static_cast<std::size_t>(mesh.triangles[t][static_cast<std::size_t>(k)])];
}

// The least unsigned distance over all triangles.
double brute_force_distance(const TriangleMeshD& mesh, const Vec3d& x) {
    double best = INFINITY;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        best = std::min(best, collision::point_triangle_proximity(
                                  x, corner(mesh, t, 0), corner(mesh, t, 1), corner(mesh, t, 2))
                                  .distance);
    }
    return best;
}

// Generalized winding number (sum of the triangles' signed solid angles over 4π, A. Van Oosterom
// and J. Strackee 1983): 1 inside a closed outward-oriented surface, 0 outside.
double winding_number(const TriangleMeshD& mesh, const Vec3d& x) {
    double sum = 0.0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3d a = corner(mesh, t, 0) - x;
        const Vec3d b = corner(mesh, t, 1) - x;
        const Vec3d c = corner(mesh, t, 2) - x;
        const double la = norm(a), lb = norm(b), lc = norm(c);
        const double numerator = dot(a, cross(b, c));
        const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        sum += 2.0 * std::atan2(numerator, denominator);
    }
    return sum / (4.0 * std::numbers::pi);
}

std::vector<Vec3d> random_points(int n, const Vec3d& lo, const Vec3d& hi, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3d> points;
    for (int i = 0; i < n; ++i) {
        points.push_back({lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
                          lo.z + (hi.z - lo.z) * u(rng)});
    }
    return points;
}

void expect_unit(const Vec3d& n) {
    EXPECT_NEAR(norm(n), 1.0, 1e-12) << n.x << " " << n.y << " " << n.z;
}

void expect_near(const Vec3d& a, const Vec3d& b, double tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "(no InvalidInput thrown)";
}

TEST(MeshObstacle, IcosphereMatchesBruteForceConvexInsideTestAndTheSphere) {
    const Vec3d center{0.1, -0.2, 0.3};
    const double radius = 0.5;
    const TriangleMeshD mesh = icosphere(3, radius, center);
    const MeshObstacle obstacle(mesh);
    // Tessellation error: the sphere lies between the polyhedron's inscribed distance and radius.
    double inscribed = radius;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3d n = obstacle.face_normals()[t];
        ASSERT_GT(dot(n, corner(mesh, t, 0) - center), 0.0) << "triangle " << t << " inward";
        inscribed = std::min(inscribed, dot(n, corner(mesh, t, 0) - center));
    }
    const double tessellation = radius - inscribed;
    ASSERT_LT(tessellation, 0.01);
    int inside_count = 0;
    for (const Vec3d& x :
         random_points(1500, center - Vec3d{1, 1, 1}, center + Vec3d{1, 1, 1}, 1)) {
        const double expected = brute_force_distance(mesh, x);
        bool behind_every_face = true;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            behind_every_face &= dot(x - corner(mesh, t, 0), obstacle.face_normals()[t]) < 0.0;
        }
        const auto s = obstacle.surface_distance(x, INFINITY);
        ASSERT_TRUE(s.has_value());
        EXPECT_EQ(std::abs(s->distance), expected);
        EXPECT_EQ(s->distance < 0.0, behind_every_face) << x.x << " " << x.y << " " << x.z;
        inside_count += behind_every_face ? 1 : 0;
        expect_unit(s->normal);
        EXPECT_NEAR(s->distance, norm(x - center) - radius, tessellation + 1e-12);
        if (norm(x - center) > 0.3) {
            EXPECT_GT(dot(s->normal, (x - center) * (1.0 / norm(x - center))), 0.99);
        }
        // A finite radius finds the same answer exactly when it is within reach.
        const auto near = obstacle.surface_distance(x, 0.1);
        EXPECT_EQ(near.has_value(), expected <= 0.1);
        if (near) {
            EXPECT_EQ(near->distance, s->distance);
            EXPECT_EQ(near->normal, s->normal);
        }
    }
    EXPECT_GT(inside_count, 50);  // the sample has both sides
}

// Distances equal brute force and the sign equals the winding number's inside test on `points`
// (those on the surface excepted); returns the number of inside points.
int expect_matches_brute_force_and_winding_number(const TriangleMeshD& mesh,
                                                  std::span<const Vec3d> points) {
    const MeshObstacle obstacle(mesh);
    int inside_count = 0;
    for (const Vec3d& x : points) {
        const double expected = brute_force_distance(mesh, x);
        const auto s = obstacle.surface_distance(x, INFINITY);
        EXPECT_TRUE(s.has_value());
        if (!s) {
            continue;
        }
        EXPECT_EQ(std::abs(s->distance), expected);
        expect_unit(s->normal);
        if (expected < 1e-9) {
            continue;
        }
        const bool inside = winding_number(mesh, x) > 0.5;
        EXPECT_EQ(s->distance < 0.0, inside) << x.x << " " << x.y << " " << x.z;
        inside_count += inside ? 1 : 0;
    }
    return inside_count;
}

TEST(MeshObstacle, NotchedBlockMatchesBruteForceAndWindingNumber) {
    // Non-convex: concave edges and corners (the notches).
    const double scale = 0.37;
    const Vec3d offset{0.1, -0.25, 0.05};
    const TriangleMeshD mesh = notched_block(scale, offset);
    std::vector<Vec3d> points =
        random_points(1500, offset - Vec3d{0.3, 0.3, 0.3}, offset + Vec3d{1.4, 1.4, 1.4}, 2);
    // Around the corner notch's inner corner (a concave vertex) and its concave edges, both sides.
    const Vec3d notch = offset + Vec3d{2.0, 2.0, 2.0} * scale;
    for (const Vec3d& d : random_points(500, {-0.08, -0.08, -0.08}, {0.08, 0.08, 0.08}, 3)) {
        points.push_back(notch + d);
    }
    const Vec3d edge_notch = offset + Vec3d{1.5, 1.0, 2.0} * scale;
    for (const Vec3d& d : random_points(300, {-0.2, -0.05, -0.05}, {0.2, 0.05, 0.05}, 4)) {
        points.push_back(edge_notch + d);
    }
    EXPECT_GT(expect_matches_brute_force_and_winding_number(mesh, points), 300);
}

TEST(MeshObstacle, SpikyStarMatchesBruteForceAndWindingNumber) {
    // Sharp spikes (faces meeting at far more than 90°) and saddle vertices between them: there
    // the normal of one triangle at the closest vertex or edge gives the wrong side, only the
    // pseudo-normals give the right one.
    TriangleMeshD mesh = icosphere(1, 0.3, {0.0, 0.0, 0.0});
    for (std::size_t v = 0; v < mesh.positions.size(); v += 3) {
        mesh.positions[v] = mesh.positions[v] * (v % 2 == 0 ? 3.0 : 0.5);
    }
    std::vector<Vec3d> points = random_points(1500, {-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}, 10);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {  // around every vertex
        for (const Vec3d& d : random_points(20, {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05},
                                            static_cast<std::uint32_t>(100 + v))) {
            points.push_back(mesh.positions[v] + d);
        }
    }
    EXPECT_GT(expect_matches_brute_force_and_winding_number(mesh, points), 100);
}

TEST(MeshObstacle, CubeCornersEdgesAndFacesGetTheirFeatureNormals) {
    const MeshObstacle cube(unit_cube());
    const double r3 = 1.0 / std::sqrt(3.0);
    const double r2 = 1.0 / std::sqrt(2.0);
    // Outside a corner, an edge, a face.
    auto s = cube.surface_distance({1.1, 1.1, 1.1}, 1.0);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->distance, 0.1 * std::sqrt(3.0), 1e-15);
    expect_near(s->normal, {r3, r3, r3}, 1e-15);
    s = cube.surface_distance({-0.2, 0.4, -0.2}, 1.0);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->distance, 0.2 * std::sqrt(2.0), 1e-15);
    expect_near(s->normal, {-r2, 0.0, -r2}, 1e-15);
    s = cube.surface_distance({0.3, 1.25, 0.6}, 1.0);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->distance, 0.25, 1e-15);
    expect_near(s->normal, {0.0, 1.0, 0.0}, 1e-15);
    // Inside near a corner: the nearest face.
    s = cube.surface_distance({0.95, 0.9, 0.92}, 1.0);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->distance, -0.05, 1e-15);
    expect_near(s->normal, {1.0, 0.0, 0.0}, 1e-15);
    // On the surface: the feature's pseudo-normal. Every corner meets one or two triangles per
    // face, but the angles at it sum to π/2 per face, so the angle-weighted normal is the
    // diagonal (an unweighted average would tilt towards the faces split at that corner).
    for (const Vec3d& c : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 1}, Vec3d{1, 1, 1}}) {
        s = cube.surface_distance(c, 0.0);
        ASSERT_TRUE(s);
        EXPECT_EQ(s->distance, 0.0);
        expect_near(s->normal, (c * 2.0 - Vec3d{1, 1, 1}) * r3, 1e-15);
    }
    s = cube.surface_distance({1.0, 0.5, 0.0}, 0.0);  // on an edge of the cube
    ASSERT_TRUE(s);
    expect_near(s->normal, {r2, 0.0, -r2}, 1e-15);
    s = cube.surface_distance({0.5, 0.5, 1.0}, 0.0);  // on a face diagonal
    ASSERT_TRUE(s);
    expect_near(s->normal, {0.0, 0.0, 1.0}, 1e-15);
    // Vertex pseudo-normals of the cube are (angle π/2 per face) · diagonal direction.
    for (std::size_t v = 0; v < cube.mesh().positions.size(); ++v) {
        const Vec3d expected =
            (cube.mesh().positions[v] * 2.0 - Vec3d{1, 1, 1}) * (0.5 * std::numbers::pi);
        expect_near(cube.vertex_normals()[v], expected, 1e-14);
    }
}

TEST(MeshObstacle, OpenSheetIsOutsideOnItsNormalsSide) {
    // A flat sheet (normals +z), tilted: the signed distance's sign is the side of the plane,
    // also beyond the boundary edges and corners; reversing the winding reverses it.
    const geometry::TriangleMesh sheet = geometry::make_grid_sheet(20, 16, 1.0f, 0.8f);
    TriangleMeshD mesh = geometry::convert_precision<double>(sheet);
    const double angle = 0.4;
    for (Vec3d& p : mesh.positions) {
        p = Vec3d{p.x, std::cos(angle) * p.y - std::sin(angle) * p.z,
                  std::sin(angle) * p.y + std::cos(angle) * p.z};
    }
    const Vec3d plane_normal{0.0, -std::sin(angle), std::cos(angle)};
    TriangleMeshD flipped = mesh;
    for (Triangle& t : flipped.triangles) {
        std::swap(t[1], t[2]);
    }
    const MeshObstacle up(mesh);
    const MeshObstacle down(flipped);
    int beyond_boundary = 0;
    for (const Vec3d& x : random_points(1000, {-0.9, -0.8, -0.5}, {0.9, 0.8, 0.5}, 5)) {
        const double side = dot(x, plane_normal);
        const auto a = up.surface_distance(x, INFINITY);
        const auto b = down.surface_distance(x, INFINITY);
        ASSERT_TRUE(a && b);
        EXPECT_EQ(std::abs(a->distance), brute_force_distance(mesh, x));
        EXPECT_NEAR(a->distance, -b->distance, 1e-15);
        if (std::abs(side) > 1e-12) {
            EXPECT_EQ(a->distance > 0.0, side > 0.0) << x.x << " " << x.y << " " << x.z;
        }
        beyond_boundary += std::abs(x.x) > 0.5 ? 1 : 0;
    }
    EXPECT_GT(beyond_boundary, 200);
}

TEST(MeshObstacle, SetPositionsMovesTheAnswersAndMatchesAFreshBuild) {
    const TriangleMeshD mesh = notched_block(0.3, {0.0, 0.0, 0.0});
    MeshObstacle moving(mesh);
    const Vec3d shift{0.7, -0.2, 1.3};
    std::vector<Vec3d> shifted;
    for (const Vec3d& p : mesh.positions) {
        shifted.push_back(p + shift);
    }
    moving.set_positions(shifted);
    EXPECT_EQ(moving.mesh().positions, shifted);
    const MeshObstacle still(mesh);
    const auto points = random_points(500, {-0.2, -0.2, -0.2}, {1.1, 1.1, 1.1}, 6);
    for (const Vec3d& x : points) {
        const auto a = still.surface_distance(x, 0.2);
        const auto b = moving.surface_distance(x + shift, 0.2);
        ASSERT_EQ(a.has_value(), b.has_value());
        if (a) {
            EXPECT_NEAR(a->distance, b->distance, 1e-12);
            expect_near(a->normal, b->normal, 1e-9);
        }
    }
    // A non-rigid deformation: refit answers equal a fresh build's, bit for bit.
    std::vector<Vec3d> bent;
    for (const Vec3d& p : mesh.positions) {
        bent.push_back({1.5 * p.x, p.y + 0.3 * std::sin(4.0 * p.x), 0.8 * p.z});
    }
    moving.set_positions(bent);
    TriangleMeshD bent_mesh = mesh;
    bent_mesh.positions = bent;
    const MeshObstacle fresh(bent_mesh);
    for (const Vec3d& x : points) {
        const auto a = fresh.surface_distance(x, 0.15);
        const auto b = moving.surface_distance(x, 0.15);
        ASSERT_EQ(a.has_value(), b.has_value());
        if (a) {
            EXPECT_EQ(a->distance, b->distance);
            EXPECT_EQ(a->normal, b->normal);
        }
    }
    EXPECT_EQ(std::vector<Vec3d>(fresh.vertex_normals().begin(), fresh.vertex_normals().end()),
              std::vector<Vec3d>(moving.vertex_normals().begin(), moving.vertex_normals().end()));
    EXPECT_EQ(fresh.bounds(), moving.bounds());
}

TEST(MeshObstacle, NothingBeyondMaxDistance) {
    const MeshObstacle sphere(icosphere(2, 0.5, {0.0, 0.0, 0.0}));
    const Vec3d x{0.05, 0.1, 0.8};
    const auto far = sphere.surface_distance(x, INFINITY);
    ASSERT_TRUE(far);
    EXPECT_GT(far->distance, 0.3);
    // Inclusive: found at exactly its distance, not just below it.
    EXPECT_TRUE(sphere.surface_distance(x, far->distance));
    EXPECT_FALSE(sphere.surface_distance(x, std::nextafter(far->distance, 0.0)));
    EXPECT_FALSE(sphere.surface_distance(x, 0.1));
    // Deep inside a closed mesh: the caller's radius does not reach the surface.
    EXPECT_FALSE(sphere.surface_distance({0.0, 0.0, 0.0}, 0.3));
    const auto deep = sphere.surface_distance({0.0, 0.0, 0.0}, 0.5);
    ASSERT_TRUE(deep);
    EXPECT_LT(deep->distance, -0.45);
    // A vertex of the mesh with radius 0; invalid radii and points find nothing.
    const Vec3d vertex = sphere.mesh().positions[3];
    const auto on = sphere.surface_distance(vertex, 0.0);
    ASSERT_TRUE(on);
    EXPECT_EQ(on->distance, 0.0);
    EXPECT_GT(dot(on->normal, vertex), 0.99 * 0.5);
    EXPECT_FALSE(sphere.surface_distance(x, -1.0));
    EXPECT_FALSE(sphere.surface_distance(x, NAN));
    EXPECT_FALSE(sphere.surface_distance({NAN, 0.0, 0.0}, INFINITY));
}

TEST(MeshObstacle, PushOutPlacesPointsAtThickness) {
    const MeshObstacle sphere(icosphere(3, 0.5, {0.0, 0.0, 0.2}));
    const double thickness = 0.01;
    const double max_depth = 0.05;
    int pushed = 0;
    for (Vec3d x : random_points(2000, {-0.6, -0.6, -0.4}, {0.6, 0.6, 0.8}, 7)) {
        const auto before = sphere.surface_distance(x, INFINITY);
        ASSERT_TRUE(before);
        const Vec3d original = x;
        const ContactCorrection contact = push_out(sphere, x, thickness, max_depth);
        if (before->distance < thickness && before->distance >= -max_depth) {
            EXPECT_NEAR(contact.depth, thickness - before->distance, 1e-15);
            EXPECT_EQ(contact.normal, before->normal);
            // Convex: the point is now exactly `thickness` from the surface.
            const auto after = sphere.surface_distance(x, INFINITY);
            EXPECT_NEAR(after->distance, thickness, 1e-12);
            ++pushed;
        } else {
            EXPECT_EQ(contact.depth, 0.0);
            EXPECT_EQ(x, original);
        }
    }
    EXPECT_GT(pushed, 20);
    // Nothing within reach: no move, zero normal.
    Vec3d far{3.0, 0.0, 0.0};
    const ContactCorrection none = push_out(sphere, far, thickness, max_depth);
    EXPECT_EQ(none.depth, 0.0);
    EXPECT_EQ(none.normal, Vec3d{});
    // Into a concave corner of the notched block: out along the nearest face's normal.
    const MeshObstacle block(notched_block(1.0, {0.0, 0.0, 0.0}));
    Vec3d x{2.2, 2.5, 1.97};  // 0.03 under the floor (z = 2) of the removed corner voxel
    const ContactCorrection contact = push_out(block, x, 0.01, 0.1);
    EXPECT_NEAR(contact.depth, 0.04, 1e-12);
    expect_near(contact.normal, {0.0, 0.0, 1.0}, 1e-15);
}

// The enclosed volume: a box's, negative when every triangle is reversed (wound inward), and
// none for an open mesh or a closed one wound inconsistently.
TEST(MeshObstacle, EnclosedVolumeOfClosedMeshesOnly) {
    geometry::TriangleMeshD box = geometry::make_box({-0.5, 0.0, 1.0}, {1.5, 0.5, 4.0});
    ASSERT_TRUE(MeshObstacle(box).enclosed_volume().has_value());
    EXPECT_NEAR(*MeshObstacle(box).enclosed_volume(), 2.0 * 0.5 * 3.0, 1e-12);
    geometry::TriangleMeshD inward = box;
    for (geometry::Triangle& t : inward.triangles) {
        std::swap(t[1], t[2]);
    }
    EXPECT_NEAR(*MeshObstacle(inward).enclosed_volume(), -3.0, 1e-12);
    geometry::TriangleMeshD mixed = box;
    std::swap(mixed.triangles[0][1], mixed.triangles[0][2]);
    EXPECT_FALSE(MeshObstacle(mixed).enclosed_volume().has_value());
    geometry::TriangleMeshD open = box;
    open.triangles.pop_back();
    EXPECT_FALSE(MeshObstacle(open).enclosed_volume().has_value());
}

TEST(MeshObstacle, RejectsBadInput) {
    TriangleMeshD mesh = icosphere(0, 1.0, {0.0, 0.0, 0.0});
    EXPECT_NE(message_of([] { MeshObstacle{TriangleMeshD{}}; }).find("no triangles"),
              std::string::npos);
    TriangleMeshD bad = mesh;
    bad.triangles[5][1] = 12;
    std::string message = message_of([&] { MeshObstacle{bad}; });
    EXPECT_NE(message.find("triangle 5"), std::string::npos) << message;
    EXPECT_NE(message.find("12"), std::string::npos) << message;
    bad = mesh;
    bad.triangles[7] = {3, 4, 3};
    message = message_of([&] { MeshObstacle{bad}; });
    EXPECT_NE(message.find("triangle 7 repeats"), std::string::npos) << message;
    bad = mesh;
    bad.positions[9].y = INFINITY;
    message = message_of([&] { MeshObstacle{bad}; });
    EXPECT_NE(message.find("vertex 9"), std::string::npos) << message;

    MeshObstacle obstacle(mesh);
    std::vector<Vec3d> positions = mesh.positions;
    positions.pop_back();
    message = message_of([&] { obstacle.set_positions(positions); });
    EXPECT_NE(message.find("positions.size() (11)"), std::string::npos) << message;
    positions = mesh.positions;
    positions[4].z = NAN;
    message = message_of([&] { obstacle.set_positions(positions); });
    EXPECT_NE(message.find("vertex 4"), std::string::npos) << message;
    EXPECT_EQ(obstacle.mesh().positions, mesh.positions);  // a rejected update changes nothing
}

TEST(MeshObstacle, DegenerateTrianglesAndUnusedVerticesAreData) {
    TriangleMeshD mesh = unit_cube();
    const auto base = static_cast<std::int32_t>(mesh.positions.size());
    // A zero-area sliver (collinear corners) and an unused vertex, beside the cube.
    mesh.positions.push_back({2.0, 0.0, 0.0});
    mesh.positions.push_back({2.5, 0.0, 0.0});
    mesh.positions.push_back({3.0, 0.0, 0.0});
    mesh.positions.push_back({9.0, 9.0, 9.0});
    mesh.triangles.push_back({base, base + 1, base + 2});
    const MeshObstacle obstacle(mesh);
    EXPECT_EQ(obstacle.face_normals().back(), Vec3d{});
    EXPECT_EQ(obstacle.vertex_normals().back(), Vec3d{});
    const auto s = obstacle.surface_distance({2.5, 0.0, 0.2}, 1.0);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->distance, 0.2, 1e-15);  // no pseudo-normal there: taken as outside
    expect_unit(s->normal);
    const auto on = obstacle.surface_distance({2.2, 0.0, 0.0}, 1.0);
    ASSERT_TRUE(on);
    EXPECT_EQ(on->distance, 0.0);
    expect_unit(on->normal);
    const auto cube = obstacle.surface_distance({0.5, 0.5, 0.45}, 1.0);
    ASSERT_TRUE(cube);
    EXPECT_NEAR(cube->distance, -0.45, 1e-15);
    // One triangle.
    const MeshObstacle single(TriangleMeshD{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    const auto below = single.surface_distance({0.2, 0.2, -0.1}, 1.0);
    ASSERT_TRUE(below);
    EXPECT_NEAR(below->distance, -0.1, 1e-15);
    expect_near(below->normal, {0.0, 0.0, 1.0}, 1e-15);
}

TEST(MeshObstacle, ScaleInvariance) {
    const TriangleMeshD unit = notched_block(1.0, {0.1, 0.2, 0.3});
    const MeshObstacle reference(unit);
    const auto points = random_points(300, {-0.5, -0.5, -0.5}, {3.5, 3.5, 3.5}, 8);
    for (const double scale : {1e-6, 1e6}) {
        TriangleMeshD scaled = unit;
        for (Vec3d& p : scaled.positions) {
            p = p * scale;
        }
        const MeshObstacle obstacle(scaled);
        for (const Vec3d& x : points) {
            const auto a = reference.surface_distance(x, 0.5);
            const auto b = obstacle.surface_distance(x * scale, 0.5 * scale);
            ASSERT_EQ(a.has_value(), b.has_value());
            if (a) {
                EXPECT_NEAR(b->distance / scale, a->distance, 1e-12);
                expect_near(b->normal, a->normal, 1e-9);
            }
        }
    }
}

TEST(MeshObstacle, BitwiseIdenticalForOneAndManyThreads) {
    const TriangleMeshD mesh = icosphere(4, 0.5, {0.0, 0.0, 0.0});
    std::vector<Vec3d> moved;
    for (const Vec3d& p : mesh.positions) {
        moved.push_back({p.x * 1.2, p.y + 0.1 * std::sin(7.0 * p.z), p.z});
    }
    const auto points = random_points(4000, {-0.7, -0.7, -0.7}, {0.7, 0.7, 0.7}, 9);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        MeshObstacle obstacle(mesh);
        obstacle.set_positions(moved);
        std::vector<std::optional<SurfaceDistance>> answers(points.size());
        parallel_for(
            static_cast<std::int64_t>(points.size()),
            [&](std::int64_t i) {
                const auto k = static_cast<std::size_t>(i);
                answers[k] = obstacle.surface_distance(points[k], 0.05);
            },
            256);
        std::vector<double> out;
        for (const Vec3d& n : obstacle.vertex_normals()) {
            out.insert(out.end(), {n.x, n.y, n.z});
        }
        for (const Vec3d& n : obstacle.edge_normals()) {
            out.insert(out.end(), {n.x, n.y, n.z});
        }
        for (const auto& a : answers) {
            out.insert(out.end(), {a ? a->distance : 1e300, a ? a->normal.x : 0.0,
                                   a ? a->normal.y : 0.0, a ? a->normal.z : 0.0});
        }
        return out;
    };
    const auto one = run(1);
    const auto many = run(4);
    set_num_threads(0);
    ASSERT_EQ(one.size(), many.size());
    EXPECT_EQ(std::memcmp(one.data(), many.data(), one.size() * sizeof(double)), 0);
}

}  // namespace
}  // namespace pliant::cloth
