#include "pliant/io/obj.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using geometry::Triangle;
using geometry::TriangleMesh;
using geometry::TriangleMeshD;
using test::expect_io_error;
using test::TempDir;
using test::write_bytes;

TriangleMeshD read_text(const TempDir& dir, const std::string& text) {
    write_bytes(dir / "mesh.obj", text);
    return read_obj(dir / "mesh.obj");
}

// Expects read_obj on `text` to throw IoError whose message starts with the path and contains
// every fragment.
void expect_broken(const std::string& text, std::initializer_list<std::string_view> fragments) {
    TempDir dir;
    const auto path = dir / "broken.obj";
    write_bytes(path, text);
    const std::string message = expect_io_error([&] { read_obj(path); }, fragments);
    EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
}

constexpr const char* TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

// ---------------------------------------------------------------------------------------------
// Round trips and the writer's format
// ---------------------------------------------------------------------------------------------

// OBJ text has no type: the floats' shortest decimals are read as doubles and round back to the
// same floats.
TEST(Obj, RoundTripFloat) {
    TempDir dir;
    const TriangleMesh mesh = test::tricky_mesh<float>();
    write_obj(dir / "mesh.obj", mesh);
    test::expect_rounds_to(mesh, read_obj(dir / "mesh.obj"));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"mesh.obj"});
}

// The coordinates are read at double precision, so doubles survive too.
TEST(Obj, RoundTripDouble) {
    TempDir dir;
    const TriangleMeshD mesh = test::tricky_mesh<double>(11);
    write_obj(dir / "mesh.obj", mesh);
    test::expect_bitwise_equal(mesh, read_obj(dir / "mesh.obj"));
}

TEST(Obj, RoundTripEmptyMesh) {
    TempDir dir;
    write_obj(dir / "empty.obj", TriangleMesh{});
    const TriangleMeshD mesh = read_obj(dir / "empty.obj");
    EXPECT_EQ(mesh.num_vertices(), 0u);
    EXPECT_EQ(mesh.num_triangles(), 0u);
}

TEST(Obj, WriterFormat) {
    TempDir dir;
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0.5f, 0}, {0, 1, -2}};
    mesh.triangles = {{0, 1, 2}};
    write_obj(dir / "f.obj", mesh);
    const std::string text = test::read_bytes(dir / "f.obj");
    EXPECT_NE(text.find("\nv 0 0 0\nv 1 0.5 0\nv 0 1 -2\nf 1 2 3\n"), std::string::npos) << text;

    TriangleMeshD precise;
    precise.positions = {{0.1, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    precise.triangles = {{2, 1, 0}};
    write_obj(dir / "d.obj", precise);
    const std::string text_d = test::read_bytes(dir / "d.obj");
    // The shortest text that reads back to the same double.
    EXPECT_NE(text_d.find("\nv 0.1 0 0\n"), std::string::npos) << text_d;
    EXPECT_NE(text_d.find("\nf 3 2 1\n"), std::string::npos) << text_d;
}

TEST(Obj, WriterRejectsInvalidMeshAndKeepsTheFile) {
    TempDir dir;
    const auto path = dir / "keep.obj";
    write_bytes(path, "previous");
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, std::numeric_limits<float>::infinity(), 0}};
    mesh.triangles = {{0, 1, 2}};
    EXPECT_THROW(write_obj(path, mesh), InvalidInput);
    EXPECT_EQ(test::read_bytes(path), "previous");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.obj"});
}

TEST(Obj, WriteIntoMissingDirectoryLeavesNothing) {
    TempDir dir;
    const auto path = dir / "no" / "such" / "mesh.obj";
    expect_io_error([&] { write_obj(path, test::tricky_mesh<double>()); },
                    {path.string(), "cannot create the temporary file"});
    EXPECT_TRUE(dir.entries().empty());
}

// ---------------------------------------------------------------------------------------------
// Hand-written files
// ---------------------------------------------------------------------------------------------

// Signed area in the z = 0 plane of triangles [begin, end).
double signed_area(const TriangleMeshD& mesh, std::size_t begin, std::size_t end) {
    double area = 0.0;
    for (std::size_t t = begin; t < end; ++t) {
        const Vec3d a = mesh.positions[static_cast<std::size_t>(mesh.triangles[t][0])];
        const Vec3d b = mesh.positions[static_cast<std::size_t>(mesh.triangles[t][1])];
        const Vec3d c = mesh.positions[static_cast<std::size_t>(mesh.triangles[t][2])];
        area += 0.5 * cross(b - a, c - a).z;
    }
    return area;
}

