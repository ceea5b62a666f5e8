// COLMAP sparse models: a tiny model written by hand as text and the same written here byte by
// byte in COLMAP's documented binary layout read equal; the writer round-trips; hostile inputs
// give IoError naming the file and the problem.
#include "pliant/io/colmap_model.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "../support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using test::write_bytes;

constexpr std::string_view CAMERAS_TXT =
    "# Camera list with one line of data per camera:\n"
    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    "# Number of cameras: 2\n"
    "1 OPENCV 640 480 500.5 501.25 320.1 239.9 -0.1 0.02 0.001 -0.002\n"
    "2 SIMPLE_PINHOLE 320 240 250 160 120\n";
constexpr std::string_view IMAGES_TXT =
    "# Image list with two lines of data per image:\n"
    "1 0.9 0.1 0.3 -0.2 1.5 -2.25 3 1 a.jpg\n"
    "10.5 20.25 7 30 40 -1\n"
    "2 1 0 0 0 0 0 4 2 b.jpg\n"
    "\n";
constexpr std::string_view POINTS_TXT =
    "# 3D point list\n"
    "7 0.5 -0.25 2 255 128 0 0.75 1 0\n";

// Little-endian bytes of a value, as COLMAP's WriteBinaryLittleEndian.
template <typename T>
void put(std::string& out, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out.append(b, sizeof(T));
}

std::string cameras_bin() {
    std::string s;
    put<std::uint64_t>(s, 2);
    put<std::int32_t>(s, 1);
    put<std::int32_t>(s, 4);  // OPENCV
    put<std::uint64_t>(s, 640);
    put<std::uint64_t>(s, 480);
    for (double p : {500.5, 501.25, 320.1, 239.9, -0.1, 0.02, 0.001, -0.002}) {
        put(s, p);
    }
    put<std::int32_t>(s, 2);
    put<std::int32_t>(s, 0);  // SIMPLE_PINHOLE
    put<std::uint64_t>(s, 320);
    put<std::uint64_t>(s, 240);
    for (double p : {250.0, 160.0, 120.0}) {
        put(s, p);
    }
    return s;
}

std::string images_bin() {
    std::string s;
    put<std::uint64_t>(s, 2);
    put<std::int32_t>(s, 1);
    for (double q : {0.9, 0.1, 0.3, -0.2, 1.5, -2.25, 3.0}) {
        put(s, q);
    }
    put<std::int32_t>(s, 1);
    s.append("a.jpg");
    s.push_back('\0');
    put<std::uint64_t>(s, 2);
    put(s, 10.5);
    put(s, 20.25);
    put<std::int64_t>(s, 7);
    put(s, 30.0);
    put(s, 40.0);
    put<std::int64_t>(s, -1);
    put<std::int32_t>(s, 2);
    for (double q : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0}) {
        put(s, q);
    }
    put<std::int32_t>(s, 2);
    s.append("b.jpg");
    s.push_back('\0');
    put<std::uint64_t>(s, 0);
    return s;
}

std::string points_bin() {
    std::string s;
    put<std::uint64_t>(s, 1);
    put<std::uint64_t>(s, 7);
    for (double x : {0.5, -0.25, 2.0}) {
        put(s, x);
    }
    s.push_back(static_cast<char>(255));
    s.push_back(static_cast<char>(128));
    s.push_back(static_cast<char>(0));
    put(s, 0.75);
    put<std::uint64_t>(s, 1);
    put<std::int32_t>(s, 1);
    put<std::int32_t>(s, 0);
    return s;
}

void write_text_model(const TempDir& dir) {
    write_bytes(dir / "cameras.txt", CAMERAS_TXT);
    write_bytes(dir / "images.txt", IMAGES_TXT);
    write_bytes(dir / "points3D.txt", POINTS_TXT);
}

void write_binary_model(const TempDir& dir) {
    write_bytes(dir / "cameras.bin", cameras_bin());
    write_bytes(dir / "images.bin", images_bin());
    write_bytes(dir / "points3D.bin", points_bin());
}

