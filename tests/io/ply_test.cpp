#include "pliant/io/ply.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <type_traits>

#include "io/ply_bytes.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/validate.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using geometry::Triangle;
using geometry::TriangleMesh;
using geometry::TriangleMeshD;
using test::ALL_FORMATS;
using test::Bytes;
using test::expect_io_error;
using test::TempDir;
using test::write_bytes;

// A unit square as two triangles, in the ASCII layout most tests start from.
constexpr const char* ASCII_SQUARE =
    "ply\n"
    "format ascii 1.0\n"
    "element vertex 4\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "end_header\n"
    "0 0 0\n"
    "1 0 0\n"
    "1 1 0\n"
    "0 1 0\n"
    "3 0 1 2\n"
    "3 0 2 3\n";

const std::vector<Triangle> SQUARE_TRIANGLES = {{0, 1, 2}, {0, 2, 3}};

void expect_square_positions(const TriangleMeshD& mesh) {
    ASSERT_EQ(mesh.num_vertices(), 4u);
    EXPECT_EQ(mesh.positions[0], (Vec3d{0, 0, 0}));
    EXPECT_EQ(mesh.positions[1], (Vec3d{1, 0, 0}));
    EXPECT_EQ(mesh.positions[2], (Vec3d{1, 1, 0}));
    EXPECT_EQ(mesh.positions[3], (Vec3d{0, 1, 0}));
}

// ---------------------------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------------------------

template <typename Real>
void check_round_trip(PlyFormat format) {
    SCOPED_TRACE(to_string(format));
    TempDir dir;
    const auto path = dir / "mesh.ply";
    const geometry::BasicTriangleMesh<Real> mesh = test::tricky_mesh<Real>();
    write_ply(path, mesh, format);
    test::expect_bitwise_equal(mesh, read_ply(path));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"mesh.ply"});
}

TEST(Ply, RoundTripFloatAscii) {
    check_round_trip<float>(PlyFormat::ascii);
}
TEST(Ply, RoundTripFloatBinaryLittleEndian) {
    check_round_trip<float>(PlyFormat::binary_little_endian);
}
TEST(Ply, RoundTripFloatBinaryBigEndian) {
    check_round_trip<float>(PlyFormat::binary_big_endian);
}
TEST(Ply, RoundTripDoubleAscii) {
    check_round_trip<double>(PlyFormat::ascii);
}
TEST(Ply, RoundTripDoubleBinaryLittleEndian) {
    check_round_trip<double>(PlyFormat::binary_little_endian);
}
TEST(Ply, RoundTripDoubleBinaryBigEndian) {
    check_round_trip<double>(PlyFormat::binary_big_endian);
}

TEST(Ply, RoundTripEmptyMeshAndPointCloud) {
    TempDir dir;
    for (const PlyFormat format : ALL_FORMATS) {
        SCOPED_TRACE(to_string(format));
        write_ply(dir / "empty.ply", TriangleMeshD{}, format);
        const TriangleMeshD empty = read_ply(dir / "empty.ply");
        EXPECT_EQ(empty.num_vertices(), 0u);
        EXPECT_EQ(empty.num_triangles(), 0u);

        TriangleMeshD points;
        points.positions = {{1, 2, 3}, {-4, 5e-300, 6e300}};
        write_ply(dir / "points.ply", points, format);
        test::expect_bitwise_equal(points, read_ply(dir / "points.ply"));
    }
}

// Scale: a 20k-triangle folded sheet through every format.
TEST(Ply, RoundTripLargeSheet) {
    TempDir dir;
    TriangleMesh sheet = geometry::make_grid_sheet(100, 100, 2.0f, 1.5f);
    geometry::fold_accordion(sheet.positions, 0.3f, 0.01f);
    ASSERT_EQ(sheet.num_triangles(), 20000u);
    for (const PlyFormat format : ALL_FORMATS) {
        SCOPED_TRACE(to_string(format));
        write_ply(dir / "sheet.ply", sheet, format);
        test::expect_bitwise_equal(sheet, read_ply(dir / "sheet.ply"));
    }
}

TEST(Ply, WriterLayoutFloatAndDouble) {
    TempDir dir;
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    write_ply(dir / "f.ply", mesh);
    const std::string expected_header =
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment written by pliant\n"
        "element vertex 3\n"
        "property float x\n"
        "property float y\n"
        "property float z\n"
        "element face 1\n"
        "property list uchar int vertex_indices\n"
        "end_header\n";
    const std::string bytes = test::read_bytes(dir / "f.ply");
    EXPECT_EQ(bytes.substr(0, expected_header.size()), expected_header);
    EXPECT_EQ(bytes.size(), expected_header.size() + std::size_t{3 * 12 + 13});
    // The face record: count 3, then 0 1 2 as little-endian int32.
    EXPECT_EQ(bytes.substr(expected_header.size() + 36),
              Bytes(std::endian::little).put<std::uint8_t>(3).put<std::int32_t>(0, 1, 2).str());

    write_ply(dir / "d.ply", geometry::convert_precision<double>(mesh), PlyFormat::ascii);
    const std::string text = test::read_bytes(dir / "d.ply");
    EXPECT_NE(text.find("format ascii 1.0\n"), std::string::npos);
    EXPECT_NE(text.find("property double x\nproperty double y\nproperty double z\n"),
              std::string::npos);
    EXPECT_NE(text.find("end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), std::string::npos);
}

TEST(Ply, WriterRejectsInvalidMeshAndKeepsTheFile) {
    TempDir dir;
    const auto path = dir / "keep.ply";
    write_bytes(path, "previous");
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 3}};
    EXPECT_THROW(write_ply(path, mesh), InvalidInput);
    mesh.triangles = {{0, 1, 2}};
    mesh.positions[1].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(write_ply(path, mesh, PlyFormat::ascii), InvalidInput);
    mesh.positions[1].y = 0.0f;
    EXPECT_THROW(write_ply(path, mesh, static_cast<PlyFormat>(7)), InvalidInput);
    EXPECT_EQ(test::read_bytes(path), "previous");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.ply"});
}

