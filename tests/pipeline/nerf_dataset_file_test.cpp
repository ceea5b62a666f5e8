// transforms.json reading and writing: the NeRF-synthetic layout (camera_angle_x, file paths
// without extension, RGBA over a background), instant-ngp intrinsics, the round trip of
// `pliant dataset`'s cameras (same rays), and broken datasets.
#include "pliant/pipeline/nerf_dataset_file.hpp"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <cmath>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/png.hpp"
#include "support/test_files.hpp"

namespace pliant::pipeline {
namespace {

using io::test::TempDir;
using io::test::write_bytes;

// A 4 × 3 RGBA PNG: pixel (x, y) = (60 x, 80 y, 200, alpha), alpha 255 except pixel (0, 0) = 0
// and (1, 0) = 128.
void write_rgba_png(const std::filesystem::path& path, int w = 4, int h = 3) {
    std::vector<unsigned char> px(static_cast<std::size_t>(4 * w * h));
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            unsigned char* p = px.data() + 4 * (y * w + x);
            p[0] = static_cast<unsigned char>(60 * x);
            p[1] = static_cast<unsigned char>(80 * y);
            p[2] = 200;
            p[3] = y == 0 && x == 0 ? 0 : (y == 0 && x == 1 ? 128 : 255);
        }
    }
    ASSERT_NE(stbi_write_png(path.string().c_str(), w, h, 4, px.data(), 4 * w), 0);
}

const char* IDENTITY = "[[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]";

std::string blender_json(const std::string& frames_extra = "",
                         const std::string& matrix = IDENTITY) {
    return std::string(R"({"camera_angle_x": 0.6911112070083618, "frames": [)") +
           R"({"file_path": "./train/r_0", "transform_matrix": )" + matrix + "}" + frames_extra +
           "]}";
}

TEST(NerfDataset, ReadsTheBlenderLayoutAndCompositesAlpha) {
    const TempDir dir;
    std::filesystem::create_directories(dir / "train");
    write_rgba_png(dir / "train/r_0.png");
    write_bytes(dir / "transforms_train.json", blender_json());
    ReadNerfDatasetOptions options;
    options.background = {1.0f, 1.0f, 1.0f};
    const nerf::Dataset ds = read_nerf_dataset(dir / "transforms_train.json", options);
    ASSERT_EQ(ds.views.size(), 1u);
    EXPECT_EQ(ds.intrinsics.width, 4);
    EXPECT_EQ(ds.intrinsics.height, 3);
    EXPECT_NEAR(ds.intrinsics.fx, 2.0 / std::tan(0.5 * 0.6911112070083618), 1e-9);
    EXPECT_DOUBLE_EQ(ds.intrinsics.fy, ds.intrinsics.fx);
    EXPECT_DOUBLE_EQ(ds.intrinsics.cx, 2.0);
    EXPECT_DOUBLE_EQ(ds.intrinsics.cy, 1.5);
    EXPECT_FALSE(ds.box.has_value());
    EXPECT_EQ(ds.views[0].name, "./train/r_0");
    EXPECT_EQ(ds.views[0].camera_to_world.eye(), (Vec3d{0, 0, 4}));
    const auto& rgb = ds.views[0].rgb;
    // Pixel (0, 0) is transparent: the white background.
    EXPECT_FLOAT_EQ(rgb[0], 1.0f);
    EXPECT_FLOAT_EQ(rgb[2], 1.0f);
    // Pixel (1, 0), alpha 128/255: 60/255 · a + 1 · (1 − a).
    const float a = 128.0f / 255.0f;
    EXPECT_NEAR(rgb[3], 60.0f / 255.0f * a + (1.0f - a), 1e-6f);
    // Pixel (2, 1) is opaque.
    EXPECT_FLOAT_EQ(rgb[3 * (4 + 2)], 120.0f / 255.0f);
    EXPECT_FLOAT_EQ(rgb[3 * (4 + 2) + 1], 80.0f / 255.0f);
}

