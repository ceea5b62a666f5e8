// PLY garments: polygons, per-vertex and per-corner UVs and simple properties kept from input to
// output frames in every format; broken files refused with the file, line and both values.
#include "pliant/io/ply_polygons.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/ply_bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/obj_polygons.hpp"
#include "pliant/io/ply.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::ALL_FORMATS;
using test::Bytes;
using test::expect_io_error;
using test::read_bytes;
using test::TempDir;
using test::write_bytes;

// A quad, a triangle and a pentagon in the z = 0 plane with per-vertex UVs (s, t), normals that
// point the wrong way, a vertex colour and a face property, as MeshLab or Blender write them.
constexpr const char* GARMENT = R"(ply
format ascii 1.0
comment made by hand
element vertex 8
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float s
property float t
property uchar red
property list uchar int extra_list
element face 3
property list uchar int vertex_indices
property int flags
element edge 1
property int vertex1
property int vertex2
end_header
0 0 0 1 0 0 0 0 10 0
1 0 0 1 0 0 0.5 0 20 2 7 8
1 1 0 1 0 0 0.5 1 30 0
0 1 0 1 0 0 0 1 40 0
2 0 0 1 0 0 1 0 50 0
3 0.5 0 1 0 0 1 0.25 60 0
2.5 1.5 0 1 0 0 0.75 1 70 0
1.5 1.5 0 1 0 0 0.25 1 80 0
4 0 1 2 3 5
3 1 4 2 -6
5 4 5 6 7 2 9
0 1
)";

PolygonMesh read_text(const TempDir& dir, const std::string& text, const char* name = "g.ply") {
    write_bytes(dir / name, text);
    return read_ply_polygons(dir / name);
}

TEST(PlyPolygons, ReadsPolygonsUvsNormalsAndProperties) {
    const TempDir dir;
    const PolygonMesh m = read_text(dir, GARMENT);
    ASSERT_EQ(m.positions.size(), 8u);
    EXPECT_EQ(m.positions[5], (Vec3d{3.0, 0.5, 0.0}));
    ASSERT_EQ(m.num_faces(), 3u);
    EXPECT_EQ(m.num_corners(0), 4u);
    EXPECT_EQ(m.num_corners(1), 3u);
    EXPECT_EQ(m.num_corners(2), 5u);
    EXPECT_EQ(m.corner_vertices, (std::vector<std::int32_t>{0, 1, 2, 3, 1, 4, 2, 4, 5, 6, 7, 2}));
    // Per-vertex UVs: one per vertex, each corner refers to its vertex's.
    ASSERT_EQ(m.uvs.size(), 8u);
    EXPECT_EQ(m.uvs[5], (std::array<double, 2>{1.0, 0.25}));
    EXPECT_EQ(m.corner_uvs, m.corner_vertices);
    // Normals are kept as read (never used) and each corner refers to its vertex's.
    ASSERT_EQ(m.normals.size(), 8u);
    EXPECT_EQ(m.corner_normals, m.corner_vertices);
    // The scalar vertex and face properties; the vertex list and the edge element are skipped.
    ASSERT_EQ(m.vertex_attributes.size(), 1u);
    EXPECT_EQ(m.vertex_attributes[0].name, "red");
    EXPECT_EQ(m.vertex_attributes[0].type, "uchar");
    EXPECT_EQ(m.vertex_attributes[0].values, (std::vector<double>{10, 20, 30, 40, 50, 60, 70, 80}));
    ASSERT_EQ(m.face_attributes.size(), 1u);
    EXPECT_EQ(m.face_attributes[0].name, "flags");
    EXPECT_EQ(m.face_attributes[0].type, "int");
    EXPECT_EQ(m.face_attributes[0].values, (std::vector<double>{5, -6, 9}));
    EXPECT_EQ(m.face_tags.size(), 3u);

    // The solver's triangles: a quad gives 2, a pentagon 3, all inside the faces.
    std::vector<std::int32_t> face_of_triangle;
    const geometry::TriangleMeshD t = triangulate(m, &face_of_triangle);
    EXPECT_EQ(t.triangles.size(), 6u);
    EXPECT_EQ(face_of_triangle, (std::vector<std::int32_t>{0, 0, 1, 2, 2, 2}));
}