TEST(Ply, WritersNameAnUnknownFormat) {
    TempDir dir;
    const auto path = dir / "never.ply";
    const auto message = [](const auto& call) {
        try {
            call();
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const auto expected = [&](const char* function) {
        return fmt::format(
            "{}: {}: format (7) is not a PlyFormat, expected one of ascii, binary_little_endian, "
            "binary_big_endian",
            function, path.string());
    };
    const auto bad = static_cast<PlyFormat>(7);
    const TriangleMesh mesh = geometry::make_grid_sheet(2, 2, 1.0f, 1.0f);
    EXPECT_EQ(message([&] { write_ply(path, mesh, bad); }), expected("write_ply"));
    const std::vector<Vec3f> points{{0.0f, 0.0f, 0.0f}};
    EXPECT_EQ(message([&] { write_point_cloud_ply(path, points, {}, bad); }),
              expected("write_point_cloud_ply"));
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Ply, PointCloudWithColours) {
    TempDir dir;
    const std::vector<Vec3f> points{{1.5f, -2.0f, 3.25f}, {0.0f, 1e-3f, -7.0f}};
    const std::vector<std::array<std::uint8_t, 3>> colors{{{255, 0, 17}}, {{1, 2, 3}}};
    for (const PlyFormat format : ALL_FORMATS) {
        SCOPED_TRACE(to_string(format));
        write_point_cloud_ply(dir / "p.ply", points, colors, format);
        const TriangleMeshD back = read_ply(dir / "p.ply");
        ASSERT_EQ(back.num_vertices(), 2u);
        EXPECT_EQ(back.num_triangles(), 0u);
        for (std::size_t i = 0; i < points.size(); ++i) {
            EXPECT_EQ(back.positions[i].x, static_cast<double>(points[i].x));
            EXPECT_EQ(back.positions[i].y, static_cast<double>(points[i].y));
            EXPECT_EQ(back.positions[i].z, static_cast<double>(points[i].z));
        }
    }
    const std::string text = test::read_bytes(dir / "p.ply");  // the last format: big endian
    EXPECT_NE(
        text.find("element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"),
        std::string::npos);
    EXPECT_EQ(text.find("element face"), std::string::npos);
    EXPECT_EQ(text.substr(text.size() - 3), std::string("\x01\x02\x03", 3));
    write_point_cloud_ply(dir / "a.ply", points, colors, PlyFormat::ascii);
    EXPECT_NE(test::read_bytes(dir / "a.ply").find("end_header\n1.5 -2 3.25 255 0 17\n"),
              std::string::npos);
    write_point_cloud_ply(dir / "n.ply", points, {}, PlyFormat::ascii);
    EXPECT_EQ(test::read_bytes(dir / "n.ply").find("red"), std::string::npos);

    // Wrong colour count and a NaN leave the file as it was.
    write_bytes(dir / "keep.ply", "previous");
    EXPECT_THROW(write_point_cloud_ply(dir / "keep.ply", points, std::span(colors).first(1)),
                 InvalidInput);
    std::vector<Vec3f> nan = points;
    nan[1].z = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(write_point_cloud_ply(dir / "keep.ply", nan, colors), InvalidInput);
    EXPECT_EQ(test::read_bytes(dir / "keep.ply"), "previous");
}

TEST(Ply, WriteIntoMissingDirectoryLeavesNothing) {
    TempDir dir;
    const auto path = dir / "missing" / "mesh.ply";
    expect_io_error([&] { write_ply(path, test::tricky_mesh<float>()); }, {path.string()});
    EXPECT_TRUE(dir.entries().empty());
}

// ---------------------------------------------------------------------------------------------
// Hand-written files
// ---------------------------------------------------------------------------------------------

TEST(Ply, AsciiSquare) {
    TempDir dir;
    write_bytes(dir / "square.ply", ASCII_SQUARE);
    const TriangleMeshD mesh = read_ply(dir / "square.ply");
    expect_square_positions(mesh);
    EXPECT_EQ(mesh.triangles, SQUARE_TRIANGLES);
}

TEST(Ply, CommentsObjInfoCrlfAndBlankLines) {
    TempDir dir;
    const std::string text =
        "ply\r\n"
        "comment made by hand\r\n"
        "format ascii 1.0\r\n"
        "obj_info anything at all\r\n"
        "element vertex 4\r\n"
        "comment between properties\r\n"
        "property float x\r\n"
        "property float y\r\n"
        "property float z\r\n"
        "element face 2\r\n"
        "property list uchar int vertex_indices\r\n"
        "end_header\r\n"
        "0 0 0\r\n"
        "\t1  0 0 \r\n"
        "\r\n"
        "1 1 0\r\n"
        "+0 1 -0\r\n"
        "3 0 1 2\r\n"
        "3 0 2 3";  // no final newline
    write_bytes(dir / "crlf.ply", text);
    const TriangleMeshD mesh = read_ply(dir / "crlf.ply");
    expect_square_positions(mesh);
    EXPECT_TRUE(std::signbit(mesh.positions[3].z));
    EXPECT_EQ(mesh.triangles, SQUARE_TRIANGLES);
}

TEST(Ply, BigEndianDoubles) {
    TempDir dir;
    Bytes data(std::endian::big);
    data.put(0.1, -2.5, 1e-300).put(3.0, 4.0, 5.0).put(-0.0, 1e300, 7.0);
    data.put<std::uint8_t>(3).put<std::int32_t>(2, 1, 0);
    write_bytes(dir / "be.ply",
                "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
                "property double y\nproperty double z\nelement face 1\n"
                "property list uchar int vertex_indices\nend_header\n" +
                    data.str());
    const TriangleMeshD mesh = read_ply(dir / "be.ply");
    ASSERT_EQ(mesh.num_vertices(), 3u);
    EXPECT_EQ(mesh.positions[0], (Vec3d{0.1, -2.5, 1e-300}));
    EXPECT_EQ(mesh.positions[1], (Vec3d{3.0, 4.0, 5.0}));
    EXPECT_EQ(mesh.positions[2], (Vec3d{-0.0, 1e300, 7.0}));
    EXPECT_TRUE(std::signbit(mesh.positions[2].x));
    EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{2, 1, 0}}));
}