TEST(NerfDataset, ReadsInstantNgpIntrinsicsAndAabb) {
    const TempDir dir;
    write_rgba_png(dir / "a.png");
    write_bytes(dir / "transforms.json",
                R"({"fl_x": 3.5, "fl_y": 4.5, "cx": 1.75, "cy": 1.25, "w": 4, "h": 3,
                    "aabb": [[-1, -2, -3], [1, 2, 3]],
                    "frames": [{"file_path": "a.png", "transform_matrix": )" +
                    std::string(IDENTITY) + "}]}");
    const nerf::Dataset ds = read_nerf_dataset(dir / "transforms.json");
    EXPECT_DOUBLE_EQ(ds.intrinsics.fx, 3.5);
    EXPECT_DOUBLE_EQ(ds.intrinsics.fy, 4.5);
    EXPECT_DOUBLE_EQ(ds.intrinsics.cx, 1.75);
    EXPECT_DOUBLE_EQ(ds.intrinsics.cy, 1.25);
    ASSERT_TRUE(ds.box.has_value());
    EXPECT_EQ(ds.box->lo, (Vec3d{-1, -2, -3}));
    EXPECT_EQ(ds.box->hi, (Vec3d{1, 2, 3}));
}

TEST(NerfDataset, WrittenCamerasGiveTheSameRays) {
    // pliant dataset's round trip: render::Camera → pose + intrinsics → JSON → reader → rays.
    const TempDir dir;
    const AABBd box{{-1, -2, 0}, {3, 1, 2}};
    const render::Camera cam = render::frame_box(box, 37.0, -25.0, 6, 4, {});
    write_rgba_png(dir / "v.png", 6, 4);
    const std::string name = "v";
    const nerf::Pose pose = nerf::pose_from_camera(cam);
    write_transforms(dir / "t.json", nerf::intrinsics_from_camera(cam), {&name, 1}, {&pose, 1},
                     box);
    const nerf::Dataset ds = read_nerf_dataset(dir / "t.json");
    ASSERT_TRUE(ds.box.has_value());
    EXPECT_EQ(ds.box->lo, box.lo);
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 6; ++i) {
            const render::Ray a = cam.pixel_ray(i, j);
            const render::Ray b =
                nerf::view_ray(ds.intrinsics, ds.views[0].camera_to_world, i + 0.5, j + 0.5);
            EXPECT_NEAR(norm(a.origin - b.origin), 0.0, 1e-12);
            EXPECT_NEAR(norm(a.direction - b.direction), 0.0, 1e-12) << i << ", " << j;
        }
    }
    // And back to a render::Camera for the ray caster.
    const render::Camera back = nerf::camera_from_view(ds.intrinsics, ds.views[0].camera_to_world);
    EXPECT_NEAR(norm(back.pixel_ray(5, 3).direction - cam.pixel_ray(5, 3).direction), 0.0, 1e-12);
}

TEST(NerfDataset, BrokenDatasetsGiveClearErrors) {
    const TempDir dir;
    std::filesystem::create_directories(dir / "train");
    write_rgba_png(dir / "train/r_0.png");
    write_rgba_png(dir / "small.png", 2, 2);
    const auto json = dir / "t.json";
    const auto read = [&] {
        return read_nerf_dataset(json);
    };

    io::test::expect_io_error(read, {"t.json", "cannot open"});
    io::test::expect_io_error([&] { read_nerf_dataset(dir.path()); },
                              {"expected a regular file, got a directory"});
    write_bytes(json, "{ not json");
    io::test::expect_io_error(read, {"t.json", "not valid JSON"});
    write_bytes(json, R"({"camera_angle_x": 0.7, "frames": []})");
    io::test::expect_io_error(read, {"frames", "non-empty"});
    write_bytes(json, blender_json(R"(, {"file_path": "./train/missing", "transform_matrix": )" +
                                   std::string(IDENTITY) + "}"));
    io::test::expect_io_error(read, {"frames[1]", "missing", "no such file"});
    write_bytes(json, blender_json(R"(, {"file_path": "small.png", "transform_matrix": )" +
                                   std::string(IDENTITY) + "}"));
    io::test::expect_io_error(read, {"frames[1]", "2 x 2", "expected 4 x 3"});
    write_bytes(json, R"({"frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
                          std::string(IDENTITY) + "}]}");
    io::test::expect_io_error(read, {"camera_angle_x", "fl_x"});
    write_bytes(json, blender_json("", "[[1,0,0],[0,1,0],[0,0,1]]"));
    io::test::expect_io_error(read, {"frames[0].transform_matrix", "row 0"});
    write_bytes(json, blender_json("", R"([[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]])"));
    io::test::expect_io_error(read, {"last row"});
    write_bytes(json, blender_json("", R"([[1,0,0,0],[0,"x",0,0],[0,0,1,0],[0,0,0,1]])"));
    io::test::expect_io_error(read, {"entry [1][1]"});
    write_bytes(
        json,
        R"({"camera_angle_x": 0.7, "aabb": [1, 2], "frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
            std::string(IDENTITY) + "}]}");
    io::test::expect_io_error(read, {"aabb"});
    // A singular rotation (two equal columns): InvalidInput naming the view.
    write_bytes(json, blender_json("", R"([[1,1,0,0],[0,0,0,0],[0,0,1,0],[0,0,0,1]])"));
    try {
        read();
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("./train/r_0"), std::string::npos) << e.what();
    }
    write_bytes(
        json,
        R"({"camera_angle_x": 0.7, "scale": 0.33, "frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
            std::string(IDENTITY) + "}]}");
    EXPECT_THROW(read(), Unsupported);
}

