#include "pliant/geometry/fit_plane.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pliant::geometry {
namespace {

constexpr std::int32_t ALL[] = {0, 1};

// Two triangles hinged on the y axis: the first in the plane z = 0 (normal +z), the second
// rotated by `angle` about the hinge, wound as the first (its normal turned by `angle`).
std::vector<Vec3d> hinge(double angle) {
    return {{0.0, 0.0, 0.0},
            {0.0, 1.0, 0.0},
            {1.0, 0.0, 0.0},
            {-std::cos(angle), 0.0, std::sin(angle)}};
}
const std::vector<Triangle> HINGE_TRIANGLES{{0, 2, 1}, {0, 1, 3}};

TEST(FitPlane, TrianglesInOnePlaneGiveItWithTheAreaWeightedCentre) {
    // A unit right triangle and one four times its area beside it, both in z = 2 facing +z.
    const std::vector<Vec3d> x{{0.0, 0.0, 2.0}, {1.0, 0.0, 2.0}, {0.0, 1.0, 2.0},
                               {3.0, 0.0, 2.0}, {5.0, 0.0, 2.0}, {3.0, 2.0, 2.0}};
    const std::vector<Triangle> triangles{{0, 1, 2}, {3, 4, 5}};
    const std::optional<FittedPlane> plane = fit_plane(x, triangles, ALL, 0.5);
    ASSERT_TRUE(plane.has_value());
    EXPECT_EQ(plane->normal, (Vec3d{0.0, 0.0, 1.0}));
    // Centroids (1/3, 1/3) with weight 1 and (11/3, 2/3) with weight 4.
    EXPECT_NEAR(plane->centre.x, (1.0 / 3.0 + 4.0 * 11.0 / 3.0) / 5.0, 1e-15);
    EXPECT_NEAR(plane->centre.y, (1.0 / 3.0 + 4.0 * 2.0 / 3.0) / 5.0, 1e-15);
    EXPECT_EQ(plane->centre.z, 2.0);
    // A subset is a plane of its own.
    const std::int32_t second[] = {1};
    EXPECT_NEAR(fit_plane(x, triangles, second, 0.5)->centre.x, 11.0 / 3.0, 1e-15);
}

TEST(FitPlane, NormalsThatDisagreeGiveNoPlane) {
    // Agreement cos(θ/2) for two equal triangles whose normals are θ apart: a hinge folded by
    // θ = 90° agrees to 0.707, by 150° to 0.259.
    const std::vector<Vec3d> right = hinge(M_PI / 2.0);
    const std::optional<FittedPlane> bisector = fit_plane(right, HINGE_TRIANGLES, ALL, 0.5);
    ASSERT_TRUE(bisector.has_value());
    EXPECT_NEAR(bisector->normal.x, std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(bisector->normal.z, std::sqrt(0.5), 1e-15);
    EXPECT_FALSE(fit_plane(right, HINGE_TRIANGLES, ALL, 0.75).has_value());
    EXPECT_FALSE(fit_plane(hinge(M_PI * 150.0 / 180.0), HINGE_TRIANGLES, ALL, 0.5).has_value());
    // Two layers of a fold lying on each other, wound against each other: their normals cancel
    // exactly, and no agreement, however small, gives a plane.
    const std::vector<Vec3d> folded = hinge(M_PI);
    EXPECT_FALSE(fit_plane(folded, HINGE_TRIANGLES, ALL, 0.5).has_value());
    const std::vector<Vec3d> flat_fold{
        {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
    EXPECT_FALSE(fit_plane(flat_fold, HINGE_TRIANGLES, ALL, 0.0).has_value());
}

TEST(FitPlane, NoAreaGivesNoPlane) {
    const std::vector<Vec3d> line{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}};
    const std::vector<Triangle> triangles{{0, 1, 2}};
    const std::int32_t first[] = {0};
    EXPECT_FALSE(fit_plane(line, triangles, first, 0.0).has_value());
    EXPECT_FALSE(fit_plane(line, triangles, {}, 0.0).has_value());
}

}  // namespace
}  // namespace pliant::geometry
