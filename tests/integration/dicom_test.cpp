// DICOM and oblique volumes end to end: the bar of issue 32 — a CT series written in shuffled
// file order with RescaleIntercept −1024 reads with the right size, spacing and HU range and
// renders — plus series listing and choice, conversion, a tilted series (rendered as it lies;
// resampled on request or for deform, said on stderr) and a broken one (exit 1 naming the problem).
// The series are written by GDCM in the test (tests/io/dicom_series.hpp).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "io/dicom_series.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/volume_io.hpp"
#include "run_cli.hpp"

namespace pliant::test {
namespace {

namespace fs = std::filesystem;

TEST(DicomCli, CtSeriesInShuffledOrderInfoAndRender) {
    const ScratchDir scratch;
    write_dicom_series(scratch / "ct", DicomSeriesSpec{}, 21);

    const CliResult info = run_cli("--json volume info " + quoted(scratch / "ct"), scratch);
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    EXPECT_EQ(j.at("format"), "dicom");
    EXPECT_EQ(j.at("dims"), nlohmann::json({32, 32, 16}));
    EXPECT_EQ(j.at("type"), "i16");
    EXPECT_DOUBLE_EQ(j.at("spacing")[0].get<double>(), 0.7);
    EXPECT_DOUBLE_EQ(j.at("spacing")[1].get<double>(), 0.8);
    EXPECT_DOUBLE_EQ(j.at("spacing")[2].get<double>(), 2.5);
    EXPECT_EQ(j.at("channels")[0].at("min"), -1024.0);
    EXPECT_EQ(j.at("channels")[0].at("max"), 1500.0);
    EXPECT_EQ(j.at("axis_aligned"), true);
    ASSERT_EQ(j.at("series").size(), 1u);
    EXPECT_EQ(j.at("series")[0].at("files"), 16);
    EXPECT_EQ(j.at("series_uid"), j.at("series")[0].at("uid"));

    const fs::path png = scratch / "ct.png";
    const CliResult render =
        run_cli("render " + quoted(scratch / "ct") + " --tf ct-bone --size 64x64 -o " + quoted(png),
                scratch);
    ASSERT_EQ(render.exit_code, 0) << render.err;
    const render::Image image = io::read_png(png);
    EXPECT_EQ(image.width, 64);
    EXPECT_NE(image, render::Image(64, 64));  // the bone sphere shows
}

TEST(DicomCli, SeveralSeriesAreListedAndChosen) {
    const ScratchDir scratch;
    write_dicom_series(scratch / "two", DicomSeriesSpec{}, 22);
    DicomSeriesSpec scout;
    scout.slices = 3;
    scout.description = "scout";
    scout.series_uid = "1.2.840.99.1";
    write_dicom_series(scratch / "two", scout, 23);

    const CliResult listed = run_cli("--json volume series " + quoted(scratch / "two"), scratch);
    ASSERT_EQ(listed.exit_code, 0) << listed.err;
    const auto series = nlohmann::json::parse(listed.out).at("series");
    ASSERT_EQ(series.size(), 2u);
    EXPECT_EQ(series[0].at("files"), 16);
    EXPECT_EQ(series[1].at("uid"), "1.2.840.99.1");
    EXPECT_EQ(series[1].at("description"), "scout");
    EXPECT_EQ(series[1].at("dims"), nlohmann::json({32, 32, 3}));

    // Default: the largest, with a note on stderr naming the other.
    const CliResult largest = run_cli("--json volume info " + quoted(scratch / "two"), scratch);
    ASSERT_EQ(largest.exit_code, 0) << largest.err;
    EXPECT_EQ(nlohmann::json::parse(largest.out).at("dims")[2], 16);
    EXPECT_NE(largest.err.find("1.2.840.99.1"), std::string::npos) << largest.err;
    const CliResult chosen = run_cli(
        "--json volume info " + quoted(scratch / "two") + " --series 1.2.840.99.1", scratch);
    ASSERT_EQ(chosen.exit_code, 0) << chosen.err;
    EXPECT_EQ(nlohmann::json::parse(chosen.out).at("dims")[2], 3);
    const CliResult rendered =
        run_cli("render " + quoted(scratch / "two") + " --series 1.2.840.99.1 --size 16x16 -o " +
                    quoted(scratch / "s.png"),
                scratch);
    EXPECT_EQ(rendered.exit_code, 0) << rendered.err;
    const CliResult unknown =
        run_cli("volume info " + quoted(scratch / "two") + " --series 7.7.7", scratch);
    EXPECT_EQ(unknown.exit_code, 1);
    EXPECT_NE(unknown.err.find("pliant: error:"), std::string::npos) << unknown.err;
    EXPECT_NE(unknown.err.find("1.2.840.99.1"), std::string::npos) << unknown.err;
}

TEST(DicomCli, ConvertKeepsVoxelsAndPlacement) {
    const ScratchDir scratch;
    write_dicom_series(scratch / "ct", DicomSeriesSpec{}, 24);
    const volume::Volume source = io::read_volume(scratch / "ct");
    for (const char* name : {"ct.nii.gz", "ct.mha", "ct.nrrd"}) {
        const CliResult r = run_cli(
            "volume convert " + quoted(scratch / "ct") + " " + quoted(scratch / name), scratch);
        ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
        const volume::Volume back = io::read_volume(scratch / name);
        ASSERT_EQ(back.dims(), source.dims()) << name;
        EXPECT_EQ(std::memcmp(back.bytes().data(), source.bytes().data(), source.size_bytes()), 0)
            << name;
        EXPECT_LT(norm(back.origin() - source.origin()), 1e-4) << name;  // NIfTI-1: floats
    }
}

TEST(DicomCli, TiltedSeriesRendersAsItLiesOrResampledOnRequest) {
    const ScratchDir scratch;
    DicomSeriesSpec spec;
    const double t = 5.0 * std::numbers::pi / 180.0;
    spec.orientation = {1, 0, 0, 0, std::cos(t), std::sin(t)};
    write_dicom_series(scratch / "tilted", spec, 25);
    const CliResult info = run_cli("--json volume info " + quoted(scratch / "tilted"), scratch);
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out).at("axis_aligned"), false);
    const CliResult render =
        run_cli("render " + quoted(scratch / "tilted") + " --tf ct-bone --size 32x32 -o " +
                    quoted(scratch / "t.png"),
                scratch);
    ASSERT_EQ(render.exit_code, 0) << render.err;
    EXPECT_EQ(render.err.find("resampled"), std::string::npos) << render.err;
    const CliResult resampled =
        run_cli("render " + quoted(scratch / "tilted") +
                    " --tf ct-bone --size 32x32 --axis-aligned -o " + quoted(scratch / "r.png"),
                scratch);
    ASSERT_EQ(resampled.exit_code, 0) << resampled.err;
    EXPECT_NE(resampled.err.find("oblique"), std::string::npos) << resampled.err;
    EXPECT_NE(resampled.err.find("resampled"), std::string::npos) << resampled.err;
    const CliResult deform = run_cli("deform " + quoted(scratch / "tilted") +
                                         " --driver rotate --angle 10 --frames 2 --cells 8 -o " +
                                         quoted(scratch / "d.nrrd"),
                                     scratch);
    EXPECT_EQ(deform.exit_code, 0) << deform.err;
    EXPECT_NE(deform.err.find("resampled"), std::string::npos) << deform.err;
}