TEST(NerfDataset, AbsurdSizesAreRefusedBeforeDecoding) {
    const TempDir dir;
    std::filesystem::create_directories(dir / "train");
    write_rgba_png(dir / "train/r_0.png");
    const auto json = dir / "t.json";
    const auto with_size = [&](const std::string& w, const std::string& h) {
        write_bytes(json, R"({"camera_angle_x": 0.7, "w": )" + w + R"(, "h": )" + h +
                              R"(, "frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
                              std::string(IDENTITY) + "}]}");
    };
    const auto read = [&] {
        return read_nerf_dataset(json);
    };
    // Sizes that are not whole pixel counts in [1, 65536] (1e30 would overflow an int).
    for (const auto& [w, h] : {std::pair{"1e30", "3"}, std::pair{"-4", "3"}, std::pair{"4", "2.5"},
                               std::pair{"4", "0"}, std::pair{"70000", "3"}}) {
        with_size(w, h);
        io::test::expect_io_error(read, {"t.json", "whole number of pixels"});
    }
    // A declared size the image does not have: refused from the image's header.
    with_size("8", "3");
    io::test::expect_io_error(read, {"frames[0]", "4 x 3", "expected 8 x 3"});
    // More decoded pixels than the memory limit: refused before any image is decoded.
    with_size("4", "3");
    ReadNerfDatasetOptions options;
    options.max_bytes = 12 * 4 * 3 - 1;
    try {
        read_nerf_dataset(json, options);
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("memory limit"), std::string::npos) << e.what();
    }
    options.max_bytes = 12 * 4 * 3;
    EXPECT_EQ(read_nerf_dataset(json, options).views.size(), 1u);
}

TEST(NerfDataset, DerivesASceneBoxFromTheCameras) {
    // Four cameras on a circle of radius 4 around (1, 2, 3), looking at it.
    nerf::Dataset ds;
    ds.intrinsics = {100, 100, 100.0, 100.0, 50.0, 50.0, {}};
    const Vec3d c{1, 2, 3};
    for (int i = 0; i < 4; ++i) {
        const double a = i * std::numbers::pi / 2;
        const render::Camera cam = render::Camera::perspective(
            c + 4.0 * Vec3d{std::cos(a), std::sin(a), 0.3}, c, {0, 0, 1}, 53.13, 100, 100);
        nerf::View v;
        v.camera_to_world = nerf::pose_from_camera(cam);
        ds.views.push_back(v);
    }
    const AABBd box = nerf::scene_box(ds);
    EXPECT_NEAR(norm(box.center() - c), 0.0, 1e-9);
    EXPECT_GT(box.extent().x, 0.5);
    EXPECT_LT(box.extent().x, 4.0);
}

}  // namespace
}  // namespace pliant::pipeline