TEST(PlyPolygons, UvPropertyNamesAndMissingUvs) {
    const TempDir dir;
    for (const auto& [u, v] : {std::pair{"u", "v"}, std::pair{"texture_u", "texture_v"},
                               std::pair{"texture_s", "texture_t"}}) {
        const PolygonMesh m =
            read_text(dir, fmt::format("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                       "property float y\nproperty float z\nproperty double {}\n"
                                       "property double {}\nelement face 1\n"
                                       "property list uchar uint vertex_index\nend_header\n"
                                       "0 0 0 0.125 0.5\n1 0 0 0.25 0.5\n0 1 0 0.5 0.75\n3 0 1 2\n",
                                       u, v));
        ASSERT_EQ(m.uvs.size(), 3u) << u;
        EXPECT_EQ(m.uvs[2], (std::array<double, 2>{0.5, 0.75})) << u;
        EXPECT_EQ(m.corner_uvs, (std::vector<std::int32_t>{0, 1, 2})) << u;
        EXPECT_TRUE(m.vertex_attributes.empty()) << u;
    }
    // Only one of a pair: no UVs, the property is kept as an attribute.
    const PolygonMesh m = read_text(
        dir,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty float s\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0 1\n1 0 0 2\n0 1 0 3\n3 0 1 2\n");
    EXPECT_TRUE(m.uvs.empty());
    EXPECT_EQ(m.corner_uvs, (std::vector<std::int32_t>{-1, -1, -1}));
    EXPECT_TRUE(m.normals.empty());
    EXPECT_EQ(m.corner_normals, (std::vector<std::int32_t>{-1, -1, -1}));
    ASSERT_EQ(m.vertex_attributes.size(), 1u);
    EXPECT_EQ(m.vertex_attributes[0].name, "s");
}

TEST(PlyPolygons, PerCornerTexcoordTakesPrecedence) {
    const TempDir dir;
    const PolygonMesh m =
        read_text(dir,
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                  "property float z\nproperty float s\nproperty float t\nelement face 2\n"
                  "property list uchar float texcoord\nproperty list uchar int vertex_indices\n"
                  "end_header\n0 0 0 9 9\n1 0 0 9 9\n1 1 0 9 9\n0 1 0 9 9\n"
                  "6 0 0 1 0 1 1 3 0 1 2\n6 0.5 0.5 0.25 0.25 0 0.5 3 0 2 3\n");
    ASSERT_EQ(m.num_faces(), 2u);
    ASSERT_EQ(m.uvs.size(), 6u);  // one per corner
    EXPECT_EQ(m.corner_uvs, (std::vector<std::int32_t>{0, 1, 2, 3, 4, 5}));
    EXPECT_EQ(m.uvs[3], (std::array<double, 2>{0.5, 0.5}));  // vertex 0 has two UVs
    EXPECT_EQ(m.uvs[0], (std::array<double, 2>{0.0, 0.0}));
}

// Reads, writes with moved positions in every format, reads back: the same faces, UVs and
// properties; positions bit for bit.
TEST(PlyPolygons, RoundTripEveryFormat) {
    const TempDir dir;
    const PolygonMesh m = read_text(dir, GARMENT);
    std::vector<Vec3d> moved = m.positions;
    for (std::size_t v = 0; v < moved.size(); ++v) {
        moved[v] = moved[v] * (1.0 / 3.0) + Vec3d{0.1, -0.2, 0.7 * static_cast<double>(v)};
    }
    for (const PlyFormat format : ALL_FORMATS) {
        const auto path = dir / fmt::format("out_{}.ply", to_string(format));
        write_ply_polygons(path, m, moved, format);
        const PolygonMesh back = read_ply_polygons(path);
        EXPECT_EQ(back.positions, moved) << to_string(format);
        EXPECT_EQ(back.face_starts, m.face_starts);
        EXPECT_EQ(back.corner_vertices, m.corner_vertices);
        EXPECT_EQ(back.uvs, m.uvs);  // float-exact values
        EXPECT_EQ(back.corner_uvs, m.corner_uvs);
        ASSERT_EQ(back.vertex_attributes.size(), 1u);
        EXPECT_EQ(back.vertex_attributes[0].name, "red");
        EXPECT_EQ(back.vertex_attributes[0].type, "uchar");
        EXPECT_EQ(back.vertex_attributes[0].values, m.vertex_attributes[0].values);
        ASSERT_EQ(back.face_attributes.size(), 1u);
        EXPECT_EQ(back.face_attributes[0].values, m.face_attributes[0].values);
        // Normals recomputed from the positions written: unit length, not the file's (1, 0, 0).
        ASSERT_EQ(back.normals.size(), 8u);
        for (const Vec3d& n : back.normals) {
            EXPECT_NEAR(norm(n), 1.0, 1e-6) << to_string(format);
        }
        // read_ply (the triangle reader) takes the same file: its fans cover the same faces.
        EXPECT_EQ(read_ply(path).triangles.size(), 6u);
    }
}

TEST(PlyPolygons, WriterLayoutAndRecomputedNormals) {
    const TempDir dir;
    const PolygonMesh m = read_text(dir, GARMENT);
    write_ply_polygons(dir / "a.ply", m, m.positions, PlyFormat::ascii);
    const std::string text = read_bytes(dir / "a.ply");
    const std::string header = text.substr(0, text.find("end_header"));
    EXPECT_EQ(header,
              "ply\nformat ascii 1.0\ncomment written by pliant\nelement vertex 8\n"
              "property double x\nproperty double y\nproperty double z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              "property float s\nproperty float t\nproperty uchar red\nelement face 3\n"
              "property list uchar int vertex_indices\nproperty int flags\n");
    // The flat garment's normals are +z (counter-clockwise faces seen from +z).
    const PolygonMesh back = read_ply_polygons(dir / "a.ply");
    for (const Vec3d& n : back.normals) {
        EXPECT_EQ(n, (Vec3d{0.0, 0.0, 1.0}));
    }
    EXPECT_NE(text.find("\n4 0 1 2 3 5\n3 1 4 2 -6\n5 4 5 6 7 2 9\n"), std::string::npos);
    EXPECT_NE(text.find(" 0.5 0 20\n"), std::string::npos) << text;
}

// An OBJ garment with a UV seam (a vertex with two UVs) is written with per-corner texcoord
// lists; without seams with per-vertex s, t. Groups and materials have no PLY form.
TEST(PlyPolygons, ObjGarmentToPlyFrames) {
    const TempDir dir;
    write_bytes(dir / "seam.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                "vt 0.5 0.5\ng a\nf 1/1 2/2 3/3 4/4\ng b\nf 2/5 5/2 3/3\n");
    const PolygonMesh seam = read_obj_polygons(dir / "seam.obj");
    write_ply_polygons(dir / "seam.ply", seam, seam.positions);
    const std::string bytes = read_bytes(dir / "seam.ply");
    EXPECT_NE(bytes.find("property list uchar float texcoord\n"), std::string::npos);
    EXPECT_EQ(bytes.find("property float s\n"), std::string::npos);
    const PolygonMesh back = read_ply_polygons(dir / "seam.ply");
    ASSERT_EQ(back.corner_uvs.size(), 7u);
    for (std::size_t c = 0; c < 7; ++c) {
        const auto uv = [](const PolygonMesh& p, std::size_t corner) {
            return p.uvs[static_cast<std::size_t>(p.corner_uvs[corner])];
        };
        EXPECT_EQ(uv(back, c), uv(seam, c)) << c;
    }
    EXPECT_EQ(back.corner_vertices, seam.corner_vertices);

    write_bytes(dir / "plain.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    const PolygonMesh plain = read_obj_polygons(dir / "plain.obj");
    write_ply_polygons(dir / "plain.ply", plain, plain.positions);
    EXPECT_NE(read_bytes(dir / "plain.ply").find("property float s\nproperty float t\n"),
              std::string::npos);
    const PolygonMesh plain_back = read_ply_polygons(dir / "plain.ply");
    EXPECT_EQ(plain_back.uvs, plain.uvs);
}

TEST(PlyPolygons, LargePolygonUsesIntCounts) {
    const TempDir dir;
    PolygonMesh m;
    constexpr int N = 300;
    for (int k = 0; k < N; ++k) {
        const double a = 2.0 * 3.14159265358979 * k / N;
        m.positions.push_back({std::cos(a), std::sin(a), 0.0});
        m.corner_vertices.push_back(k);
        m.corner_uvs.push_back(-1);
        m.corner_normals.push_back(-1);
    }
    m.face_starts.push_back(N);
    m.face_tags.emplace_back();
    write_ply_polygons(dir / "big.ply", m, m.positions);
    EXPECT_NE(read_bytes(dir / "big.ply").find("property list int int vertex_indices\n"),
              std::string::npos);
    const PolygonMesh back = read_ply_polygons(dir / "big.ply");
    EXPECT_EQ(back.corner_vertices, m.corner_vertices);
    EXPECT_TRUE(back.uvs.empty());
}

TEST(PlyPolygons, BigEndianBinaryWithAttributes) {
    const TempDir dir;
    Bytes data(std::endian::big);
    data.put(0.0, 0.0, 0.0).put<float>(0.25f, 0.5f).put<std::int16_t>(-3);
    data.put(1.0, 0.0, 0.0).put<float>(0.75f, 0.5f).put<std::int16_t>(4);
    data.put(1.0, 1.0, 0.0).put<float>(0.75f, 1.0f).put<std::int16_t>(5);
    data.put(0.0, 1.0, 0.0).put<float>(0.25f, 1.0f).put<std::int16_t>(6);
    data.put<std::uint16_t>(4).put<std::uint32_t>(0, 1, 2, 3).put<double>(2.5);
    const PolygonMesh m =
        read_text(dir,
                  "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n"
                  "property double y\nproperty double z\nproperty float texture_u\n"
                  "property float texture_v\nproperty short quality\nelement face 1\n"
                  "property list ushort uint vertex_indices\nproperty double weight\nend_header\n" +
                      data.str());
    EXPECT_EQ(m.positions[2], (Vec3d{1.0, 1.0, 0.0}));
    EXPECT_EQ(m.uvs[1], (std::array<double, 2>{0.75, 0.5}));
    EXPECT_EQ(m.vertex_attributes[0].values, (std::vector<double>{-3, 4, 5, 6}));
    EXPECT_EQ(m.face_attributes[0].values, (std::vector<double>{2.5}));
    EXPECT_EQ(m.num_corners(0), 4u);
}

TEST(PlyPolygons, WriterRejectsBadInputAndKeepsTheFile) {
    const TempDir dir;
    const PolygonMesh m = read_text(dir, GARMENT);
    const auto path = dir / "keep.ply";
    write_bytes(path, "old");
    std::vector<Vec3d> wrong(3);
    EXPECT_THROW(write_ply_polygons(path, m, wrong), InvalidInput);
    std::vector<Vec3d> nan = m.positions;
    nan[4].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(write_ply_polygons(path, m, nan), InvalidInput);
    try {
        write_ply_polygons(path, m, m.positions, static_cast<PlyFormat>(7));
        ADD_FAILURE() << "accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()),
                  "write_ply_polygons: " + path.string() +
                      ": format (7) is not a PlyFormat, expected one of ascii, "
                      "binary_little_endian, binary_big_endian");
    }
    PolygonMesh short_attribute = m;
    short_attribute.vertex_attributes[0].values.pop_back();
    try {
        write_ply_polygons(path, short_attribute, m.positions);
        ADD_FAILURE() << "accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("vertex attribute 'red' has 7 values, expected 8"),
                  std::string::npos)
            << e.what();
    }
    PolygonMesh out_of_range = m;
    out_of_range.vertex_attributes[0].values[2] = 256.0;  // uchar
    EXPECT_THROW(write_ply_polygons(path, out_of_range, m.positions), InvalidInput);
    out_of_range.vertex_attributes[0].values[2] = 2.5;
    EXPECT_THROW(write_ply_polygons(path, out_of_range, m.positions), InvalidInput);
    PolygonMesh bad_type = m;
    bad_type.face_attributes[0].type = "int64";
    EXPECT_THROW(write_ply_polygons(path, bad_type, m.positions), InvalidInput);
    EXPECT_EQ(read_bytes(path), "old");
    EXPECT_THROW(write_ply_polygons(dir / "missing" / "x.ply", m, m.positions), IoError);
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"g.ply", "keep.ply"}));
}

