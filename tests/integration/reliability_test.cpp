// Faults around the files every command writes (docs/reliability.md): a full disk (simulated
// with the shell's file-size limit, RLIMIT_FSIZE, with SIGXFSZ ignored so writes fail with EFBIG
// as on a full disk) and an output directory that cannot exist. Each must give `pliant: error:`
// naming the output, exit code 1, and leave neither the output nor a temporary file behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "integration/run_cli.hpp"

namespace pliant::test {
namespace {

// The names in `dir` other than the inputs.
std::vector<std::string> leftovers(const std::filesystem::path& dir,
                                   const std::vector<std::string>& inputs) {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        const std::string name = entry.path().filename().string();
        if (name != "stdout.txt" && name != "stderr.txt" &&
            std::find(inputs.begin(), inputs.end(), name) == inputs.end()) {
            names.push_back(name);
        }
    }
    return names;
}

struct Writer {
    const char* what;
    std::string args;    // after the input volume
    std::string output;  // the file it writes
};

TEST(Reliability, FullDiskLeavesNoPartialOutput) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "in.nrrd") + " --dims 64", scratch)
            .exit_code,
        0);
    const std::string in = quoted(scratch / "in.nrrd");
    const Writer writers[] = {
        {"volume convert", "volume convert " + in + " " + quoted(scratch / "out.nrrd"), "out.nrrd"},
        {"render", "render " + in + " --size 256x256 -o " + quoted(scratch / "out.png"), "out.png"},
        {"deform", "deform " + in + " --driver rotate --frames 1 -o " + quoted(scratch / "d.nrrd"),
         "d.nrrd"},
        {"volume generate", "volume generate sphere " + quoted(scratch / "g.nrrd") + " --dims 64",
         "g.nrrd"},
    };
    for (const Writer& w : writers) {
        SCOPED_TRACE(w.what);
        // One block (512 or 1024 bytes, by the shell): less than any of the outputs.
        const CliResult r = run_cli(w.args, scratch, "ulimit -f 1; trap '' XFSZ;");
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(r.err.find("pliant: error: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(w.output), std::string::npos) << r.err;
        EXPECT_EQ(leftovers(scratch.path(), {"in.nrrd"}), std::vector<std::string>{});
    }
}

TEST(Reliability, OutputUnderAFileIsAnErrorNotACrash) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "in.nrrd") + " --dims 8", scratch)
            .exit_code,
        0);
    {
        std::FILE* f = std::fopen((scratch / "file").c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fclose(f);
    }
    const std::string in = quoted(scratch / "in.nrrd");
    const std::string bad = (scratch / "file").string() + "/";
    const Writer writers[] = {
        {"volume convert", "volume convert " + in + " '" + bad + "out.nrrd'", "out.nrrd"},
        {"render", "render " + in + " --size 16x16 -o '" + bad + "out.png'", "out.png"},
        {"deform", "deform " + in + " --driver rotate --frames 1 -o '" + bad + "d.nrrd'", "d.nrrd"},
        {"cloth",
         "cloth " + quoted(std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes/flag.json") +
             " --frames 1 --no-preview --out '" + bad + "cloth'",
         "cloth"},
    };
    for (const Writer& w : writers) {
        SCOPED_TRACE(w.what);
        const CliResult r = run_cli(w.args, scratch);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(r.err.find("pliant: error: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(w.output), std::string::npos) << r.err;
        EXPECT_EQ(leftovers(scratch.path(), {"in.nrrd", "file"}), std::vector<std::string>{});
    }
}

}  // namespace
}  // namespace pliant::test