void expect_tiny_model(const ColmapModel& m) {
    ASSERT_EQ(m.cameras.size(), 2u);
    EXPECT_EQ(m.cameras[0].id, 1u);
    EXPECT_EQ(m.cameras[0].model_id, 4);
    EXPECT_EQ(m.cameras[0].width, 640u);
    EXPECT_EQ(m.cameras[0].height, 480u);
    EXPECT_EQ(m.cameras[0].params,
              (std::vector<double>{500.5, 501.25, 320.1, 239.9, -0.1, 0.02, 0.001, -0.002}));
    EXPECT_EQ(m.cameras[1].model_id, 0);
    EXPECT_EQ(m.cameras[1].params, (std::vector<double>{250.0, 160.0, 120.0}));
    ASSERT_EQ(m.images.size(), 2u);
    EXPECT_EQ(m.images[0].qvec, (std::array<double, 4>{0.9, 0.1, 0.3, -0.2}));
    EXPECT_EQ(m.images[0].tvec, (std::array<double, 3>{1.5, -2.25, 3.0}));
    EXPECT_EQ(m.images[0].camera_id, 1u);
    EXPECT_EQ(m.images[0].name, "a.jpg");
    ASSERT_EQ(m.images[0].points2d.size(), 2u);
    EXPECT_EQ(m.images[0].points2d[0].x, 10.5);
    EXPECT_EQ(m.images[0].points2d[0].point3d_id, 7);
    EXPECT_EQ(m.images[0].points2d[1].point3d_id, -1);
    EXPECT_EQ(m.images[1].name, "b.jpg");
    EXPECT_TRUE(m.images[1].points2d.empty());
    ASSERT_EQ(m.points.size(), 1u);
    EXPECT_EQ(m.points[0].id, 7u);
    EXPECT_EQ(m.points[0].xyz, (std::array<double, 3>{0.5, -0.25, 2.0}));
    EXPECT_EQ(m.points[0].rgb, (std::array<std::uint8_t, 3>{255, 128, 0}));
    EXPECT_EQ(m.points[0].error, 0.75);
    ASSERT_EQ(m.points[0].track.size(), 1u);
    EXPECT_EQ(m.points[0].track[0].image_id, 1u);
    EXPECT_EQ(m.points[0].track[0].point2d_index, 0u);
}

TEST(ColmapModel, TextAndBinaryReadEqual) {
    TempDir text, binary;
    write_text_model(text);
    write_binary_model(binary);
    EXPECT_TRUE(is_colmap_model_directory(text.path()));
    EXPECT_TRUE(is_colmap_model_directory(binary.path()));
    expect_tiny_model(read_colmap_model(text.path()));
    expect_tiny_model(read_colmap_model(binary.path()));
}

TEST(ColmapModel, WriterRoundTripsBothFormats) {
    TempDir src, text, binary;
    write_text_model(src);
    const ColmapModel m = read_colmap_model(src.path());
    write_colmap_model(text.path(), m, ColmapFormat::text);
    write_colmap_model(binary.path(), m, ColmapFormat::binary);
    expect_tiny_model(read_colmap_model(text.path(), ColmapFormat::text));
    expect_tiny_model(read_colmap_model(binary.path(), ColmapFormat::binary));
    // The binary writer's bytes are the hand-written layout's.
    EXPECT_EQ(test::read_bytes(binary / "cameras.bin"), cameras_bin());
    EXPECT_EQ(test::read_bytes(binary / "images.bin"), images_bin());
    EXPECT_EQ(test::read_bytes(binary / "points3D.bin"), points_bin());
}

TEST(ColmapModel, PointsAreOptional) {
    TempDir dir;
    write_bytes(dir / "cameras.txt", CAMERAS_TXT);
    write_bytes(dir / "images.txt", IMAGES_TXT);
    EXPECT_TRUE(read_colmap_model(dir.path()).points.empty());
}

TEST(ColmapModel, MissingFilesAndNonModels) {
    TempDir dir;
    EXPECT_FALSE(is_colmap_model_directory(dir.path()));
    expect_io_error([&] { read_colmap_model(dir.path()); }, {"not a COLMAP model", "cameras.txt"});
    write_bytes(dir / "cameras.txt", CAMERAS_TXT);
    expect_io_error([&] { read_colmap_model(dir.path()); }, {"images.txt"});
}