// Extra vertex properties between and around x, y, z, with mixed types and sizes.
TEST(Ply, ExtraVertexPropertiesAreSkipped) {
    TempDir dir;
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
        "property float nx\nproperty double x\nproperty uchar red\nproperty float y\n"
        "property short z\nproperty float ny\nproperty float nz\nproperty uchar green\n"
        "property uchar blue\nend_header\n";
    Bytes data(std::endian::little);
    data.put(0.5f).put(1.25).put<std::uint8_t>(255).put(-2.5f).put<std::int16_t>(-7);
    data.put(0.25f, 0.75f).put<std::uint8_t>(1, 2);
    data.put(9.0f).put(-3.0).put<std::uint8_t>(0).put(4.0f).put<std::int16_t>(12);
    data.put(9.0f, 9.0f).put<std::uint8_t>(3, 4);
    write_bytes(dir / "extra.ply", header + data.str());
    const TriangleMeshD mesh = read_ply(dir / "extra.ply");
    ASSERT_EQ(mesh.num_vertices(), 2u);
    EXPECT_EQ(mesh.positions[0], (Vec3d{1.25, -2.5, -7}));
    EXPECT_EQ(mesh.positions[1], (Vec3d{-3.0, 4.0, 12}));
    EXPECT_EQ(mesh.num_triangles(), 0u);

    write_bytes(dir / "extra_ascii.ply",
                "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n"
                "0 1 0 0 0 1 10 20 30\n3 0 1 2\n3 0 2 3\n");
    const TriangleMeshD ascii = read_ply(dir / "extra_ascii.ply");
    expect_square_positions(ascii);
    EXPECT_EQ(ascii.triangles, SQUARE_TRIANGLES);
}

// A list property on the vertices (variable-size vertex records).
TEST(Ply, ListPropertyOnVertices) {
    TempDir dir;
    const std::string header =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property list uchar float weights\nproperty float y\nproperty float z\n"
        "property list int double extra\n"
        "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    Bytes data(std::endian::big);
    data.put(1.0f).put<std::uint8_t>(2).put(0.5f, 0.5f).put(2.0f, 3.0f).put<std::int32_t>(0);
    data.put(4.0f).put<std::uint8_t>(0).put(5.0f, 6.0f).put<std::int32_t>(1).put(8.0);
    data.put(7.0f).put<std::uint8_t>(3).put(0.1f, 0.2f, 0.7f).put(8.0f, 9.0f);
    data.put<std::int32_t>(2).put(1.0, 2.0);
    data.put<std::uint8_t>(3).put<std::uint32_t>(0, 1, 2);
    write_bytes(dir / "vlist.ply", header + data.str());
    const TriangleMeshD mesh = read_ply(dir / "vlist.ply");
    ASSERT_EQ(mesh.num_vertices(), 3u);
    EXPECT_EQ(mesh.positions[0], (Vec3d{1, 2, 3}));
    EXPECT_EQ(mesh.positions[1], (Vec3d{4, 5, 6}));
    EXPECT_EQ(mesh.positions[2], (Vec3d{7, 8, 9}));
    EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{0, 1, 2}}));

    write_bytes(dir / "vlist_ascii.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                "property list uchar float weights\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar uint vertex_indices\nend_header\n"
                "1 2 0.5 0.5 2 3\n4 0 5 6\n7 3 0.1 0.2 0.7 8 9\n3 0 1 2\n");
    const TriangleMeshD ascii = read_ply(dir / "vlist_ascii.ply");
    EXPECT_EQ(ascii.positions, mesh.positions);
    EXPECT_EQ(ascii.triangles, mesh.triangles);
}

