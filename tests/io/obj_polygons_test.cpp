// Polygon OBJ (garments): faces, UVs, normals, objects, groups and materials kept from input to
// output frames; triangulation for the solver; broken files refused with line numbers.
#include "pliant/io/obj_polygons.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pliant/io/obj.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::read_bytes;
using test::TempDir;
using test::write_bytes;

// A quad, a triangle and a pentagon in the z = 0 plane, in two groups with two materials,
// with UVs and normals, as a DCC tool writes them.
constexpr const char* GARMENT = R"(# exported
mtllib shirt.mtl
o shirt
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 3 0.5 0
v 2.5 1.5 0
v 1.5 1.5 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
g front
usemtl cotton_red
s 1
f 1/1/1 2/2/1 3/3/1 4/4/1
f 2/2/1 5/1/1 3/3/1
g back sleeve
usemtl cotton_blue
f -4 -3 -2 -1 3
)";

double area(const geometry::TriangleMeshD& m) {
    double sum = 0.0;
    for (const geometry::Triangle& t : m.triangles) {
        const Vec3d& a = m.positions[static_cast<std::size_t>(t[0])];
        const Vec3d& b = m.positions[static_cast<std::size_t>(t[1])];
        const Vec3d& c = m.positions[static_cast<std::size_t>(t[2])];
        sum += 0.5 * norm(cross(b - a, c - a));
    }
    return sum;
}

TEST(ObjPolygons, ReadsFacesUvsNormalsGroupsAndMaterials) {
    const TempDir dir;
    write_bytes(dir / "g.obj", GARMENT);
    const PolygonMesh m = read_obj_polygons(dir / "g.obj");
    ASSERT_EQ(m.positions.size(), 8u);
    EXPECT_EQ(m.uvs.size(), 4u);
    EXPECT_EQ(m.normals.size(), 1u);
    ASSERT_EQ(m.num_faces(), 3u);
    EXPECT_EQ(m.num_corners(0), 4u);
    EXPECT_EQ(m.num_corners(1), 3u);
    EXPECT_EQ(m.num_corners(2), 5u);
    EXPECT_EQ(m.corner_uvs[4], 1);  // face 2's first corner: 2/2/1
    EXPECT_EQ(m.corner_normals[4], 0);
    EXPECT_EQ(m.corner_vertices[7], 4);  // -4 of 8 vertices is vertex 5
    EXPECT_EQ(m.corner_uvs[7], -1);
    EXPECT_EQ(m.corner_normals[7], -1);
    ASSERT_EQ(m.material_libraries.size(), 1u);
    EXPECT_EQ(m.material_libraries[0], "shirt.mtl");
    const auto name = [&](std::int32_t i) {
        return i < 0 ? std::string() : m.names[static_cast<std::size_t>(i)];
    };
    EXPECT_EQ(name(m.face_tags[0].object), "shirt");
    EXPECT_EQ(name(m.face_tags[0].group), "front");
    EXPECT_EQ(name(m.face_tags[0].material), "cotton_red");
    EXPECT_EQ(name(m.face_tags[0].smoothing), "1");
    EXPECT_EQ(name(m.face_tags[2].group), "back sleeve");
    EXPECT_EQ(name(m.face_tags[2].material), "cotton_blue");
    EXPECT_EQ(m.face_tags[0].material, m.face_tags[1].material);
}

TEST(ObjPolygons, TriangulatesQuadsAndNgonsCoveringTheirArea) {
    const TempDir dir;
    write_bytes(dir / "g.obj", GARMENT);
    const PolygonMesh m = read_obj_polygons(dir / "g.obj");
    std::vector<std::int32_t> faces;
    const geometry::TriangleMeshD t = triangulate(m, &faces);
    ASSERT_EQ(t.triangles.size(), 2u + 1u + 3u);
    EXPECT_EQ(faces, (std::vector<std::int32_t>{0, 0, 1, 2, 2, 2}));
    for (const geometry::Triangle& tri : t.triangles) {  // the input's winding: normals +z
        const Vec3d n = cross(t.positions[static_cast<std::size_t>(tri[1])] -
                                  t.positions[static_cast<std::size_t>(tri[0])],
                              t.positions[static_cast<std::size_t>(tri[2])] -
                                  t.positions[static_cast<std::size_t>(tri[0])]);
        EXPECT_GT(n.z, 0.0);
    }
    // Shoelace areas: quad 1, triangle 0.5, pentagon (5, 6, 7, 8, 3) 1.875.
    EXPECT_NEAR(area(t), 1.0 + 0.5 + 1.875, 1e-12);
}

TEST(ObjPolygons, EarClipsConcavePolygons) {
    // An L-shaped hexagon of area 3, listed from a reflex corner: a fan from corner 1 would cover
    // area outside it.
    const TempDir dir;
    write_bytes(dir / "l.obj",
                "v 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nv 2 1 0\n"
                "f 1 2 3 4 5 6\n");
    const geometry::TriangleMeshD t = triangulate(read_obj_polygons(dir / "l.obj"));
    ASSERT_EQ(t.triangles.size(), 4u);
    EXPECT_NEAR(area(t), 3.0, 1e-12);
}

