// pliant view end to end: help, usage errors (exit 2), bad input and no display (exit 1, before
// any window), and under xvfb-run (Mesa's software OpenGL; skipped when xvfb-run is not
// installed) headless screenshots compared with the offline renderers at the same camera:
//   cloth: the viewer's OpenGL drawing of a simulated frame vs render::MeshRasterizer on the
//          frame `pliant cloth` wrote (the same simulation), PSNR ≥ 25 dB;
//   volume: the viewer's image vs `pliant render` (the same ray caster), with and without a
//          clipping plane, PSNR ≥ 25 dB (identical in practice);
// the overlay never appears in screenshots, and a deforming volume runs.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "pliant/io/mesh_io.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/pipeline/cloth_look.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/mesh_rasterizer.hpp"
#include "pliant/volume/generate.hpp"
#include "run_cli.hpp"

namespace pliant::test {
namespace {

// scenes/sheet2244.json: 33 × 34 quads (2,244 triangles, the seed paper's smallest size)
// dropped onto a sphere above a floor, copied into the scratch directory.
std::filesystem::path write_scene(const ScratchDir& scratch) {
    const std::filesystem::path path = scratch / "grid.json";
    std::filesystem::copy_file(
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "sheet2244.json", path);
    return path;
}

std::filesystem::path write_phantom(const ScratchDir& scratch) {
    const std::filesystem::path path = scratch / "phantom.nrrd";
    io::write_volume(path, volume::shepp_logan_3d({48, 48, 48}));
    return path;
}

TEST(ViewCli, HelpListsTheViewsAndOptions) {
    const ScratchDir scratch;
    const CliResult r = run_cli("view --help", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("cloth"), std::string::npos);
    EXPECT_NE(r.out.find("volume"), std::string::npos);
    const CliResult c = run_cli("view cloth --help", scratch);
    ASSERT_EQ(c.exit_code, 0);
    for (const char* option : {"--screenshot", "--frames", "--camera", "--size", "--no-ui",
                               "--substeps-per-frame", "--check-every"}) {
        EXPECT_NE(c.out.find(option), std::string::npos) << option;
    }
    const CliResult v = run_cli("view volume --help", scratch);
    ASSERT_EQ(v.exit_code, 0);
    for (const char* option : {"--deform", "--tf", "--opacity-scale", "--threshold", "--clip",
                               "--driver", "--stiffness", "--preview-divisor"}) {
        EXPECT_NE(v.out.find(option), std::string::npos) << option;
    }
    // Each view's own defaults, as run when the options are not given.
    EXPECT_NE(c.out.find("=[-60,25,0]"), std::string::npos) << c.out;
    EXPECT_NE(c.out.find("=1280x720"), std::string::npos) << c.out;
    EXPECT_NE(v.out.find("=[30,20,0]"), std::string::npos) << v.out;
    EXPECT_NE(v.out.find("=512x512"), std::string::npos) << v.out;
}

TEST(ViewCli, UsageErrorsExitTwo) {
    const ScratchDir scratch;
    const std::string scene = quoted(write_scene(scratch));
    const std::string volume = quoted(write_phantom(scratch));
    for (const std::string& args :
         {std::string("view"), std::string("view cloth"),
          "view cloth " + scene + " --screenshot a.png",
          "view cloth " + scene + " --frames 2 --screenshot a.jpg",
          "view cloth " + scene + " --size 10", "view cloth " + scene + " --msaa 99",
          "view volume " + volume + " --driver twist",
          "view volume " + volume + " --deform --driver spin",
          "view volume " + volume + " --clip 1,2,3", "view volume " + volume + " --threshold 300",
          "view volume " + volume + " --opacity-scale 0",
          "view volume " + volume + " --thin-levels 1",
          "view volume " + volume + " --deform --thin-levels 3"}) {
        const CliResult r = run_cli(args + " 2>&1", scratch, "env -u DISPLAY");
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out << r.err;
    }
}

// Input is read and checked before a window opens: no display is needed to report it.
TEST(ViewCli, BadInputExitsOneBeforeAnyWindow) {
    const ScratchDir scratch;
    CliResult r = run_cli("view cloth " + quoted(scratch / "missing.json") + " --frames 1", scratch,
                          "env -u DISPLAY");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
    const std::filesystem::path broken = scratch / "broken.json";
    std::ofstream(broken) << R"({"cloth": {"grid": {"quads": [0, 4]}}})";
    r = run_cli("view cloth " + quoted(broken) + " --frames 1", scratch, "env -u DISPLAY");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    const std::filesystem::path not_a_volume = scratch / "volume.nrrd";
    std::ofstream(not_a_volume) << "NRRD0004\ntype: nonsense\n";
    r = run_cli("view volume " + quoted(not_a_volume) + " --frames 1", scratch, "env -u DISPLAY");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    r = run_cli("view volume " + quoted(write_phantom(scratch)) + " --tf nonexistent.json", scratch,
                "env -u DISPLAY");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("nonexistent.json"), std::string::npos) << r.err;
}

// No display: a clear error naming the cause, exit 1, no crash (or, in a build without the
// viewer, the message that says so).
TEST(ViewCli, NoDisplayIsAClearError) {
    const ScratchDir scratch;
    const std::string scene = quoted(write_scene(scratch));
    const std::string volume = quoted(write_phantom(scratch));
    for (const std::string& args : {"view cloth " + scene + " --frames 1",
                                    "view volume " + volume + " --frames 1 --deform"}) {
        const CliResult r = run_cli(args, scratch, "env -u DISPLAY -u WAYLAND_DISPLAY");
        EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("pliant: error: ", 0), 0u) << r.err;
#if PLIANT_HAS_VIEWER
        EXPECT_NE(r.err.find("DISPLAY"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
#else
        EXPECT_NE(r.err.find("built without the viewer"), std::string::npos) << r.err;
#endif
    }
}

#if PLIANT_HAS_VIEWER

bool has_xvfb() {
    return std::system("command -v xvfb-run >/dev/null 2>&1") == 0;
}

// The viewer under a virtual X server (a free server number per run, so tests run in parallel).
CliResult run_headless(const std::string& args, const ScratchDir& scratch) {
    return run_cli(args, scratch, "xvfb-run -a");
}

std::vector<float> to_floats(const render::Image& image) {
    std::vector<float> out(image.pixels.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i] = static_cast<float>(image.pixels[i]) / 255.0f;
    }
    return out;
}

double psnr(const render::Image& a, const render::Image& b) {
    return nerf::psnr(to_floats(a), to_floats(b));
}

Vec3d vec3(const nlohmann::json& j) {
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

render::Camera camera_from_json(const nlohmann::json& c) {
    return render::Camera::perspective(vec3(c["eye"]), vec3(c["target"]), vec3(c["up"]),
                                       c["fov_y_degrees"].get<double>(), c["width"].get<int>(),
                                       c["height"].get<int>());
}

// The viewer's frame 3 (40 substeps per frame, the scene's: frames of `pliant cloth`) against
// the mesh rasterizer on the frame `pliant cloth` wrote, with the viewer's camera and the
// preview's look.
TEST(ViewCli, ClothScreenshotMatchesTheMeshRasterizer) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    const std::filesystem::path scene = write_scene(scratch);
    const CliResult sim = run_cli(
        "cloth " + quoted(scene) + " --frames 3 --no-preview --out " + quoted(scratch / "run"),
        scratch);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    // The offline image: frame 3 as written, the scene's obstacles as the preview draws them.
    const geometry::TriangleMeshD frame =
        io::read_mesh(scratch / "run" / "frames" / "frame_0003.obj");
    const cloth::ClothScene parsed = pipeline::read_cloth_scene(scene);
    const pipeline::ClothSetup setup = pipeline::load_cloth_setup(parsed, "grid");
    std::vector<render::RenderMesh> meshes;
    for (const pipeline::ObstacleShape& shape : setup.shapes) {
        meshes.push_back(
            {shape.rest.positions, shape.rest.triangles, pipeline::OBSTACLE_COLOR, shape.smooth});
    }
    meshes.push_back({frame.positions, frame.triangles, pipeline::CLOTH_COLOR, true});

    // Automatic multisampling (none on Mesa's software renderer), and 4 samples.
    for (const std::string msaa : {"", " --msaa 4"}) {
        const std::filesystem::path shot = scratch / "cloth.png";
        const CliResult r = run_headless("--json view cloth " + quoted(scene) +
                                             " --frames 3 --substeps-per-frame 40 --sync --no-ui "
                                             "--size 480x360 --screenshot " +
                                             quoted(shot) + msaa,
                                         scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_EQ(j["triangles"].get<int>(), 2244);
        EXPECT_EQ(j["frames"].get<int>(), 3);
        EXPECT_EQ(j["simulated_frames"].get<int>(), 3);
        EXPECT_EQ(j["max_intersecting_pairs"].get<int>(), 0);
        EXPECT_GT(j["fps"].get<double>(), 0.0);
        if (!msaa.empty()) {
            EXPECT_EQ(j["msaa_samples"].get<int>(), 4);
        } else if (j["gl_renderer"].get<std::string>().find("llvmpipe") != std::string::npos) {
            EXPECT_EQ(j["msaa_samples"].get<int>(), 0);
        }
        const render::Image viewer = io::read_png(shot);
        ASSERT_EQ(viewer.width, 480);
        ASSERT_EQ(viewer.height, 360);
        const render::Image offline = render::render_meshes(camera_from_json(j["camera"]), meshes,
                                                            pipeline::cloth_raster_options());
        const double db = psnr(viewer, offline);
        std::printf("cloth screenshot%s vs mesh rasterizer: %.2f dB\n", msaa.c_str(), db);
        EXPECT_GE(db, 25.0);
        // The cloth is there: many pixels of its red (front) or tinted (back) colour.
        int cloth_pixels = 0;
        for (std::size_t i = 0; i < viewer.pixels.size(); i += 3) {
            cloth_pixels += viewer.pixels[i] > viewer.pixels[i + 2] + 60 ? 1 : 0;
        }
        EXPECT_GT(cloth_pixels, 2000);
    }
}

// Without --sync the simulation runs beside the drawing: frames are drawn whether or not a new
// simulated frame is ready; paused, nothing is simulated.
TEST(ViewCli, ClothSimulatesInTheBackground) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    const std::string scene = quoted(write_scene(scratch));
    CliResult r =
        run_headless("--json view cloth " + scene + " --frames 20 --size 320x240", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto j = nlohmann::json::parse(r.out);
    EXPECT_FALSE(j["sync"].get<bool>());
    EXPECT_EQ(j["frames"].get<int>(), 20);
    EXPECT_GE(j["simulated_frames"].get<int>(), 1);
    EXPECT_LE(j["simulated_frames"].get<int>(), 20);
    EXPECT_GT(j["simulated_frames_per_second"].get<double>(), 0.0);
    r = run_headless("--json view cloth " + scene + " --frames 5 --size 320x240 --paused", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["simulated_frames"].get<int>(), 0);
    EXPECT_EQ(j["intersecting_pairs_frame"].get<int>(), 0);  // the start was counted
}

// The viewer reports a start as `pliant cloth` does: two sheets crossing like an X on stderr,
// then untangled (the counts in --json).
TEST(ViewCli, ClothStartIsReportedAsTheCommandReportsIt) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    std::ofstream(scratch / "x.json") << R"({"cloth": {"grid": {"size": [1, 1], "quads": [8, 8]},
        "instances": [{}, {"rotate_degrees": [20, 0, 0], "translate": [0.0123, 0.0171, 0]}]},
        "gravity": [0, 0, 0], "frames": 1})";
    const CliResult r = run_headless(
        "--json view cloth " + quoted(scratch / "x.json") + " --frames 1 --size 160x120", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const auto pairs = j["initial_intersecting_pairs"].get<std::int64_t>();
    EXPECT_GT(pairs, 0);
    EXPECT_NE(r.err.find(fmt::format("the cloth intersects itself at the start ({} pairs", pairs)),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("untangled in "), std::string::npos) << r.err;
}