TEST(Ply, EdgeElementAfterFacesIsSkipped) {
    TempDir dir;
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
        "property float y\nproperty float z\nelement face 2\n"
        "property list uchar int vertex_indices\nelement edge 3\nproperty int vertex1\n"
        "property int vertex2\nproperty uchar red\nelement material 1\n"
        "property list uchar char name\nend_header\n";
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(1.0f, 1.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint8_t>(3).put<std::int32_t>(0, 1, 2);
    data.put<std::uint8_t>(3).put<std::int32_t>(0, 2, 3);
    for (int e = 0; e < 3; ++e) {
        data.put<std::int32_t>(e, e + 1).put<std::uint8_t>(200);
    }
    data.put<std::uint8_t>(4).put<std::int8_t>('s', 'k', 'i', 'p');
    write_bytes(dir / "edges.ply", header + data.str());
    const TriangleMeshD mesh = read_ply(dir / "edges.ply");
    expect_square_positions(mesh);
    EXPECT_EQ(mesh.triangles, SQUARE_TRIANGLES);

    write_bytes(
        dir / "edges_ascii.ply",
        std::string(ASCII_SQUARE)
                .replace(std::string(ASCII_SQUARE).find("end_header"), 10,
                         "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header") +
            "0 1\n1 2\n");
    const TriangleMeshD ascii = read_ply(dir / "edges_ascii.ply");
    expect_square_positions(ascii);
    EXPECT_EQ(ascii.triangles, SQUARE_TRIANGLES);
}

TEST(Ply, FacesBeforeVertices) {
    TempDir dir;
    write_bytes(dir / "order.ply",
                "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
                "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "end_header\n3 2 0 1\n0 0 0\n1 0 0\n0 1 0\n");
    const TriangleMeshD mesh = read_ply(dir / "order.ply");
    EXPECT_EQ(mesh.num_vertices(), 3u);
    EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{2, 0, 1}}));
}

TEST(Ply, PolygonsAreFanTriangulated) {
    TempDir dir;
    write_bytes(dir / "poly.ply",
                "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
                "property float z\nelement face 3\nproperty list uchar int vertex_indices\n"
                "end_header\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 2 0\n-1 1 0\n"
                "4 0 1 2 3\n5 0 1 2 3 4\n6 5 4 3 2 1 0\n");
    const TriangleMeshD mesh = read_ply(dir / "poly.ply");
    const std::vector<Triangle> expected = {
        {0, 1, 2}, {0, 2, 3},                        // quad
        {0, 1, 2}, {0, 2, 3}, {0, 3, 4},             // pentagon
        {5, 4, 3}, {5, 3, 2}, {5, 2, 1}, {5, 1, 0},  // hexagon
    };
    EXPECT_EQ(mesh.triangles, expected);
}

