// pliant render on an oblique volume (a NIfTI tilted by 5°, as a tilted scan): rendered as it
// lies in world space by default, without resampling and without the resample info line, the
// image the library gives for the file read with its direction; `--axis-aligned` resamples first,
// says so, and renders nearly the same picture. pliant dataset renders it as it lies too, its
// `aabb` the world box.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <numbers>
#include <string>

#include "pliant/io/png.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "run_cli.hpp"
#include "support/images.hpp"

namespace pliant::test {
namespace {

std::filesystem::path write_tilted(const ScratchDir& scratch) {
    volume::Volume v = volume::shepp_logan_3d({32, 28, 24});
    v.set_spacing({1.0, 1.0, 1.5});
    const double t = 5.0 * std::numbers::pi / 180.0;
    v.set_direction(
        {Vec3d{std::cos(t), 0, -std::sin(t)}, Vec3d{0, 1, 0}, Vec3d{std::sin(t), 0, std::cos(t)}});
    const std::filesystem::path path = scratch / "tilted.nii.gz";
    io::write_volume(path, v);
    return path;
}

TEST(RenderObliqueCli, TiltedNiftiRendersInWorldSpaceWithoutResampling) {
    const ScratchDir scratch;
    const auto path = write_tilted(scratch);
    const std::string common = " --tf mri-brain --size 64x56 --camera 30,20,90";
    const CliResult native =
        run_cli("render " + quoted(path) + common + " -o " + quoted(scratch / "n.png"), scratch);
    ASSERT_EQ(native.exit_code, 0) << native.err;
    EXPECT_EQ(native.err.find("resampled"), std::string::npos) << native.err;
    EXPECT_EQ(native.err.find("oblique"), std::string::npos) << native.err;
    const render::Image image = io::read_png(scratch / "n.png");

    // The library, on the file read with its direction, framed on its world box.
    const volume::Volume v = io::read_volume(path, {.orientation = io::Orientation::keep});
    ASSERT_FALSE(v.is_axis_aligned());
    const volume::TransferFunction tf = volume::preset("mri-brain", v);
    render::Image expected;
    render::RayCaster(v, &tf, {})
        .render(render::orbit_camera(v.world_bounds(), 30.0, 20.0, 90.0, 64, 56), expected);
    EXPECT_EQ(image, expected);

    const CliResult resampled = run_cli(
        "render " + quoted(path) + common + " --axis-aligned -o " + quoted(scratch / "r.png"),
        scratch);
    ASSERT_EQ(resampled.exit_code, 0) << resampled.err;
    EXPECT_NE(resampled.err.find("oblique"), std::string::npos) << resampled.err;
    EXPECT_NE(resampled.err.find("resampled"), std::string::npos) << resampled.err;
    // The resampled grid covers the tilted box about the same centre: the same camera sees
    // nearly the same picture (trilinear blur, corners of air).
    const double p = psnr(image, io::read_png(scratch / "r.png"));
    EXPECT_GE(p, 30.0);
    std::printf("native vs --axis-aligned: %.1f dB\n", p);
}

TEST(RenderObliqueCli, ViewAxisFramesTheWorldBox) {
    const ScratchDir scratch;
    const auto path = write_tilted(scratch);
    const CliResult r =
        run_cli("render " + quoted(path) + " --view -y -o " + quoted(scratch / "v.png"), scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const render::Image image = io::read_png(scratch / "v.png");
    // Longer side 512, the other from the world box seen along y (x across, z up).
    const volume::Volume v = io::read_volume(path, {.orientation = io::Orientation::keep});
    const Vec3d e = v.world_bounds().extent();
    ASSERT_GT(e.z, e.x);  // 24 × 1.5 along k, turned 5° from z
    EXPECT_EQ(image.height, 512);
    EXPECT_EQ(image.width, static_cast<int>(std::lround(512.0 * e.x / e.z)));
    EXPECT_NE(image, render::Image(image.width, image.height));
}

TEST(RenderObliqueCli, AxisAlignedFlagLeavesAnAxisAlignedVolumeAlone) {
    const ScratchDir scratch;
    const auto path = scratch / "straight.nrrd";
    io::write_volume(path, volume::shepp_logan_3d({24, 24, 24}));
    const CliResult a = run_cli(
        "render " + quoted(path) + " --size 40x40 -o " + quoted(scratch / "a.png"), scratch);
    const CliResult b = run_cli(
        "render " + quoted(path) + " --size 40x40 --axis-aligned -o " + quoted(scratch / "b.png"),
        scratch);
    ASSERT_EQ(a.exit_code, 0) << a.err;
    ASSERT_EQ(b.exit_code, 0) << b.err;
    EXPECT_EQ(b.err.find("resampled"), std::string::npos) << b.err;
    EXPECT_EQ(io::read_png(scratch / "a.png"), io::read_png(scratch / "b.png"));
}

TEST(RenderObliqueCli, DatasetRendersTheTiltedVolumeAsItLies) {
    const ScratchDir scratch;
    const auto path = write_tilted(scratch);
    const CliResult r = run_cli("dataset " + quoted(path) +
                                    " --views 3 --test-every 3 --size 24x24 --tf mri-brain -o " +
                                    quoted(scratch / "ds"),
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("resampled"), std::string::npos) << r.err;
    std::ifstream in(scratch / "ds" / "transforms_train.json");
    const auto j = nlohmann::json::parse(in);
    const volume::Volume v = io::read_volume(path, {.orientation = io::Orientation::keep});
    const AABBd box = v.world_bounds();
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(j.at("aabb")[0][a].get<double>(), box.lo[a], 1e-9);
        EXPECT_NEAR(j.at("aabb")[1][a].get<double>(), box.hi[a], 1e-9);
    }
}

}  // namespace
}  // namespace pliant::test