// --- broken files ------------------------------------------------------------------------------

class PlyPolygonsBroken : public ::testing::Test {
protected:
    std::string expect_broken(const std::string& bytes,
                              std::initializer_list<std::string_view> fragments) {
        const auto path = m_dir / "broken.ply";
        write_bytes(path, bytes);
        std::string message = expect_io_error([&] { read_ply_polygons(path); }, fragments);
        EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
        return message;
    }

    TempDir m_dir;
};

constexpr const char* ASCII_UV_HEADER =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nproperty float s\nproperty float t\nelement face 1\n"
    "property list uchar int vertex_indices\nend_header\n";
constexpr const char* FOUR_VERTICES = "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n";

TEST_F(PlyPolygonsBroken, WrongCounts) {
    // One record too many (the count says 1 face), one too few.
    expect_broken(std::string(ASCII_UV_HEADER) + FOUR_VERTICES + "4 0 1 2 3\n3 0 1 2\n",
                  {"line 17", "unexpected data after the last element", "'3'"});
    std::string header = ASCII_UV_HEADER;
    header.replace(header.find("face 1"), 6, "face 2");
    expect_broken(header + FOUR_VERTICES + "4 0 1 2 3\n",
                  {"line 17", "truncated data, expected 2 records of element 'face', got 1"});
    // A list length that does not match its values.
    expect_broken(std::string(ASCII_UV_HEADER) + FOUR_VERTICES + "4 0 1 2\n",
                  {"line 16", "missing data in element 'face' record 0",
                   "property 'vertex_indices' item", "got the end of the line"});
    expect_broken(std::string(ASCII_UV_HEADER) + FOUR_VERTICES + "3 0 1 2 3\n",
                  {"line 16", "extra value '3' after element 'face' record 0"});
}