TEST(ObjPolygons, WritesTheInputsFacesWithNewPositions) {
    const TempDir dir;
    write_bytes(dir / "g.obj", GARMENT);
    const PolygonMesh m = read_obj_polygons(dir / "g.obj");
    std::vector<Vec3d> moved = m.positions;
    for (Vec3d& p : moved) {
        p = Vec3d{p.x, -p.z, p.y + 0.25};  // rotated to stand in the x-z plane: normals -y
    }
    write_obj_polygons(dir / "out.obj", m, moved);
    const std::string text = read_bytes(dir / "out.obj");
    EXPECT_NE(text.find("mtllib shirt.mtl\n"), std::string::npos) << text;
    EXPECT_NE(text.find("o shirt\ng front\ns 1\nusemtl cotton_red\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf "
                        "2/2/2 5/1/5 3/3/3\n"
                        "g back sleeve\nusemtl cotton_blue\nf 5//5 6//6 7//7 8//8 3//3\n"),
              std::string::npos)
        << text;
    const PolygonMesh back = read_obj_polygons(dir / "out.obj");
    EXPECT_EQ(back.positions, moved);
    EXPECT_EQ(back.uvs, m.uvs);
    EXPECT_EQ(back.corner_vertices, m.corner_vertices);
    EXPECT_EQ(back.face_starts, m.face_starts);
    ASSERT_EQ(back.face_tags.size(), m.face_tags.size());
    const auto name = [](const PolygonMesh& mesh, std::int32_t i) {
        return i < 0 ? std::string() : mesh.names[static_cast<std::size_t>(i)];
    };
    for (std::size_t f = 0; f < m.face_tags.size(); ++f) {
        EXPECT_EQ(name(back, back.face_tags[f].object), name(m, m.face_tags[f].object));
        EXPECT_EQ(name(back, back.face_tags[f].group), name(m, m.face_tags[f].group));
        EXPECT_EQ(name(back, back.face_tags[f].smoothing), name(m, m.face_tags[f].smoothing));
        EXPECT_EQ(name(back, back.face_tags[f].material), name(m, m.face_tags[f].material));
    }
    ASSERT_EQ(back.normals.size(), 8u);
    for (const Vec3d& n : back.normals) {
        EXPECT_NEAR(n.y, -1.0, 1e-6);
    }
    // The triangle reader sees the same vertices and the same triangulation.
    const geometry::TriangleMeshD triangles = read_obj(dir / "out.obj");
    EXPECT_EQ(triangles.positions, moved);
    EXPECT_EQ(triangles.triangles.size(), 6u);

    // Without normals in the input, none are written.
    write_bytes(dir / "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
    const PolygonMesh plain = read_obj_polygons(dir / "plain.obj");
    write_obj_polygons(dir / "plain_out.obj", plain, plain.positions);
    const std::string plain_text = read_bytes(dir / "plain_out.obj");
    EXPECT_EQ(plain_text.find("vn"), std::string::npos);
    EXPECT_NE(plain_text.find("f 1/1 2/1 3/1\n"), std::string::npos) << plain_text;

    EXPECT_THROW(write_obj_polygons(dir / "bad.obj", m, std::span(moved).first(3)), InvalidInput);
    moved[0].x = std::nan("");
    EXPECT_THROW(write_obj_polygons(dir / "bad.obj", m, moved), InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.obj"));
}

TEST(ObjPolygons, ForwardReferencesAndCrLfAreAccepted) {
    const TempDir dir;
    write_bytes(dir / "f.obj", "f 1 2 3 # a face first\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\n");
    EXPECT_EQ(read_obj_polygons(dir / "f.obj").num_faces(), 1u);
}

TEST(ObjPolygons, BrokenFilesNameTheLine) {
    const TempDir dir;
    const auto expect = [&](const std::string& text,
                            std::initializer_list<std::string_view> parts) {
        write_bytes(dir / "b.obj", text);
        expect_io_error([&] { read_obj_polygons(dir / "b.obj"); }, parts);
    };
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    write_bytes(dir / "none.obj", tri);
    EXPECT_EQ(read_obj_polygons(dir / "none.obj").num_faces(), 0u);
    expect("v 0 0\n", {"line 1", "'v' needs x y z", "got 2 numbers"});
    expect("v 0 nan 0\n", {"line 1", "v y", "finite number", "'nan'"});
    expect("v 0 0 1e999\n", {"line 1", "v z"});
    expect(tri + "vt\n", {"line 4", "'vt' needs u"});
    expect(tri + "vn 0 x 1\n", {"line 4", "vn y"});
    expect(tri + "f 1 2\n", {"line 4", "at least 3 corners", "got 2"});
    expect(tri + "f 1 2 0\n", {"line 4", "vertex index 0"});
    expect(tri + "f 1 2 -4\n", {"line 4", "vertex index -4", "-3 <= index"});
    expect(tri + "f 1 2 4\n", {"vertex index 4", "out of range", "index <= 3"});
    expect(tri + "f 1/1 2/1 3/1\n", {"texture coordinate index 1", "out of range"});
    expect(tri + "f 1//1 2//1 3//1\n", {"normal index 1", "out of range"});
    expect(tri + "f 1 2 x\n", {"line 4", "vertex index", "'x'"});
    expect(tri + "f 1/ 2 3\n", {"line 4", "face corner '1/'"});
    expect(tri + "f 1/1/1/1 2 3\n", {"line 4", "face corner '1/1/1/1'"});
    expect(tri + "f /1 2 3\n", {"line 4", "face corner '/1'"});
    expect(tri + "f 1 2 1\n", {"line 4", "repeats vertex 1", "corners 1 and 3"});
    expect(tri + "f 1 2 99999999999\n", {"line 4", "vertex index 99999999999"});
    expect_io_error([&] { read_obj_polygons(dir / "missing.obj"); }, {"missing.obj"});
}

}  // namespace
}  // namespace pliant::io
