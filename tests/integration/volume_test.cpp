// `pliant volume` end to end: generate, info (against the generator's known numbers), convert
// (bitwise round trip through NRRD, NIfTI and raw + JSON), clean, the memory limit, and errors.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "integration/run_cli.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::test {
namespace {

TEST(VolumeCommand, GenerateInfoConvertRoundTrip) {
    ScratchDir scratch;
    const CliResult generated = run_cli(
        "volume generate shepp-logan " + quoted(scratch / "sl.nrrd") + " --dims 24", scratch);
    ASSERT_EQ(generated.exit_code, 0) << generated.err;
    // The file holds exactly the generator's volume.
    const volume::Volume expected = volume::shepp_logan_3d({24, 24, 24});
    const volume::Volume written = io::read_volume(scratch / "sl.nrrd");
    ASSERT_EQ(written.size_bytes(), expected.size_bytes());
    EXPECT_TRUE(
        std::equal(written.bytes().begin(), written.bytes().end(), expected.bytes().begin()));

    const CliResult info = run_cli("--json volume info " + quoted(scratch / "sl.nrrd"), scratch);
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const nlohmann::json json = nlohmann::json::parse(info.out);
    EXPECT_EQ(json.at("dims"), nlohmann::json({24, 24, 24}));
    EXPECT_EQ(json.at("type"), "f32");
    EXPECT_EQ(json.at("bytes"), 24 * 24 * 24 * 4);
    EXPECT_DOUBLE_EQ(json.at("bounds")[0][0].get<double>(), -1.0);
    EXPECT_DOUBLE_EQ(json.at("bounds")[1][2].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(json.at("channels")[0].at("max").get<double>(), 2.0);  // the skull

    for (const char* name : {"sl.nii.gz", "sl.json", "sl.nhdr"}) {
        const CliResult convert =
            run_cli("volume convert " + quoted(scratch / "sl.nrrd") + " " + quoted(scratch / name),
                    scratch);
        ASSERT_EQ(convert.exit_code, 0) << name << ": " << convert.err;
        const volume::Volume back = io::read_volume(scratch / name);
        EXPECT_TRUE(std::equal(back.bytes().begin(), back.bytes().end(), expected.bytes().begin()))
            << name;
        // NIfTI stores spacing as float; NRRD and the JSON sidecar keep the double.
        EXPECT_NEAR(back.spacing().x, expected.spacing().x, 1e-7) << name;
        if (std::string(name) != "sl.nii.gz") {
            EXPECT_EQ(back.spacing(), expected.spacing()) << name;
        }
    }
}

TEST(VolumeCommand, CleanThresholdsAndNormalizesAlpha) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate rgba-test " + quoted(scratch / "rt.nrrd") + " --dims 16", scratch)
            .exit_code,
        0);
    // The test object's opacities are 0.6 (arrows, cube) and 0.1 (sphere): T = 35 (0.137)
    // removes the sphere; normalization by the maximum maps 0.6 to 1.
    const CliResult clean = run_cli("volume clean " + quoted(scratch / "rt.nrrd") + " " +
                                        quoted(scratch / "clean.nrrd") + " --threshold 35",
                                    scratch);
    ASSERT_EQ(clean.exit_code, 0) << clean.err;
    const volume::Volume v = io::read_volume(scratch / "clean.nrrd");
    const auto rgba = v.values<volume::VoxelType::rgba32f>();
    bool has_opaque = false;
    for (std::size_t i = 3; i < rgba.size(); i += 4) {
        EXPECT_TRUE(rgba[i] == 0.0f || rgba[i] == 1.0f) << rgba[i];
        has_opaque |= rgba[i] == 1.0f;
    }
    EXPECT_TRUE(has_opaque);
    // A scalar volume cannot be cleaned.
    ASSERT_EQ(run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 8", scratch)
                  .exit_code,
              0);
    const CliResult scalar = run_cli(
        "volume clean " + quoted(scratch / "s.nrrd") + " " + quoted(scratch / "x.nrrd"), scratch);
    EXPECT_EQ(scalar.exit_code, 1);
    EXPECT_FALSE(std::filesystem::exists(scratch / "x.nrrd"));
}

TEST(VolumeCommand, LimitsAndErrors) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 32", scratch)
            .exit_code,
        0);
    // 32³ f32 = 128 KiB: refused under a 0.1 MiB limit, before allocating.
    const CliResult limited =
        run_cli("volume info " + quoted(scratch / "s.nrrd") + " --max-memory 0.1", scratch);
    EXPECT_EQ(limited.exit_code, 1);
    EXPECT_NE(limited.err.find("pliant: error:"), std::string::npos) << limited.err;
    EXPECT_NE(limited.err.find("limit"), std::string::npos) << limited.err;
    EXPECT_EQ(run_cli("volume info " + quoted(scratch / "s.nrrd") + " --max-memory 0.2", scratch)
                  .exit_code,
              0);
    std::ofstream(scratch / "garbage.nrrd") << "not a volume";
    const CliResult garbage = run_cli("volume info " + quoted(scratch / "garbage.nrrd"), scratch);
    EXPECT_EQ(garbage.exit_code, 1);
    EXPECT_NE(garbage.err.find("garbage.nrrd"), std::string::npos) << garbage.err;
    EXPECT_EQ(run_cli("volume info " + quoted(scratch / "missing.nii"), scratch).exit_code, 1);
    EXPECT_EQ(
        run_cli("volume convert " + quoted(scratch / "s.nrrd") + " " + quoted(scratch / "s.stl"),
                scratch)
            .exit_code,
        1);
    EXPECT_EQ(run_cli("volume", scratch).exit_code, 2);
    EXPECT_EQ(run_cli("volume generate cube " + quoted(scratch / "c.nrrd"), scratch).exit_code, 2);
    EXPECT_EQ(run_cli("volume clean a b --threshold 300", scratch).exit_code, 2);
}

}  // namespace
}  // namespace pliant::test