TEST(Ply, VertexIndexAliasWithUshortCounts) {
    TempDir dir;
    const std::string header =
        "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float32 x\n"
        "property float32 y\nproperty float32 z\nelement face 1\n"
        "property list ushort uint vertex_index\nend_header\n";
    Bytes data(std::endian::big);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(1.0f, 1.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint16_t>(4).put<std::uint32_t>(0, 1, 2, 3);
    write_bytes(dir / "alias.ply", header + data.str());
    const TriangleMeshD mesh = read_ply(dir / "alias.ply");
    expect_square_positions(mesh);
    EXPECT_EQ(mesh.triangles, SQUARE_TRIANGLES);
}

TEST(Ply, OtherFacePropertiesAreSkipped) {
    TempDir dir;
    write_bytes(dir / "faceprops.ply",
                "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                "property float z\nelement face 2\nproperty uchar flags\n"
                "property list uchar float texcoord\nproperty list int int vertex_indices\n"
                "property double quality\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                "7 6 0 0 1 0 1 1 3 0 1 2 0.5\n0 0 3 0 2 3 nan\n");
    const TriangleMeshD mesh = read_ply(dir / "faceprops.ply");
    expect_square_positions(mesh);
    EXPECT_EQ(mesh.triangles, SQUARE_TRIANGLES);
}

// Every scalar type name, in ASCII and binary, for x, y and z.
template <typename T>
std::string binary_xyz(T x, T y, T z, std::endian order) {
    return Bytes(order).put(x, y, z).str();
}

TEST(Ply, EveryScalarTypeForCoordinates) {
    struct Case {
        const char* name;
        std::string little;  // (1, 2, -3) or (1, 2, 3) for unsigned types
        std::string big;
        double z;
    };
    const auto make = []<typename T>(const char* name, T) {
        const T z = std::is_signed_v<T> ? T(-3) : T(3);
        return Case{name, binary_xyz<T>(1, 2, z, std::endian::little),
                    binary_xyz<T>(1, 2, z, std::endian::big), static_cast<double>(z)};
    };
    const std::vector<Case> cases = {
        make("char", std::int8_t{}),     make("int8", std::int8_t{}),
        make("uchar", std::uint8_t{}),   make("uint8", std::uint8_t{}),
        make("short", std::int16_t{}),   make("int16", std::int16_t{}),
        make("ushort", std::uint16_t{}), make("uint16", std::uint16_t{}),
        make("int", std::int32_t{}),     make("int32", std::int32_t{}),
        make("uint", std::uint32_t{}),   make("uint32", std::uint32_t{}),
        make("float", float{}),          make("float32", float{}),
        make("double", double{}),        make("float64", double{}),
    };
    TempDir dir;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string properties = fmt::format(
            "element vertex 1\nproperty {0} x\nproperty {0} y\nproperty {0} z\nend_header\n",
            c.name);
        const Vec3d expected{1, 2, c.z};
        write_bytes(dir / "t.ply",
                    "ply\nformat ascii 1.0\n" + properties + fmt::format("1 2 {}\n", c.z));
        EXPECT_EQ(read_ply(dir / "t.ply").positions.at(0), expected);
        write_bytes(dir / "t.ply",
                    "ply\nformat binary_little_endian 1.0\n" + properties + c.little);
        EXPECT_EQ(read_ply(dir / "t.ply").positions.at(0), expected);
        write_bytes(dir / "t.ply", "ply\nformat binary_big_endian 1.0\n" + properties + c.big);
        EXPECT_EQ(read_ply(dir / "t.ply").positions.at(0), expected);
    }
}

// A float property means the float's value, not the decimal's double.
TEST(Ply, AsciiFloatPropertyRoundsToFloat) {
    TempDir dir;
    write_bytes(dir / "f.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty double y\n"
                "property float z\nend_header\n0.1 0.1 1e-50\n");
    const TriangleMeshD mesh = read_ply(dir / "f.ply");
    EXPECT_EQ(mesh.positions[0].x, static_cast<double>(0.1f));
    EXPECT_EQ(mesh.positions[0].y, 0.1);
    EXPECT_EQ(mesh.positions[0].z, 0.0);  // underflows float: the nearest float is 0
}

// ---------------------------------------------------------------------------------------------
// Broken files: IoError naming the file and the problem
// ---------------------------------------------------------------------------------------------

class PlyBroken : public ::testing::Test {
protected:
    // Writes `bytes` to a file and expects read_ply to fail with a message naming the file and
    // containing every fragment.
    std::string expect_broken(const std::string& bytes,
                              std::initializer_list<std::string_view> fragments) {
        const auto path = m_dir / "broken.ply";
        write_bytes(path, bytes);
        std::string message = expect_io_error([&] { read_ply(path); }, fragments);
        EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
        return message;
    }

    static std::string with_data(const std::string& header_tail, const std::string& data,
                                 const char* format = "ascii") {
        return fmt::format("ply\nformat {} 1.0\n", format) + header_tail + "end_header\n" + data;
    }

    TempDir m_dir;
};

constexpr const char* XYZ_FLOAT =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\n";
constexpr const char* TRIANGLE_VERTICES = "0 0 0\n1 0 0\n0 1 0\n";

TEST_F(PlyBroken, MissingFile) {
    const auto path = m_dir / "nope.ply";
    expect_io_error([&] { read_ply(path); }, {path.string(), "cannot open"});
    expect_io_error([&] { read_ply(m_dir.path()); }, {m_dir.path().string(), "directory"});
}

TEST_F(PlyBroken, EmptyFile) {
    expect_broken("", {"not a PLY file", "empty file"});
}

TEST_F(PlyBroken, NotAPlyFile) {
    expect_broken("solid cube\nfacet normal 0 0 1\n", {"not a PLY file", "'solid cube'"});
    expect_broken(std::string("\x89PNG\r\n\x1a\n\0\0", 10), {"not a PLY file", "\\x89PNG"});
    expect_broken("plyfoo\n", {"not a PLY file", "expected 'ply'"});
}

TEST_F(PlyBroken, MissingEndHeader) {
    expect_broken("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
                  {"truncated PLY header", "expected an 'end_header' line", "after line 4"});
    expect_broken("ply\n", {"end_header"});
}

TEST_F(PlyBroken, UnknownFormatAndVersion) {
    expect_broken(with_data(XYZ_FLOAT, "", "binary_middle_endian"),
                  {"line 2", "unknown PLY format 'binary_middle_endian'",
                   "expected one of ascii, binary_little_endian, binary_big_endian"});
    expect_broken("ply\nformat ascii 2.0\nend_header\n",
                  {"line 2", "unsupported PLY version '2.0'"});
    expect_broken("ply\nelement vertex 0\nend_header\n", {"no format line"});
    expect_broken("ply\nformat ascii\nend_header\n", {"line 2", "malformed format line"});
}

TEST_F(PlyBroken, MalformedHeaderLines) {
    expect_broken(with_data("element vertex 3\nproperty int64 x\n", ""),
                  {"line 4", "unknown property type 'int64'", "expected one of char, uchar"});
    expect_broken(with_data("property float x\n", ""), {"line 3", "property before any element"});
    expect_broken(with_data("element vertex -3\n", ""),
                  {"line 3", "bad count for element 'vertex'", "got '-3'"});
    expect_broken(with_data("element vertex lots\n", ""), {"line 3", "got 'lots'"});
    expect_broken(with_data("elemnt vertex 3\n", ""),
                  {"line 3", "unknown header keyword 'elemnt'"});
    expect_broken(with_data("element vertex 1\nproperty float x\nproperty float x\n", ""),
                  {"line 5", "duplicate property 'x'"});
    expect_broken(with_data("element vertex 1\nelement vertex 1\n", ""),
                  {"line 4", "duplicate element 'vertex'"});
    expect_broken(with_data("element face 1\nproperty list float int vertex_indices\n", ""),
                  {"line 4", "count type float, expected an integer type"});
}

TEST_F(PlyBroken, MissingVertexElementOrCoordinates) {
    expect_broken(with_data("element face 0\nproperty list uchar int vertex_indices\n", ""),
                  {"no vertex element"});
    expect_broken(
        with_data("element vertex 1\nproperty float y\nproperty float z\n", "0 0\n"),
        {"element 'vertex' has no property 'x'", "expected scalar properties x, y and z"});
    expect_broken(with_data("element vertex 1\nproperty float x\nproperty float y\n", "0 0\n"),
                  {"no property 'z'"});
    expect_broken(with_data("element vertex 1\nproperty list uchar float x\nproperty float y\n"
                            "property float z\n",
                            "1 0 0 0\n"),
                  {"property 'x' of element 'vertex' is a list, expected a scalar"});
}

TEST_F(PlyBroken, BadFaceDeclarations) {
    const std::string vertices =
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    expect_broken(with_data(vertices + "element face 1\nproperty list uchar int indices\n",
                            TRIANGLE_VERTICES),
                  {"element 'face' has no property 'vertex_indices'"});
    expect_broken(
        with_data(vertices + "element face 1\nproperty int vertex_indices\n", TRIANGLE_VERTICES),
        {"property 'vertex_indices' of element 'face' is a scalar, expected a list"});
    expect_broken(with_data(vertices + "element face 1\nproperty list uchar float vertex_indices\n",
                            TRIANGLE_VERTICES),
                  {"item type float, expected an integer type"});
}

TEST_F(PlyBroken, TruncatedBinaryData) {
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n";
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint8_t>(3).put<std::int32_t>(0, 1, 2);
    const std::string file = header + data.str();
    expect_broken(file.substr(0, file.size() - 5),
                  {"truncated binary data in element 'face' record 0 of 1",
                   "expected 12 bytes for property 'vertex_indices', got 7"});
    expect_broken(file.substr(0, header.size() + 30),
                  {"line 3", "truncated data or wrong count",
                   "element 'vertex' declares 3 records of at least 12 bytes",
                   "expected at most 2 in the 30 bytes of data left"});
    // Faces first: their lists are longer than the minimum, so the vertices are cut short only
    // once the faces are decoded.
    const std::string faces_first_header =
        "ply\nformat binary_little_endian 1.0\nelement face 1\n"
        "property list uchar int vertex_indices\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n";
    Bytes faces_first(std::endian::little);
    faces_first.put<std::uint8_t>(3).put<std::int32_t>(0, 1, 2);
    faces_first.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    const std::string file2 = faces_first_header + faces_first.str();
    expect_broken(file2.substr(0, file2.size() - 5),
                  {"truncated binary data in element 'vertex'",
                   "expected 3 records of 12 bytes, got 31 bytes"});
    expect_broken(file + "xyz", {"3 bytes of unexpected data after the last element"});
}

// Every proper prefix of a valid binary file fails cleanly, wherever it is cut.
TEST_F(PlyBroken, EveryPrefixOfABinaryFileIsRejected) {
    const auto path = m_dir / "full.ply";
    TriangleMeshD mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = SQUARE_TRIANGLES;
    write_ply(path, mesh, PlyFormat::binary_big_endian);
    const std::string file = test::read_bytes(path);
    const auto prefix_path = m_dir / "prefix.ply";
    for (std::size_t size = 0; size < file.size(); ++size) {
        write_bytes(prefix_path, std::string_view(file).substr(0, size));
        try {
            read_ply(prefix_path);
            ADD_FAILURE() << "prefix of " << size << " bytes was accepted";
        } catch (const IoError& e) {
            ASSERT_EQ(std::string(e.what()).rfind(prefix_path.string(), 0), 0u) << e.what();
        }
    }
}

TEST_F(PlyBroken, TruncatedAsciiData) {
    expect_broken(with_data(XYZ_FLOAT, TRIANGLE_VERTICES),
                  {"line 7", "truncated data or wrong count",
                   "element 'face' declares 1 records of at least 2 bytes",
                   "expected at most 0 in the 0 bytes of data left"});
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "\n\n\n\n"),
                  {"line 17", "truncated data, expected 1 records of element 'face', got 0"});
    expect_broken(
        with_data(XYZ_FLOAT, "0 0 0\n1 0 0\n0 1 0\n3 0 1"),
        {"line 13", "truncated data in element 'face' record 0",
         "expected a int value for property 'vertex_indices' item", "got the end of the file"});
    expect_broken(with_data(XYZ_FLOAT, "0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
                  {"line 11", "missing data in element 'vertex' record 1",
                   "expected a float value for property 'z', got the end of the line"});
}