TEST(ColmapModel, HostileTextInputs) {
    const auto cameras = [](std::string_view text) {
        return parse_colmap_cameras(text, ColmapFormat::text, "cameras.txt");
    };
    expect_io_error([&] { cameras("1 FANCY 640 480 1 2 3\n"); },
                    {"cameras.txt", "line 1", "unknown camera model", "OPENCV"});
    expect_io_error([&] { cameras("1 PINHOLE 640 480 1 2 3\n"); },
                    {"line 1", "PINHOLE has 4 parameters, got 3"});
    expect_io_error([&] { cameras("1 PINHOLE 640 480 nan 2 3 4\n"); }, {"finite"});
    expect_io_error([&] { cameras("1 PINHOLE 0 480 1 2 3 4\n"); }, {"WIDTH"});
    expect_io_error([&] { cameras("1 PINHOLE 99999999 480 1 2 3 4\n"); }, {"WIDTH"});
    expect_io_error([&] { cameras("-3 PINHOLE 640 480 1 2 3 4\n"); }, {"CAMERA_ID"});
    const auto images = [](std::string_view text) {
        return parse_colmap_images(text, ColmapFormat::text, "images.txt");
    };
    expect_io_error([&] { images("1 1 0 0 0 0 0 0 1\n\n"); }, {"10 words"});
    expect_io_error([&] { images("1 0 0 0 0 0 0 0 1 a.jpg\n\n"); }, {"quaternion"});
    expect_io_error([&] { images("1 1 0 0 0 0 0 inf 1 a.jpg\n\n"); }, {"translation"});
    expect_io_error([&] { images("1 1 0 0 0 0 0 0 1 a.jpg\n1 2\n"); }, {"triples"});
    const auto points = [](std::string_view text) {
        return parse_colmap_points(text, ColmapFormat::text, "points3D.txt");
    };
    expect_io_error([&] { points("1 0 0 0 300 0 0 0\n"); }, {"colour"});
    expect_io_error([&] { points("1 0 0 0 1 0 0 0 5\n"); }, {"pairs"});
}

TEST(ColmapModel, HostileBinaryInputs) {
    // A count larger than the file can hold is refused before anything is allocated.
    std::string huge;
    put<std::uint64_t>(huge, std::uint64_t{1} << 60);
    expect_io_error([&] { parse_colmap_cameras(huge, ColmapFormat::binary, "cameras.bin"); },
                    {"cameras.bin", "bytes"});
    expect_io_error([&] { parse_colmap_images(huge, ColmapFormat::binary, "images.bin"); },
                    {"images.bin", "bytes"});
    expect_io_error([&] { parse_colmap_points(huge, ColmapFormat::binary, "points3D.bin"); },
                    {"points3D.bin", "bytes"});
    // Truncated records, trailing bytes.
    const std::string c = cameras_bin();
    expect_io_error(
        [&] { parse_colmap_cameras(c.substr(0, c.size() - 3), ColmapFormat::binary, "c"); },
        {"truncated"});
    expect_io_error([&] { parse_colmap_cameras(c + "x", ColmapFormat::binary, "c"); },
                    {"unexpected bytes"});
    // An unknown model id.
    std::string bad = c;
    const std::int32_t model = 42;
    std::memcpy(bad.data() + 8 + 4, &model, 4);
    expect_io_error([&] { parse_colmap_cameras(bad, ColmapFormat::binary, "c"); },
                    {"unknown camera model id 42"});
    // A NaN parameter.
    bad = c;
    const double nan = std::nan("");
    std::memcpy(bad.data() + 8 + 24, &nan, 8);
    expect_io_error([&] { parse_colmap_cameras(bad, ColmapFormat::binary, "c"); }, {"finite"});
    // A name without its NUL.
    std::string im;
    put<std::uint64_t>(im, 1);
    im += images_bin().substr(8, 4 + 56 + 4 + 5);  // up to "a.jpg"
    im += std::string(20, 'x');
    expect_io_error([&] { parse_colmap_images(im, ColmapFormat::binary, "i"); }, {"NUL"});
}

TEST(ColmapModel, CrossReferencesAreChecked) {
    TempDir dir;
    write_text_model(dir);
    ColmapModel m = read_colmap_model(dir.path());
    ColmapModel bad = m;
    bad.images[1].camera_id = 9;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"names camera 9"});
    bad = m;
    bad.cameras[1].id = 1;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"duplicate camera id 1"});
    bad = m;
    bad.images[1].id = 1;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"duplicate image id 1"});
    bad = m;
    bad.points[0].track[0].image_id = 5;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"names image 5"});
    bad = m;
    bad.points[0].track[0].point2d_index = 2;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"2-D point 2"});
    bad = m;
    bad.images[0].points2d[1].point3d_id = 8;
    expect_io_error([&] { validate_colmap_model(bad, "model"); }, {"3-D point 8"});
}

TEST(ColmapModel, ModelNamesAndCounts) {
    EXPECT_EQ(colmap_camera_model_name(4), "OPENCV");
    EXPECT_EQ(colmap_camera_model_id("OPENCV_FISHEYE"), 5);
    EXPECT_EQ(colmap_camera_model_num_params(6), 12);
    EXPECT_FALSE(colmap_camera_model_name(11).has_value());
    EXPECT_EQ(colmap_camera_model_num_params(-1), 0);
}

}  // namespace
}  // namespace pliant::io