TEST(Obj, QuadsAndPolygonsAreTriangulated) {
    TempDir dir;
    const TriangleMeshD mesh = read_text(dir,
                                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0.5 0\n"
                                         "f 1 2 3 4\n"
                                         "f 1 2 5 3 4\n");
    EXPECT_EQ(mesh.num_vertices(), 5u);
    ASSERT_EQ(mesh.num_triangles(), 2u + 3u);
    // The quad's triangles use only its corners; both polygons are tiled exactly, with the
    // polygon's (counter-clockwise) orientation: signed areas 1 and 1.5.
    for (std::size_t t = 0; t < 2; ++t) {
        for (const int v : mesh.triangles[t]) {
            EXPECT_LT(v, 4);
        }
    }
    EXPECT_DOUBLE_EQ(signed_area(mesh, 0, 2), 1.0);
    EXPECT_DOUBLE_EQ(signed_area(mesh, 2, 5), 1.5);
}

TEST(Obj, IndexFormsNegativeIndicesCommentsAndCrlf) {
    TempDir dir;
    const TriangleMeshD mesh = read_text(dir,
                                         "# a comment\r\n"
                                         "mtllib missing.mtl\r\n"
                                         "o first\r\n"
                                         "v 0 0 0\r\n"
                                         "  v\t1 0 0 1\r\n"         // w is ignored
                                         "v 0 1 0 0.5 0.5 0.5\r\n"  // a vertex colour is ignored
                                         "vt 0 0\r\nvt 1 0\r\nvt 0 1\r\n"
                                         "vn 0 0 1\r\n"
                                         "usemtl red\r\n"
                                         "f 1/1/1 2/2/1 3/3/1\r\n"
                                         "g second\r\n"
                                         "v 1 1 0\r"  // old Mac line ending
                                         "f -3//1 -1//1 -2//1\n"
                                         "l 1 2\n"
                                         "p 3\n"
                                         "f 2/2 4/1 3/3\n");
    ASSERT_EQ(mesh.num_vertices(), 4u);
    EXPECT_EQ(mesh.positions[1], (Vec3d{1, 0, 0}));
    EXPECT_EQ(mesh.positions[2], (Vec3d{0, 1, 0}));
    EXPECT_EQ(mesh.positions[3], (Vec3d{1, 1, 0}));
    EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {1, 3, 2}, {1, 3, 2}}));
}

TEST(Obj, VerticesWithoutFaces) {
    TempDir dir;
    const TriangleMeshD mesh = read_text(dir, "v 1e-300 -2 +3\nv 0.1 0.2 0.3\n");
    ASSERT_EQ(mesh.num_vertices(), 2u);
    EXPECT_EQ(mesh.positions[0], (Vec3d{1e-300, -2, 3}));
    EXPECT_EQ(mesh.positions[1], (Vec3d{0.1, 0.2, 0.3}));
    EXPECT_EQ(mesh.num_triangles(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Broken files
// ---------------------------------------------------------------------------------------------

TEST(ObjBroken, MissingFile) {
    TempDir dir;
    const auto path = dir / "missing.obj";
    expect_io_error([&] { read_obj(path); }, {path.string(), "cannot open file"});
}

TEST(ObjBroken, FaceIndexOutOfRange) {
    expect_broken(std::string(TRIANGLE) + "f 1 2 3\nf 1 2 5\n",
                  {"line 5", "face vertex index 5 is out of range", "expected 1 <= index <= 3"});
    expect_broken(std::string(TRIANGLE) + "f 1 2 3 7\n", {"line 4", "index 7"});
    expect_broken(std::string(TRIANGLE) + "f -5 1 2\n",
                  {"line 4", "face vertex index -5 reaches before the first vertex",
                   "expected -3 <= index <= -1"});
    expect_broken(std::string(TRIANGLE) + "f 0 1 2\n",
                  {"line 4", "bad face vertex '0'", "expected a 1-based vertex index"});
    expect_broken(std::string(TRIANGLE) + "f 1 x 2\n", {"line 4", "bad face vertex 'x'"});
    expect_broken(std::string(TRIANGLE) + "f 1 2 99999999999\n",
                  {"line 4", "bad face vertex '99999999999'"});
}

TEST(ObjBroken, FaceWithTwoVertices) {
    expect_broken(std::string(TRIANGLE) + "f 1 2\n",
                  {"line 4", "face has 2 vertices, expected at least 3"});
}

TEST(ObjBroken, RepeatedVertex) {
    expect_broken(std::string(TRIANGLE) + "f 1 2 2\n", {"triangle 0 repeats a vertex"});
}

TEST(ObjBroken, NonFiniteOrGarbageCoordinates) {
    expect_broken("v 0 0 0\nv nan 0 0\n",
                  {"line 2", "vertex 2 coordinate x: expected a finite number, got 'nan'"});
    expect_broken("v 0 inf 0\n", {"line 1", "coordinate y", "got 'inf'"});
    expect_broken("v 0 0 1e999\n", {"line 1", "coordinate z", "got '1e999'"});
    expect_broken("v 0 abc 0\n", {"line 1", "coordinate y", "got 'abc'"});
    expect_broken("v 0 0,5 0\n", {"line 1", "got '0,5'"});
    expect_broken("v 1 2\n", {"line 1", "vertex 1 has 2 coordinates, expected 3"});
}

}  // namespace
}  // namespace pliant::io