TEST_F(PlyBroken, HugeCountsFailBeforeAllocating) {
    // 999999999999 vertices: far beyond 32-bit indices, and far beyond the data.
    expect_broken(with_data("element vertex 999999999999\nproperty double x\nproperty double y\n"
                            "property double z\n",
                            "0 0 0\n", "binary_little_endian"),
                  {"line 3", "999999999999"});
    // 100M vertices of 24 bytes (2.4 GB) with 24 bytes of data: refused by size.
    expect_broken(with_data("element vertex 100000000\nproperty double x\nproperty double y\n"
                            "property double z\n",
                            std::string(24, '\0'), "binary_little_endian"),
                  {"line 3", "element 'vertex' declares 100000000 records of at least 24 bytes",
                   "expected at most 1 in the 24 bytes of data left"});
    expect_broken(with_data(std::string(XYZ_FLOAT).replace(std::string(XYZ_FLOAT).find("face 1"), 6,
                                                           "face 4000000000"),
                            TRIANGLE_VERTICES + std::string("3 0 1 2\n")),
                  {"line 7", "element 'face' declares 4000000000 records", "expected at most"});
    expect_broken(with_data("element vertex 50000000\nproperty float x\nproperty float y\n"
                            "property float z\n",
                            "1 2 3\n"),
                  {"line 3", "declares 50000000 records", "expected at most 1 in the 6 bytes"});
}

