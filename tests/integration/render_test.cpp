// pliant render end to end: a small generated volume written with io::write_volume, rendered to a
// PNG of the requested size; --json keys; usage errors exit 2, unreadable files exit 1.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>

#include "pliant/io/png.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/volume/generate.hpp"
#include "run_cli.hpp"

namespace pliant::test {
namespace {

std::filesystem::path write_phantom(const ScratchDir& scratch) {
    const std::filesystem::path path = scratch / "phantom.nrrd";
    io::write_volume(path, volume::shepp_logan_3d({24, 24, 24}));
    return path;
}

TEST(RenderCli, WritesAPngOfTheRequestedSize) {
    const ScratchDir scratch;
    const auto volume = write_phantom(scratch);
    const auto png = scratch / "out.png";
    const CliResult r = run_cli(
        "render " + quoted(volume) + " --tf mri-brain --size 40x30 -o " + quoted(png), scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const render::Image image = io::read_png(png);
    EXPECT_EQ(image.width, 40);
    EXPECT_EQ(image.height, 30);
    EXPECT_NE(image, render::Image(40, 30));  // something was drawn
}

// Legal but almost certainly not meant: a CT preset on a volume without air (values 0-1), and a
// transfer function that shows none of the volume, are warned about; a fitting preset is not.
TEST(RenderCli, TransferFunctionsThatShowNothingAreWarnedAbout) {
    const ScratchDir scratch;
    const auto volume = write_phantom(scratch);
    const auto png = scratch / "out.png";
    const CliResult ct = run_cli(
        "render " + quoted(volume) + " --tf ct-bone --size 16x16 -o " + quoted(png), scratch);
    ASSERT_EQ(ct.exit_code, 0) << ct.err;
    EXPECT_NE(ct.err.find("pliant: warning: transfer function 'ct-bone' is for CT in Hounsfield "
                          "units"),
              std::string::npos)
        << ct.err;
    std::ofstream(scratch / "high.json") << R"({"color": [{"value": 50, "rgb": [1, 1, 1]}],
        "opacity": [{"value": 50, "alpha": 0}, {"value": 60, "alpha": 1}]})";
    const CliResult high =
        run_cli("render " + quoted(volume) + " --tf " + quoted(scratch / "high.json") +
                    " --size 16x16 -o " + quoted(png),
                scratch);
    ASSERT_EQ(high.exit_code, 0) << high.err;
    EXPECT_NE(high.err.find("makes 0 % of the volume's voxels visible"), std::string::npos)
        << high.err;
    const CliResult fitting = run_cli(
        "render " + quoted(volume) + " --tf mri-brain --size 16x16 -o " + quoted(png), scratch);
    ASSERT_EQ(fitting.exit_code, 0) << fitting.err;
    EXPECT_EQ(fitting.err.find("warning"), std::string::npos) << fitting.err;
}

TEST(RenderCli, JsonHasTheTimingsAndSamples) {
    const ScratchDir scratch;
    const auto volume = write_phantom(scratch);
    const auto png = scratch / "view.png";
    const CliResult r = run_cli("--json render " + quoted(volume) + " --view -z --size 24x24 -o " +
                                    quoted(png) + " --background 0.1,0.2,0.3 --step 0.05",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    for (const char* key : {"output", "width", "height", "frames", "step", "opacity_unit",
                            "prepare_ms", "ms_per_frame", "samples"}) {
        EXPECT_TRUE(j.contains(key)) << key;
    }
    EXPECT_GT(j["samples"].get<std::int64_t>(), 0);
    EXPECT_DOUBLE_EQ(j["step"].get<double>(), 0.05);
    // Without --size, --view picks 512 on the longer side.
    const CliResult d =
        run_cli("--json render " + quoted(volume) + " --view +x -o " + quoted(png), scratch);
    ASSERT_EQ(d.exit_code, 0) << d.err;
    EXPECT_EQ(io::read_png(png).width, 512);
}

TEST(RenderCli, BadOptionsExitTwo) {
    const ScratchDir scratch;
    const auto volume = write_phantom(scratch);
    const std::string v = quoted(volume);
    const std::string out = " -o " + quoted(scratch / "x.png");
    for (const std::string& args :
         {"render " + v + " --view up" + out, "render " + v + " --size 0x10" + out,
          "render " + v + " --size 10" + out, "render " + v + " --step -1" + out,
          "render " + v + " --background 2,0,0" + out,
          "render " + v + " --view +x --camera 1,2,3" + out, "render " + v,
          "render " + v + " -o " + quoted(scratch / "x.jpg"),
          "render " + v + " --orbit 4 -o " + quoted(scratch / "x.png")}) {
        const CliResult r = run_cli(args, scratch);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    }
    EXPECT_FALSE(std::filesystem::exists(scratch / "x.png"));
}

TEST(RenderCli, BadFilesExitOne) {
    const ScratchDir scratch;
    const auto broken = scratch / "broken.nrrd";
    {
        std::FILE* f = std::fopen(broken.c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fputs("NRRD0004\ntype: float\ndimension: 3\nsizes: 100 100 100\n", f);
        std::fclose(f);
    }
    const auto out = scratch / "x.png";
    for (const std::string& args :
         {"render " + quoted(scratch / "missing.nrrd") + " -o " + quoted(out),
          "render " + quoted(broken) + " -o " + quoted(out)}) {
        const CliResult r = run_cli(args, scratch);
        EXPECT_EQ(r.exit_code, 1) << args;
        EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    }
    const auto volume = write_phantom(scratch);
    const CliResult tf = run_cli("render " + quoted(volume) + " --tf " +
                                     quoted(scratch / "none.json") + " -o " + quoted(out),
                                 scratch);
    EXPECT_EQ(tf.exit_code, 1) << tf.err;
    EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace pliant::test
