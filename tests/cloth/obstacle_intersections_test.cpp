#include "pliant/cloth/obstacle_intersections.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <random>
#include <vector>

#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/triangle_intersection.hpp"

namespace pliant::cloth {
namespace {

// Independent reference for a box: the triangle clipped by the box's six closed half-spaces
// (Sutherland–Hodgman); it reaches into the box when anything is left.
bool clipped_by_box_is_not_empty(const BoxObstacle& box, const std::array<Vec3d, 3>& triangle) {
    std::vector<Vec3d> polygon(triangle.begin(), triangle.end());
    for (int axis = 0; axis < 3; ++axis) {
        for (const int side : {-1, 1}) {
            // Keep s · (p[axis] − bound) ≤ 0.
            const double bound = side < 0 ? box.min[axis] : box.max[axis];
            const auto offset = [&](const Vec3d& p) {
                return side * (p[axis] - bound);
            };
            std::vector<Vec3d> kept;
            for (std::size_t i = 0; i < polygon.size(); ++i) {
                const Vec3d& p = polygon[i];
                const Vec3d& q = polygon[(i + 1) % polygon.size()];
                const double op = offset(p);
                const double oq = offset(q);
                if (op <= 0.0) {
                    kept.push_back(p);
                }
                if ((op < 0.0 && oq > 0.0) || (op > 0.0 && oq < 0.0)) {
                    kept.push_back(p + (q - p) * (op / (op - oq)));
                }
            }
            polygon = std::move(kept);
            if (polygon.empty()) {
                return false;
            }
        }
    }
    return true;
}

// The smallest f(p) over the points p of a barycentric grid of n + 1 points per edge on the
// triangle (its corners included).
template <typename F>
double smallest_on_grid(const std::array<Vec3d, 3>& t, int n, F&& f) {
    double best = INFINITY;
    for (int i = 0; i <= n; ++i) {
        for (int j = 0; i + j <= n; ++j) {
            const double u = static_cast<double>(i) / n;
            const double v = static_cast<double>(j) / n;
            best = std::min(best, f(t[0] * (1.0 - u - v) + t[1] * u + t[2] * v));
        }
    }
    return best;
}

std::array<Vec3d, 3> random_triangle(std::mt19937_64& random) {
    std::uniform_real_distribution<double> centre(-1.0, 1.0);
    std::uniform_real_distribution<double> spread(-0.6, 0.6);
    const Vec3d c{centre(random), centre(random), centre(random)};
    return {c + Vec3d{spread(random), spread(random), spread(random)},
            c + Vec3d{spread(random), spread(random), spread(random)},
            c + Vec3d{spread(random), spread(random), spread(random)}};
}

TEST(ObstacleIntersections, BoxesMatchClipping) {
    const BoxObstacle box{{-0.3, -0.2, -0.4}, {0.4, 0.3, 0.2}};
    std::mt19937_64 random(11);
    int reaching = 0;
    int corners_outside = 0;
    for (int i = 0; i < 20000; ++i) {
        const std::array<Vec3d, 3> t = random_triangle(random);
        const bool expected = clipped_by_box_is_not_empty(box, t);
        ASSERT_EQ(triangle_reaches_into(box, t[0], t[1], t[2]), expected) << "triangle " << i;
        reaching += expected ? 1 : 0;
        const auto inside = [&](const Vec3d& p) {
            return p.x >= box.min.x && p.x <= box.max.x && p.y >= box.min.y && p.y <= box.max.y &&
                   p.z >= box.min.z && p.z <= box.max.z;
        };
        corners_outside += expected && !inside(t[0]) && !inside(t[1]) && !inside(t[2]) ? 1 : 0;
    }
    // Both answers occur, and many triangles cut into the box with every corner outside it.
    EXPECT_GT(reaching, 2000);
    EXPECT_LT(reaching, 18000);
    EXPECT_GT(corners_outside, 500);
}

TEST(ObstacleIntersections, SpheresAndPlanesMatchSampling) {
    const SphereObstacle sphere{{0.1, -0.1, 0.2}, 0.35};
    const PlaneObstacle plane{{0.0, 0.0, 0.1}, {0.2, -0.3, 1.0}};
    std::mt19937_64 random(12);
    int reaching = 0;
    for (int i = 0; i < 4000; ++i) {
        const std::array<Vec3d, 3> t = random_triangle(random);
        // The grid's points are within spacing · longest edge of every point of the triangle.
        const double longest = std::max({norm(t[1] - t[0]), norm(t[2] - t[1]), norm(t[0] - t[2])});
        const int n = 64;
        // An upper bound of the distance from the centre, within the grid's spacing of it.
        const double d =
            smallest_on_grid(t, n, [&](const Vec3d& p) { return norm(p - sphere.center); });
        const bool reaches = triangle_reaches_into(sphere, t[0], t[1], t[2]);
        if (d <= sphere.radius) {
            EXPECT_TRUE(reaches) << "triangle " << i;
        } else if (d > sphere.radius + longest / n) {
            EXPECT_FALSE(reaches) << "triangle " << i;
        }
        reaching += reaches ? 1 : 0;
        // The plane: the smallest offset along the normal over the grid (linear: at a corner).
        const double lowest = smallest_on_grid(
            t, n, [&](const Vec3d& p) { return dot(p - plane.point, plane.normal); });
        EXPECT_EQ(triangle_reaches_into(plane, t[0], t[1], t[2]), lowest <= 0.0) << i;
    }
    EXPECT_GT(reaching, 200);
}

// A sheet of 30 × 30 quads, 1 m square at z = 0.
ClothModel sheet() {
    return ClothModel(geometry::convert_precision<double>(geometry::make_grid_sheet(30, 30, 1, 1)),
                      ClothMaterial{});
}

TEST(ObstacleIntersections, CountsMeshObstaclesWherePlacedAndAnalyticOnes) {
    ClothModel model = sheet();
    EXPECT_EQ(count_obstacle_intersections(model), 0);
    // A closed box mesh well below the sheet, moved up through it by its motion (a constant
    // translation: placed there from time 0).
    const geometry::TriangleMeshD box = geometry::make_box({-0.2, -0.1, -1.3}, {0.1, 0.2, -0.9});
    Motion lift;
    lift.keyframes = {Keyframe{0.0, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}}};
    model.add_mesh_obstacle(std::make_shared<const MeshObstacle>(box), lift);
    // The reference: every (cloth triangle, placed box triangle) pair, exactly.
    std::vector<Vec3d> placed;
    for (const Vec3d& p : box.positions) {
        placed.push_back(p + Vec3d{0.0, 0.0, 1.0});
    }
    const auto cloth_at = [&](std::int32_t v) {
        return model.positions()[static_cast<std::size_t>(v)];
    };
    std::int64_t expected = 0;
    for (const geometry::Triangle& c : model.triangles()) {
        for (const geometry::Triangle& b : box.triangles) {
            expected +=
                geometry::triangles_intersect(cloth_at(c[0]), cloth_at(c[1]), cloth_at(c[2]),
                                              placed[static_cast<std::size_t>(b[0])],
                                              placed[static_cast<std::size_t>(b[1])],
                                              placed[static_cast<std::size_t>(b[2])])
                    ? 1
                    : 0;
        }
    }
    EXPECT_GT(expected, 10);
    EXPECT_EQ(count_obstacle_intersections(model), expected);