TEST_F(PlyBroken, HugeListLengthIsTruncation) {
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uint int vertex_indices\nend_header\n";
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint32_t>(4000000000u).put<std::int32_t>(0, 1, 2);
    expect_broken(header + data.str(),
                  {"truncated binary data in element 'face' record 0",
                   "expected 16000000000 bytes for property 'vertex_indices', got 12"});
}

TEST_F(PlyBroken, NegativeIndex) {
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3 0 -1 2\n"),
                  {"line 13", "face 0 corner 1 has vertex index -1", "expected 0 <= index < 3"});
    Bytes data(std::endian::big);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint8_t>(3).put<std::int32_t>(0, 1, -7);
    const std::string message =
        expect_broken(with_data(XYZ_FLOAT, data.str(), "binary_big_endian"),
                      {"face 0 corner 2 has vertex index -7", "expected 0 <= index < 3"});
    EXPECT_EQ(message.find("line"), std::string::npos) << message;
}

TEST_F(PlyBroken, IndexNotBelowVertexCount) {
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3 0 1 3\n"),
                  {"line 13", "face 0 corner 2 has vertex index 3", "expected 0 <= index < 3"});
    const std::string uint_faces =
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar uint vertex_indices\n";
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint8_t>(3).put<std::uint32_t>(4294967295u, 1, 2);
    expect_broken(with_data(uint_faces, data.str(), "binary_little_endian"),
                  {"face 0 corner 0 has vertex index 4294967295", "expected 0 <= index < 3"});
}

TEST_F(PlyBroken, FaceWithTwoVertices) {
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "2 0 1\n"),
                  {"line 13", "face 0 has 2 vertices, expected at least 3"});
    Bytes data(std::endian::little);
    data.put(0.0f, 0.0f, 0.0f).put(1.0f, 0.0f, 0.0f).put(0.0f, 1.0f, 0.0f);
    data.put<std::uint8_t>(0);
    expect_broken(with_data(XYZ_FLOAT, data.str(), "binary_little_endian"),
                  {"face 0 has 0 vertices, expected at least 3"});
}

TEST_F(PlyBroken, RepeatedVertexInATriangle) {
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3 0 1 1\n"),
                  {"line 13", "face 0 repeats a vertex in triangle (0, 1, 1)"});
}