TEST(ObliqueCli, NiftiTiltedBy5DegreesIsReadNotRefused) {
    // The file that used to fail with "only axis-aligned volumes are supported".
    const ScratchDir scratch;
    volume::Volume v = volume::Volume::allocate({24, 20, 16}, volume::VoxelType::f32, {1, 1, 1.5});
    const double t = 5.0 * std::numbers::pi / 180.0;
    v.set_direction(
        {Vec3d{std::cos(t), 0, -std::sin(t)}, Vec3d{0, 1, 0}, Vec3d{std::sin(t), 0, std::cos(t)}});
    auto values = v.values<volume::VoxelType::f32>();
    for (std::size_t n = 0; n < values.size(); ++n) {
        values[n] = static_cast<float>(n % 24);  // a ramp along i
    }
    io::write_volume(scratch / "tilted.nii.gz", v);
    const CliResult info =
        run_cli("--json volume info " + quoted(scratch / "tilted.nii.gz"), scratch);
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    EXPECT_EQ(j.at("axis_aligned"), false);
    EXPECT_NEAR(j.at("direction")[0][2].get<double>(), -std::sin(t), 1e-6);
    const CliResult render = run_cli("render " + quoted(scratch / "tilted.nii.gz") +
                                         " --size 32x32 -o " + quoted(scratch / "t.png"),
                                     scratch);
    ASSERT_EQ(render.exit_code, 0) << render.err;
    EXPECT_EQ(render.err.find("resampled"), std::string::npos) << render.err;  // as it lies
    EXPECT_NE(io::read_png(scratch / "t.png"), render::Image(32, 32));
    // Converted, the direction goes along (MetaImage here).
    ASSERT_EQ(run_cli("volume convert " + quoted(scratch / "tilted.nii.gz") + " " +
                          quoted(scratch / "tilted.mha"),
                      scratch)
                  .exit_code,
              0);
    const volume::Volume back =
        io::read_volume(scratch / "tilted.mha", {.orientation = io::Orientation::keep});
    EXPECT_LT(norm(back.direction()[0] - v.direction()[0]), 1e-6);
}

TEST(DicomCli, BrokenSeriesExitsOneNamingTheProblem) {
    const ScratchDir scratch;
    const std::vector<fs::path> files = write_dicom_series(scratch / "gap", DicomSeriesSpec{}, 26);
    fs::remove(files[9]);
    const CliResult r =
        run_cli("render " + quoted(scratch / "gap") + " -o " + quoted(scratch / "x.png"), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("1 slice missing between"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(scratch / "x.png"));
    fs::create_directories(scratch / "nothing");
    const CliResult empty = run_cli("volume info " + quoted(scratch / "nothing"), scratch);
    EXPECT_EQ(empty.exit_code, 1);
    EXPECT_NE(empty.err.find("no DICOM image"), std::string::npos) << empty.err;
}

}  // namespace
}  // namespace pliant::test