    // A sphere that reaches 5 cm above the sheet's plane from below, and a plane under it: the
    // sphere adds the triangles within 0.3 m of its centre.
    const SphereObstacle sphere{{0.3, 0.3, -0.25}, 0.3};
    model.add_obstacle(sphere);
    model.add_obstacle(PlaneObstacle{{0.0, 0.0, -0.5}, {0.0, 0.0, 1.0}});
    std::int64_t in_sphere = 0;
    for (const geometry::Triangle& c : model.triangles()) {
        in_sphere +=
            triangle_reaches_into(sphere, cloth_at(c[0]), cloth_at(c[1]), cloth_at(c[2])) ? 1 : 0;
    }
    // The cap's disc has radius √(0.3² − 0.25²) ≈ 0.166 m: about 0.087 m² of the sheet's 1 m²
    // (1,800 triangles).
    EXPECT_GT(in_sphere, 100);
    EXPECT_LT(in_sphere, 300);
    set_num_threads(1);
    const std::int64_t one = count_obstacle_intersections(model);
    set_num_threads(2);
    const std::int64_t two = count_obstacle_intersections(model);
    set_num_threads(0);
    EXPECT_EQ(one, expected + in_sphere);
    EXPECT_EQ(two, one);
}

}  // namespace
}  // namespace pliant::cloth