TEST_F(PlyBroken, NonFiniteCoordinates) {
    expect_broken(with_data(XYZ_FLOAT, "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
                  {"line 11", "vertex 1 has a non-finite coordinate", "got (nan, 0, 0)"});
    expect_broken(with_data(XYZ_FLOAT, "0 0 0\n1 0 0\n0 -inf 0\n3 0 1 2\n"),
                  {"line 12", "vertex 2 has a non-finite coordinate", "-inf"});
    Bytes data(std::endian::little);
    data.put(0.0, 0.0, 0.0).put(1.0, 0.0, std::numeric_limits<double>::infinity());
    data.put(0.0, std::numeric_limits<double>::quiet_NaN(), 0.0);
    expect_broken(with_data("element vertex 3\nproperty double x\nproperty double y\n"
                            "property double z\n",
                            data.str(), "binary_little_endian"),
                  {"vertex 1 has a non-finite coordinate", "got (1, 0, inf)"});
    // Finite in double, beyond the float range of the declared type.
    expect_broken(
        with_data(XYZ_FLOAT, "0 0 0\n1e39 0 0\n0 1 0\n3 0 1 2\n"),
        {"line 11", "bad value for property 'x'", "a value in the range of float", "'1e39'"});
}

TEST_F(PlyBroken, GarbageTokens) {
    expect_broken(with_data(XYZ_FLOAT, "0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n"),
                  {"line 11", "bad value for property 'y' of element 'vertex' record 1",
                   "expected a number of type float", "got 'abc'"});
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3.0 0 1 2\n"),
                  {"line 13", "bad value for property 'vertex_indices' list length",
                   "expected a number of type uchar", "got '3.0'"});
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "300 0 1 2\n"),
                  {"line 13", "expected a uchar in [0, 255]", "got '300'"});
    expect_broken(with_data(XYZ_FLOAT, "0 0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  {"line 10", "extra value '0' after element 'vertex' record 0",
                   "expected the end of the line"});
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3 0 1 2\nmore\n"),
                  {"line 14", "unexpected data after the last element", "got 'more'"});
    expect_broken(with_data(XYZ_FLOAT, std::string(TRIANGLE_VERTICES) + "3 0x1 1 2\n"),
                  {"line 13", "got '0x1'"});
}

// Random byte corruption: read_ply returns a valid mesh or throws IoError, nothing else (the
// sanitizers watch the memory accesses).
TEST_F(PlyBroken, RandomCorruptionNeverCrashes) {
    std::mt19937 rng(1234);
    const auto path = m_dir / "fuzz.ply";
    TriangleMesh mesh = test::tricky_mesh<float>();
    mesh.positions.resize(12);
    mesh.triangles.resize(10);
    for (const PlyFormat format : ALL_FORMATS) {
        write_ply(path, mesh, format);
        const std::string original = test::read_bytes(path);
        std::uniform_int_distribution<std::size_t> position(0, original.size() - 1);
        std::uniform_int_distribution<int> byte(0, 255);
        int num_rejected = 0;
        for (int trial = 0; trial < 150; ++trial) {
            std::string corrupted = original;
            const int num_flips = 1 + trial % 4;
            for (int i = 0; i < num_flips; ++i) {
                corrupted[position(rng)] = static_cast<char>(byte(rng));
            }
            write_bytes(path, corrupted);
            try {
                const TriangleMeshD read = read_ply(path);
                EXPECT_NO_THROW(geometry::validate_mesh(read, "fuzz"));
            } catch (const IoError&) {
                ++num_rejected;
            }
        }
        EXPECT_GT(num_rejected, 0) << to_string(format);
    }
}

// ---------------------------------------------------------------------------------------------
// A real file
// ---------------------------------------------------------------------------------------------

std::uint64_t little_endian_u64(const std::string& bytes, std::size_t at) {
    std::uint64_t value = 0;
    for (int i = 7; i >= 0; --i) {
        value = (value << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(i)]);
    }
    return value;
}

TEST(PlyRealFile, ClothFunnelFrame227) {
    const std::filesystem::path path =
        std::filesystem::path(PLIANT_SHARED_DATA_DIR) / "cloth-funnel" / "frames" / "227.ply";
    if (!std::filesystem::exists(path)) {
        GTEST_SKIP() << "external data not found: " << path;
    }
    const TriangleMeshD mesh = read_ply(path);
    EXPECT_EQ(mesh.num_vertices(), 9450u);
    EXPECT_EQ(mesh.num_triangles(), 18484u);

    // Decode the first vertex and the first face by hand from the bytes after end_header.
    const std::string bytes = test::read_bytes(path);
    const std::size_t data = bytes.find("end_header\n") + std::string("end_header\n").size();
    for (int k = 0; k < 3; ++k) {
        const auto expected =
            std::bit_cast<double>(little_endian_u64(bytes, data + 8 * static_cast<std::size_t>(k)));
        EXPECT_EQ(std::bit_cast<std::uint64_t>(mesh.positions[0][k]),
                  std::bit_cast<std::uint64_t>(expected))
            << "axis " << k;
    }
    EXPECT_NEAR(mesh.positions[0].x, -0.0029849, 1e-7);
    const std::size_t face0 = data + std::size_t{9450} * 24;
    ASSERT_EQ(static_cast<unsigned char>(bytes[face0]), 3);
    for (int k = 0; k < 3; ++k) {
        const std::size_t at = face0 + 1 + 4 * static_cast<std::size_t>(k);
        const auto index =
            static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at]) |
                                       (static_cast<unsigned char>(bytes[at + 1]) << 8) |
                                       (static_cast<unsigned char>(bytes[at + 2]) << 16) |
                                       (static_cast<unsigned char>(bytes[at + 3]) << 24));
        EXPECT_EQ(static_cast<std::uint32_t>(mesh.triangles[0][k]), index) << "corner " << k;
    }

    // And it survives every format bit for bit.
    TempDir dir;
    for (const PlyFormat format : ALL_FORMATS) {
        SCOPED_TRACE(to_string(format));
        write_ply(dir / "227.ply", mesh, format);
        test::expect_bitwise_equal(mesh, read_ply(dir / "227.ply"));
    }
}

}  // namespace
}  // namespace pliant::io
