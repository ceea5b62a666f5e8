// --max-memory on every command that allocates by input size (pipeline/memory_budget.hpp): a
// limit too small for the work is refused before allocating, with "<what> needs X, more than the
// Y allowed by --max-memory (or available)", exit 1 and nothing written; the same run without the
// limit (the memory available) succeeds.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "integration/run_cli.hpp"

namespace pliant::test {
namespace {

constexpr const char* REFUSED = "allowed by --max-memory (or available)";

// A 64³ sphere volume (f32: 1 MiB) in scratch/in.nrrd.
std::string sphere(const ScratchDir& scratch) {
    const CliResult r =
        run_cli("volume generate sphere " + quoted(scratch / "in.nrrd") + " --dims 64", scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return quoted(scratch / "in.nrrd");
}

void expect_refused(const CliResult& r, const std::string& what) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("pliant: error: " + what), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(REFUSED), std::string::npos) << r.err;
}

TEST(MemoryLimit, RenderRefusesAnImageOrVolumeTooLargeBeforeAllocating) {
    ScratchDir scratch;
    const std::string in = sphere(scratch);
    const auto out = scratch / "out.png";
    // The image alone: 4096 x 4096 x 3 bytes = 50.3 MB > 2 MiB, refused before reading the volume.
    expect_refused(
        run_cli("render " + in + " --size 4096x4096 --max-memory 2 -o " + quoted(out), scratch),
        "render: a 4096x4096 image needs 50.3 MB, more than the 2.1 MB");
    EXPECT_FALSE(std::filesystem::exists(out));
    // The volume (1.05 MB) fits, with the caster's tables (5 bytes per voxel) it does not.
    expect_refused(
        run_cli("render " + in + " --size 16x16 --max-memory 2 -o " + quoted(out), scratch),
        "render: ray-casting a 16x16 image of the 64 x 64 x 64 f32 volume needs 2.36 MB, more "
        "than the 2.1 MB");
    EXPECT_FALSE(std::filesystem::exists(out));
    // An orbit is refused the same way, before ffmpeg starts.
    const auto video = scratch / "orbit.mp4";
    expect_refused(
        run_cli("render " + in + " --size 4096x4096 --orbit 4 --max-memory 2 -o " + quoted(video),
                scratch),
        "render: a 4096x4096 image");
    EXPECT_FALSE(std::filesystem::exists(video));
    // Enough memory, and the default (the memory available): rendered.
    for (const std::string limit : {" --max-memory 4", ""}) {
        const CliResult r =
            run_cli("render " + in + " --size 16x16" + limit + " -o " + quoted(out), scratch);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_TRUE(std::filesystem::exists(out));
        std::filesystem::remove(out);
    }
}

TEST(MemoryLimit, DatasetRefusesBeforeWritingAnything) {
    ScratchDir scratch;
    const std::string in = sphere(scratch);
    const auto dir = scratch / "ds";
    expect_refused(
        run_cli("dataset " + in + " --views 2 --size 16x16 --max-memory 2 -o " + quoted(dir),
                scratch),
        "dataset: ray-casting a 16x16 image of the 64 x 64 x 64 f32 volume needs 2.36 MB");
    EXPECT_FALSE(std::filesystem::exists(dir));
    expect_refused(
        run_cli("dataset " + in + " --views 2 --size 8000x8000 --max-memory 100 -o " + quoted(dir),
                scratch),
        "dataset: a 8000x8000 view needs 192 MB, more than the 105 MB");
    EXPECT_FALSE(std::filesystem::exists(dir));
    const CliResult r =
        run_cli("dataset " + in + " --views 2 --size 16x16 -o " + quoted(dir), scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "transforms_train.json"));
}

