#include "pliant/geometry/normals.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::geometry {
namespace {

// A flat sheet: every normal is +z exactly; a sphere: normals point away from the centre.
TEST(Normals, FlatSheetAndSphere) {
    const TriangleMeshD sheet = convert_precision<double>(make_grid_sheet(5, 4, 2.0f, 1.0f));
    for (const Vec3f& n : vertex_normals(sheet.positions, sheet.triangles)) {
        EXPECT_EQ(n, (Vec3f{0.0f, 0.0f, 1.0f}));
    }
    const Vec3d centre{1.0, -2.0, 0.5};
    const TriangleMeshD ball = make_uv_sphere(centre, 0.7, 32);
    const std::vector<Vec3f> normals = vertex_normals(ball.positions, ball.triangles);
    ASSERT_EQ(normals.size(), ball.positions.size());
    for (std::size_t v = 0; v < normals.size(); ++v) {
        const Vec3d radial = (ball.positions[v] - centre) / 0.7;
        EXPECT_GT(dot(vec3_cast<double>(normals[v]), radial), 0.99) << "vertex " << v;
        EXPECT_NEAR(norm(normals[v]), 1.0f, 1e-6f);
    }
}

// Area weighting: vertex 0 is shared by triangles of area 8 (normal +z, twice, and once
// reversed) and one of area 0.5 (normal +y): the sum is (0, 1, 16). Unused vertices and
// cancelling pairs get the zero vector.
TEST(Normals, AreaWeightedAndDegenerate) {
    const std::vector<Vec3d> positions = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0},
                                          {1, 0, 0}, {0, 0, 1}, {9, 9, 9}};
    const std::vector<Triangle> triangles = {{0, 1, 2}, {0, 4, 3}, {1, 2, 0}, {2, 1, 0}};
    const std::vector<Vec3f> normals = vertex_normals(positions, triangles);
    const Vec3d expected = Vec3d{0.0, 1.0, 16.0} / std::sqrt(257.0);
    EXPECT_NEAR(norm(vec3_cast<double>(normals[0]) - expected), 0.0, 1e-6);
    EXPECT_EQ(normals[1], (Vec3f{0.0f, 0.0f, 1.0f}));
    EXPECT_EQ(normals[3], (Vec3f{0.0f, 1.0f, 0.0f}));
    EXPECT_EQ(normals[5], (Vec3f{0.0f, 0.0f, 0.0f}));
    const std::vector<Triangle> cancelling = {{0, 1, 2}, {0, 2, 1}};
    for (const Vec3f& n : vertex_normals(positions, cancelling)) {
        EXPECT_EQ(n, (Vec3f{0.0f, 0.0f, 0.0f}));
    }
    EXPECT_TRUE(vertex_normals({}, {}).empty());
}

TEST(Normals, BitwiseIdenticalForOneAndTwoThreads) {
    TriangleMesh folded = make_grid_sheet(120, 90, 2.0f, 1.5f);
    fold_accordion(folded.positions, 0.2f, 0.01f);
    const TriangleMeshD sheet = convert_precision<double>(folded);
    set_num_threads(1);
    const std::vector<Vec3f> one = vertex_normals(sheet.positions, sheet.triangles);
    set_num_threads(2);
    const std::vector<Vec3f> two = vertex_normals(sheet.positions, sheet.triangles);
    set_num_threads(0);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3f)), 0);
}

}  // namespace
}  // namespace pliant::geometry