TEST_F(PlyPolygonsBroken, IndicesAndPolygons) {
    const std::string head = std::string(ASCII_UV_HEADER) + FOUR_VERTICES;
    expect_broken(head + "4 0 1 2 4\n",
                  {"line 16", "face 0 corner 3 has vertex index 4", "expected 0 <= index < 4"});
    expect_broken(head + "4 0 -1 2 3\n", {"face 0 corner 1 has vertex index -1"});
    expect_broken(head + "2 0 1\n", {"face 0 has 2 vertices, expected at least 3"});
    expect_broken(head + "4 0 1 2 1\n", {"face 0 repeats vertex 1", "distinct"});
}

TEST_F(PlyPolygonsBroken, NonFiniteValues) {
    expect_broken(std::string(ASCII_UV_HEADER) + "0 0 0 0 0\n1 nan 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n" +
                      "4 0 1 2 3\n",
                  {"line 13", "vertex 1 has a non-finite coordinate"});
    expect_broken(std::string(ASCII_UV_HEADER) + "0 0 0 0 0\n1 0 0 inf 0\n1 1 0 1 1\n0 1 0 0 1\n" +
                      "4 0 1 2 3\n",
                  {"line 13", "vertex 1 has a non-finite texture coordinate"});
    expect_broken(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        "property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
        "3 0 1 2 6 0 0 1 0 nan 1\n",
        {"line 14", "face 0 corner 2 has a non-finite texcoord"});
}