TEST(MemoryLimit, DeformRefusesATetGridTooLargeBeforeBuildingIt) {
    ScratchDir scratch;
    const std::string in = sphere(scratch);
    const auto out = scratch / "d.nrrd";
    // 64³ cells of one voxel: 1,310,720 tets at 128 bytes = 168 MB > 64 MiB.
    expect_refused(run_cli("deform " + in + " --driver rotate --frames 1 --cells 1 " +
                               "--max-memory 64 -o " + quoted(out),
                           scratch),
                   "deform: a grid of 262144 cells of 1^3 voxels over the 64 x 64 x 64 volume "
                   "needs 170 MB, more than the 67.1 MB");
    EXPECT_FALSE(std::filesystem::exists(out));
    // Cells of 8 voxels: 512 cells, well within 64 MiB.
    const CliResult r = run_cli("deform " + in + " --driver rotate --frames 1 --cells 8 " +
                                    "--max-memory 64 -o " + quoted(out),
                                scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(out));
}

TEST(MemoryLimit, CollideRefusesAMeshWhoseBroadPhaseDoesNotFit) {
    ScratchDir scratch;
    // A 40 x 40-quad grid: 3,200 triangles, 1.6 MB of broad phase at 500 bytes each.
    std::string obj;
    const int n = 40;
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
        }
    }
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1;
            obj += "f " + std::to_string(a) + " " + std::to_string(a + 1) + " " +
                   std::to_string(a + n + 2) + "\n";
            obj += "f " + std::to_string(a) + " " + std::to_string(a + n + 2) + " " +
                   std::to_string(a + n + 1) + "\n";
        }
    }
    const auto mesh = scratch / "grid.obj";
    {
        std::FILE* f = std::fopen(mesh.c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fputs(obj.c_str(), f);
        std::fclose(f);
    }
    const CliResult refused = run_cli("collide " + quoted(mesh) + " --max-memory 1", scratch);
    expect_refused(refused,
                   "collide: the broad phase over 3200 triangles needs 1.6 MB, more than the "
                   "1.05 MB");
    EXPECT_EQ(refused.out, "");
    for (const std::string limit : {" --max-memory 4", ""}) {
        const CliResult r = run_cli("collide " + quoted(mesh) + limit + " --json", scratch);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_NE(r.out.find("\"triangles\": 3200"), std::string::npos) << r.out;
    }
}

TEST(MemoryLimit, NerfEvalRefusesTheCasterBeforeAllocating) {
    ScratchDir scratch;
    ASSERT_EQ(run_cli("volume generate rgba-test " + quoted(scratch / "rgba.nrrd") + " --dims 32",
                      scratch)
                  .exit_code,
              0);
    const auto dir = scratch / "ds";
    ASSERT_EQ(run_cli("dataset " + quoted(scratch / "rgba.nrrd") + " --views 2 --size 16x16 -o " +
                          quoted(dir),
                      scratch)
                  .exit_code,
              0);
    const std::string eval =
        "nerf eval " + quoted(dir / "transforms_test.json") + " " + quoted(scratch / "rgba.nrrd");
    // The rgba32f volume (0.52 MB) is read within 1 MiB; with its caster (4 floats per voxel
    // and α apart, counted as a fifth) it needs more.
    expect_refused(run_cli(eval + " --max-memory 1", scratch),
                   "nerf eval: ray-casting a 16x16 image of the 32 x 32 x 32 rgba32f volume "
                   "needs 1.22 MB, more than the 1.05 MB");
    EXPECT_EQ(run_cli(eval, scratch).exit_code, 0);
}

TEST(MemoryLimit, UsageErrorsForBadLimits) {
    ScratchDir scratch;
    for (const char* command : {"render in.nrrd -o a.png", "dataset in.nrrd -o d", "collide m.obj",
                                "deform in.nrrd -o d.nrrd"}) {
        for (const char* value : {"0", "-1", "nan", "abc"}) {
            const CliResult r = run_cli(std::string(command) + " --max-memory " + value, scratch);
            EXPECT_EQ(r.exit_code, 2) << command << " " << value << ": " << r.err;
        }
    }
}

}  // namespace
}  // namespace pliant::test