TEST(ViewCli, VolumeScreenshotMatchesPliantRender) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    const std::string volume = quoted(write_phantom(scratch));
    for (const std::string& extra :
         {std::string(), std::string(" --clip 0.1,0,0,-1,0.3,0.2 --shading")}) {
        const std::filesystem::path reference = scratch / "reference.png";
        const CliResult offline = run_cli("render " + volume +
                                              " --tf mri-brain --camera 30,20,0 --size 160x128 "
                                              "-o " +
                                              quoted(reference) + extra,
                                          scratch);
        ASSERT_EQ(offline.exit_code, 0) << offline.err;
        const std::filesystem::path shot = scratch / "volume.png";
        const CliResult r = run_headless("--json view volume " + volume +
                                             " --tf mri-brain --camera 30,20,0 --size 160x128 "
                                             "--frames 3 --no-ui --screenshot " +
                                             quoted(shot) + extra,
                                         scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_EQ(j["full_resolution_images"].get<int>(), 1);  // an unchanging view: cast once
        const render::Image a = io::read_png(shot), b = io::read_png(reference);
        ASSERT_EQ(a.width, 160);
        ASSERT_EQ(a.height, 128);
        const double db = psnr(a, b);
        std::printf("volume screenshot vs pliant render%s: %.2f dB\n", extra.c_str(), db);
        EXPECT_GE(db, 25.0);
        EXPECT_NE(a, render::Image(160, 128));
    }
}