TEST_F(PlyPolygonsBroken, MismatchedPropertyLists) {
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n";
    expect_broken(head +
                      "property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                      "3 0 1 2 4 0 0 1 0\n",
                  {"face 0 has 4 texcoord values for 3 corners, expected 6"});
    expect_broken(head + "property float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1\n",
                  {"property 'texcoord' of element 'face' is a scalar"});
    expect_broken(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty int vertex_indices\nend_header\n",
        {"property 'vertex_indices' of element 'face' is a scalar, expected a list"});
    expect_broken(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar float vertex_indices\n"
        "end_header\n",
        {"item type float, expected an integer type"});
    expect_broken(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "end_header\n",
        {"element 'vertex' has no property 'z'"});
    expect_broken(
        "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
        "end_header\n",
        {"no vertex element"});
}

TEST_F(PlyPolygonsBroken, HugeCountsAndListsFailBeforeAllocating) {
    expect_broken(
        "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n" +
            std::string(12, '\0'),
        {"line 3", "999999999999", "expected at most 2147483647"});
    expect_broken(
        "ply\nformat binary_little_endian 1.0\nelement vertex 100000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n" +
            std::string(24, '\0'),
        {"line 3", "declares 100000000 records of at least 12 bytes", "expected at most 2"});
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint32_t>(4000000000u).put<std::int32_t>(0, 1, 2);
    expect_broken(
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uint int vertex_indices\nend_header\n" +
            data.str(),
        {"truncated binary data in element 'face' record 0",
         "expected 16000000000 bytes for property 'vertex_indices', got 12"});
    // A skipped list of a huge length too.
    Bytes skipped(std::endian::little);
    skipped.put(0.0f, 0.0f, 0.0f).put<std::uint32_t>(4000000000u);
    expect_broken(
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
        "property float y\nproperty float z\nproperty list uint double junk\nend_header\n" +
            skipped.str(),
        {"truncated binary data in element 'vertex' record 0", "property 'junk'"});
}

