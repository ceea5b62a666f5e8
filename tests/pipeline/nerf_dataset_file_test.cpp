// transforms.json reading and writing: the NeRF-synthetic layout (camera_angle_x, file paths
// without extension, RGBA over a background), instant-ngp intrinsics, the round trip of
// `pliant dataset`'s cameras (same rays), and broken datasets.
#include "pliant/pipeline/nerf_dataset_file.hpp"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/colmap_model.hpp"
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
    write_bytes(json, R"({"camera_angle_x": 1e999, "frames": []})");
    io::test::expect_io_error(read, {"t.json", "not valid JSON", "number overflow"});
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

// The warnings logged while f runs.
template <typename F>
std::vector<std::string> warnings_of(F&& f) {
    std::vector<std::string> out;
    const LogSink previous = set_log_sink([&](LogLevel level, std::string_view message) {
        if (level == LogLevel::warning) {
            out.emplace_back(message);
        }
    });
    try {
        f();
    } catch (...) {
        set_log_sink(previous);
        throw;
    }
    set_log_sink(previous);
    return out;
}

bool mentions(const std::vector<std::string>& lines, std::string_view text) {
    return std::any_of(lines.begin(), lines.end(),
                       [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

std::string frame(const std::string& file, const std::string& extra = "") {
    return R"({"file_path": ")" + file + R"(", "transform_matrix": )" + IDENTITY + extra + "}";
}

TEST(NerfDataset, NerfstudioPerFrameIntrinsics) {
    const TempDir dir;
    write_rgba_png(dir / "a.png");
    write_rgba_png(dir / "b.png");
    // No file-level focal length: nerfstudio's per-frame layout.
    write_bytes(
        dir / "t.json",
        R"({"camera_model": "OPENCV", "frames": [)" +
            frame("a.png", R"(, "fl_x": 3.5, "fl_y": 3.6, "cx": 2.1, "cy": 1.4, "k1": 0.01)") +
            ", " +
            frame("b.png", R"(, "fl_x": 3.7, "fl_y": 3.6, "cx": 2.0, "cy": 1.5, "k1": 0.02)") +
            "]}");
    const nerf::Dataset ds = read_nerf_dataset(dir / "t.json");
    EXPECT_EQ(ds.intrinsics.fx, 3.5);
    EXPECT_EQ(ds.intrinsics.cx, 2.1);
    EXPECT_EQ(ds.intrinsics.lens.model, nerf::LensModel::opencv);
    EXPECT_EQ(ds.intrinsics.lens.k1, 0.01);
    EXPECT_FALSE(ds.views[0].intrinsics.has_value());
    ASSERT_TRUE(ds.views[1].intrinsics.has_value());
    EXPECT_EQ(ds.views[1].intrinsics->fx, 3.7);
    EXPECT_EQ(ds.views[1].intrinsics->cy, 1.5);
    EXPECT_EQ(ds.views[1].intrinsics->lens.k1, 0.02);
    // A frame of another size is refused.
    write_bytes(dir / "t.json", R"({"fl_x": 3, "w": 4, "h": 3, "frames": [)" + frame("a.png") +
                                    ", " + frame("b.png", R"(, "w": 8)") + "]}");
    EXPECT_THROW(read_nerf_dataset(dir / "t.json"), Unsupported);
}

TEST(NerfDataset, LensModelsAndTheirCoefficients) {
    const TempDir dir;
    write_rgba_png(dir / "a.png");
    const auto read_with = [&](const std::string& keys) {
        write_bytes(dir / "t.json", R"({"fl_x": 3, "w": 4, "h": 3, )" + keys + R"(, "frames": [)" +
                                        frame("a.png") + "]}");
        return read_nerf_dataset(dir / "t.json");
    };
    nerf::Dataset ds = read_with(R"("camera_model": "OPENCV_FISHEYE", "k1": 0.1, "k4": -0.01)");
    EXPECT_EQ(ds.intrinsics.lens.model, nerf::LensModel::opencv_fisheye);
    EXPECT_EQ(ds.intrinsics.lens.k4, -0.01);
    // Coefficients without a model: OPENCV (nerfstudio's and instant-ngp's reading).
    ds = read_with(R"("k1": -0.05, "p2": 0.001)");
    EXPECT_EQ(ds.intrinsics.lens.model, nerf::LensModel::opencv);
    EXPECT_EQ(ds.intrinsics.lens.p2, 0.001);
    ds = read_with(R"("is_fisheye": true, "k1": 0.02)");
    EXPECT_EQ(ds.intrinsics.lens.model, nerf::LensModel::opencv_fisheye);
    // A coefficient the model lacks, an unknown model, a non-number.
    try {
        read_with(R"("camera_model": "PINHOLE", "k1": 0.1)");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("k1"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("PINHOLE"), std::string::npos) << e.what();
    }
    io::test::expect_io_error([&] { read_with(R"("camera_model": "FANCY")"); },
                              {"camera_model", "FANCY", "OPENCV_FISHEYE"});
    io::test::expect_io_error([&] { read_with(R"("k1": "big")"); }, {"k1", "number"});
    // A lens that folds back inside the image.
    EXPECT_THROW(read_with(R"("camera_model": "SIMPLE_RADIAL", "k1": -3)"), InvalidInput);
}

TEST(NerfDataset, EveryKeyIsUnderstoodOrNamed) {
    const TempDir dir;
    write_rgba_png(dir / "a.png");
    const auto read_with = [&](const std::string& keys, const std::string& frame_keys = "") {
        write_bytes(dir / "t.json", R"({"fl_x": 3, )" + keys + R"(, "frames": [)" +
                                        frame("a.png", frame_keys) + "]}");
        return warnings_of([&] { read_nerf_dataset(dir / "t.json"); });
    };
    std::vector<std::string> w = read_with(R"("foo": 1)", R"(, "bar": 2, "colmap_im_id": 3)");
    EXPECT_TRUE(mentions(w, "`foo`"));
    EXPECT_TRUE(mentions(w, "frames[0]: key `bar`"));
    EXPECT_FALSE(mentions(w, "colmap_im_id"));
    // nerfstudio's applied_transform: understood; a broken one is an error.
    w = read_with(R"("applied_transform": [[0,1,0,0],[1,0,0,0],[0,0,-1,0]])");
    EXPECT_TRUE(w.empty());
    io::test::expect_io_error([&] { read_with(R"("applied_transform": [1, 2])"); },
                              {"applied_transform", "3 x 4"});
    EXPECT_TRUE(mentions(read_with(R"("orientation_override": "up")"), "orientation_override"));
    EXPECT_TRUE(read_with(R"("orientation_override": "none")").empty());
    EXPECT_TRUE(mentions(read_with(R"("aabb_scale": 16)"), "aabb_scale"));
    EXPECT_TRUE(read_with(R"("aabb_scale": 1)").empty());
    io::test::expect_io_error([&] { read_with(R"("aabb_scale": 3)"); }, {"power of two"});
}

TEST(NerfDataset, MasksFromFilesAndAlpha) {
    const TempDir dir;
    write_rgba_png(dir / "a.png");
    // Mask: pixel (2, 1) and (3, 2) ignored.
    std::vector<unsigned char> m(12, 255);
    m[1 * 4 + 2] = 0;
    m[2 * 4 + 3] = 0;
    ASSERT_NE(stbi_write_png((dir / "m.png").string().c_str(), 4, 3, 1, m.data(), 4), 0);
    write_bytes(dir / "t.json",
                R"({"fl_x": 3, "frames": [)" + frame("a.png", R"(, "mask_path": "m.png")") + "]}");
    nerf::Dataset ds = read_nerf_dataset(dir / "t.json");
    ASSERT_EQ(ds.views[0].mask.size(), 12u);
    EXPECT_EQ(ds.views[0].mask[6], 0);
    EXPECT_EQ(ds.views[0].mask[11], 0);
    EXPECT_EQ(ds.views[0].mask[0], 1);
    // With alpha_mask, the alpha-0 pixel (0, 0) too.
    ReadNerfDatasetOptions o;
    o.alpha_mask = true;
    ds = read_nerf_dataset(dir / "t.json", o);
    EXPECT_EQ(ds.views[0].mask[0], 0);
    EXPECT_EQ(ds.views[0].mask[1], 1);  // alpha 128 counts
    EXPECT_EQ(ds.views[0].mask[6], 0);
    write_bytes(dir / "t.json", R"({"fl_x": 3, "frames": [)" +
                                    frame("a.png", R"(, "mask_path": "nope.png")") + "]}");
    io::test::expect_io_error([&] { read_nerf_dataset(dir / "t.json"); },
                              {"mask_path", "no such file"});
}

TEST(NerfDataset, DownscaleBoxFiltersAndKeepsThePixelCentres) {
    const TempDir dir;
    write_rgba_png(dir / "a.png", 5, 4);  // 5 x 4 → 2 x 2 at N = 2 (the last column dropped)
    write_bytes(dir / "t.json", R"({"fl_x": 4.5, "fl_y": 5, "cx": 2.25, "cy": 1.75, "k1": 0.01,
                                    "frames": [)" +
                                    frame("a.png") + "]}");
    const nerf::Dataset full = read_nerf_dataset(dir / "t.json");
    ReadNerfDatasetOptions o;
    o.downscale = 2;
    const nerf::Dataset half = read_nerf_dataset(dir / "t.json", o);
    EXPECT_EQ(half.intrinsics.width, 2);
    EXPECT_EQ(half.intrinsics.height, 2);
    EXPECT_EQ(half.intrinsics.fx, 2.25);
    EXPECT_EQ(half.intrinsics.fy, 2.5);
    EXPECT_EQ(half.intrinsics.cx, 1.125);
    EXPECT_EQ(half.intrinsics.cy, 0.875);
    EXPECT_EQ(half.intrinsics.lens.k1, 0.01);
    // Pixel (1, 1) of the small image is the mean of pixels (2..3, 2..3) of the large one.
    for (int c = 0; c < 3; ++c) {
        const auto at = [&](int x, int y) {
            return full.views[0].rgb[3 * (y * 5 + x) + c];
        };
        EXPECT_FLOAT_EQ(half.views[0].rgb[3 * 3 + c],
                        (at(2, 2) + at(3, 2) + at(2, 3) + at(3, 3)) / 4.0f);
    }
    // The small pixel's centre (i + 0.5) is the large block's centre 2 i + 1: the same ray.
    for (int i = 0; i < 2; ++i) {
        const render::Ray a =
            nerf::view_ray(half.intrinsics, half.views[0].camera_to_world, i + 0.5, i + 0.5);
        const render::Ray b = nerf::view_ray(full.intrinsics, full.views[0].camera_to_world,
                                             2.0 * i + 1.0, 2.0 * i + 1.0);
        EXPECT_NEAR(norm(a.direction - b.direction), 0.0, 1e-12);
    }
    o.downscale = 5;
    EXPECT_THROW(read_nerf_dataset(dir / "t.json", o), InvalidInput);
}

TEST(NerfDataset, ReadsJpegPhotos) {
    const TempDir dir;
    std::vector<unsigned char> px(16 * 8 * 3, 128);
    ASSERT_NE(stbi_write_jpg((dir / "p.jpg").string().c_str(), 16, 8, 3, px.data(), 95), 0);
    write_bytes(dir / "t.json", R"({"fl_x": 10, "frames": [)" + frame("p") + "]}");
    const nerf::Dataset ds = read_nerf_dataset(dir / "t.json");
    EXPECT_EQ(ds.intrinsics.width, 16);
    EXPECT_NEAR(ds.views[0].rgb[0], 128.0f / 255.0f, 2.0f / 255.0f);
}

TEST(NerfDataset, ReadsAColmapModelDirectory) {
    const TempDir dir;
    std::filesystem::create_directories(dir / "sparse" / "0");
    std::filesystem::create_directories(dir / "images");
    write_rgba_png(dir / "images" / "b.png");
    write_rgba_png(dir / "images" / "a.png");
    write_bytes(dir / "sparse/0/cameras.txt", "1 OPENCV 4 3 3.5 3.4 2.1 1.4 -0.01 0.001 0 0\n");
    write_bytes(dir / "sparse/0/images.txt",
                "1 1 0 0 0 0 0 4 1 b.png\n\n2 0.9 0.1 0.3 -0.2 1.5 -2.25 3 1 a.png\n\n");
    const nerf::Dataset ds = read_nerf_dataset(dir / "sparse" / "0");
    ASSERT_EQ(ds.views.size(), 2u);
    EXPECT_EQ(ds.views[0].name, "a.png");  // sorted by name
    EXPECT_EQ(ds.intrinsics.lens.model, nerf::LensModel::opencv);
    EXPECT_EQ(ds.intrinsics.fy, 3.4);
    const nerf::ColmapTransforms t =
        nerf::transforms_from_colmap(io::read_colmap_model(dir / "sparse" / "0"));
    EXPECT_EQ(ds.views[1].camera_to_world.m, t.frames[1].camera_to_world.m);
    EXPECT_EQ(ds.views[0].rgb.size(), 36u);
    // The photos elsewhere: images_dir, or a clear error naming --images.
    std::filesystem::rename(dir / "images", dir / "photos");
    io::test::expect_io_error([&] { read_nerf_dataset(dir / "sparse" / "0"); }, {"--images"});
    ReadNerfDatasetOptions o;
    o.images_dir = dir / "photos";
    EXPECT_EQ(read_nerf_dataset(dir / "sparse" / "0", o).views.size(), 2u);
    // A directory that is neither a model nor holds transforms.json.
    io::test::expect_io_error([&] { read_nerf_dataset(dir / "photos"); },
                              {"neither transforms.json nor a COLMAP model"});
}

}  // namespace
}  // namespace pliant::pipeline