// The overlay is drawn after the screenshot is taken: with and without it the PNG is the same.
TEST(ViewCli, ScreenshotsNeverShowTheOverlay) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    const std::string scene = quoted(write_scene(scratch));
    const std::string volume = quoted(write_phantom(scratch));
    // Cloth with 4× multisampling asked for explicitly (resolved by the read).
    const std::string common = " --frames 2 --size 400x300 --msaa 4 --screenshot ";
    for (const std::string& view : {"view cloth --sync " + scene, "view volume " + volume}) {
        const CliResult with = run_headless(view + common + quoted(scratch / "ui.png"), scratch);
        ASSERT_EQ(with.exit_code, 0) << with.err;
        EXPECT_NE(with.out.find("2 frames"), std::string::npos) << with.out;
        const CliResult without =
            run_headless(view + common + quoted(scratch / "no_ui.png") + " --no-ui", scratch);
        ASSERT_EQ(without.exit_code, 0) << without.err;
        EXPECT_EQ(io::read_png(scratch / "ui.png"), io::read_png(scratch / "no_ui.png")) << view;
    }
}

TEST(ViewCli, DeformingVolumeRunsAndChanges) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    const std::string volume = quoted(write_phantom(scratch));
    const std::string common = " --tf mri-brain --size 128x128 --no-ui --screenshot ";
    const CliResult rest = run_headless(
        "view volume " + volume + " --frames 1 --deform" + common + quoted(scratch / "rest.png"),
        scratch);
    ASSERT_EQ(rest.exit_code, 0) << rest.err;
    const CliResult r =
        run_headless("--json view volume " + volume +
                         " --frames 12 --sync --deform --driver twist --stiffness 0.8" + common +
                         quoted(scratch / "twist.png"),
                     scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["deform"].get<bool>());
    EXPECT_EQ(j["driver"], "twist");
    EXPECT_GT(j["tets"].get<int>(), 0);
    EXPECT_EQ(j["full_resolution_images"].get<int>(), 12);  // a new image every frame
    EXPECT_NEAR(j["simulated_seconds"].get<double>(), 12.0 / 24.0, 1e-9);
    EXPECT_GT(j["mean_resample_ms"].get<double>(), 0.0);
    // Each frame's map state is installed or computed by the render (mean_prepare_ms); where the
    // render is the longer side the frame's thread computes it (mean_occupancy_ms, timing-bound:
    // tests/viewer/volume_session_test.cpp checks both placements).
    EXPECT_GT(j["mean_prepare_ms"].get<double>(), 0.0);
    EXPECT_LT(psnr(io::read_png(scratch / "rest.png"), io::read_png(scratch / "twist.png")), 40.0);
}