// Every proper prefix of a valid binary file's data fails cleanly, wherever it is cut (the
// header's own prefixes are the header parser's tests).
TEST_F(PlyPolygonsBroken, EveryPrefixOfBinaryDataIsRejected) {
    write_bytes(m_dir / "q.ply", std::string(ASCII_UV_HEADER) + FOUR_VERTICES + "4 0 1 2 3\n");
    PolygonMesh m = read_ply_polygons(m_dir / "q.ply");
    m.face_attributes.push_back({"flags", "short", {7.0}});
    const auto path = m_dir / "full.ply";
    write_ply_polygons(path, m, m.positions, PlyFormat::binary_little_endian);
    const std::string file = read_bytes(path);
    const std::size_t data = file.find("end_header\n") + 11;
    const auto prefix_path = m_dir / "prefix.ply";
    for (std::size_t size = data; size < file.size(); ++size) {
        write_bytes(prefix_path, std::string_view(file).substr(0, size));
        try {
            read_ply_polygons(prefix_path);
            ADD_FAILURE() << "prefix of " << size << " bytes was accepted";
        } catch (const IoError& e) {
            ASSERT_EQ(std::string(e.what()).rfind(prefix_path.string(), 0), 0u) << e.what();
        }
    }
    expect_broken(file + "x", {"1 bytes of unexpected data after the last element"});
}

}  // namespace
}  // namespace pliant::io