// An oblique volume (a phantom turned 5°, NIfTI) is shown as it lies, as `pliant render` renders
// it (no resampling, no info line); with --deform (as `pliant deform`) or --axis-aligned it is
// resampled to an axis-aligned grid first, and says so.
TEST(ViewCli, ObliqueVolumeScreenshotMatchesPliantRender) {
    if (!has_xvfb()) {
        GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb xauth)";
    }
    const ScratchDir scratch;
    volume::Volume v = volume::shepp_logan_3d({40, 36, 32});
    const double t = 5.0 * std::acos(-1.0) / 180.0;
    v.set_direction(
        {Vec3d{std::cos(t), 0, -std::sin(t)}, Vec3d{0, 1, 0}, Vec3d{std::sin(t), 0, std::cos(t)}});
    io::write_volume(scratch / "tilted.nii.gz", v);
    const std::string volume = quoted(scratch / "tilted.nii.gz");
    const std::string common = " --tf mri-brain --camera 30,20,0 --size 160x128";
    const CliResult offline =
        run_cli("render " + volume + common + " -o " + quoted(scratch / "reference.png"), scratch);
    ASSERT_EQ(offline.exit_code, 0) << offline.err;
    const CliResult r =
        run_headless("view volume " + volume + common + " --frames 2 --no-ui --screenshot " +
                         quoted(scratch / "volume.png"),
                     scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("resampled"), std::string::npos) << r.err;
    const double db =
        psnr(io::read_png(scratch / "volume.png"), io::read_png(scratch / "reference.png"));
    std::printf("oblique volume screenshot vs pliant render: %.2f dB\n", db);
    EXPECT_GE(db, 25.0);
    const CliResult deform = run_headless("view volume " + volume + common +
                                              " --frames 1 --deform --no-ui --screenshot " +
                                              quoted(scratch / "deform.png"),
                                          scratch);
    ASSERT_EQ(deform.exit_code, 0) << deform.err;
    EXPECT_NE(deform.err.find("resampled"), std::string::npos) << deform.err;
    const CliResult resampled = run_headless(
        "view volume " + volume + common + " --frames 1 --axis-aligned --no-ui --screenshot " +
            quoted(scratch / "resampled.png"),
        scratch);
    ASSERT_EQ(resampled.exit_code, 0) << resampled.err;
    EXPECT_NE(resampled.err.find("resampled"), std::string::npos) << resampled.err;
}

#endif  // PLIANT_HAS_VIEWER

}  // namespace
}  // namespace pliant::test
