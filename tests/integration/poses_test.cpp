// pliant nerf poses without COLMAP's work: the checks made before COLMAP runs (empty folder,
// unreadable photos, photos of different sizes, COLMAP missing) and the handling of the COLMAP
// child (a failing stage, Ctrl-C), with a stand-in `colmap` script on $PATH. The run on real
// photos is poses_colmap_test.cpp.
#include <gtest/gtest.h>
#include <signal.h>  // NOLINT(modernize-deprecated-headers): kill is POSIX
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "pliant/io/png.hpp"
#include "run_cli.hpp"

namespace pliant::test {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

// n textured PNG photos of w × h in dir.
void write_photos(const fs::path& dir, int n, int w, int h) {
    fs::create_directories(dir);
    for (int i = 0; i < n; ++i) {
        render::Image image(w, h);
        for (std::size_t k = 0; k < image.pixels.size(); ++k) {
            image.pixels[k] =
                static_cast<std::uint8_t>((k * 37 + static_cast<std::size_t>(i) * 11) % 251);
        }
        io::write_png(dir / ("photo_" + std::to_string(i) + ".png"), image);
    }
}

// A stand-in `colmap` in dir/bin that runs `body` (a shell script) whatever its arguments.
std::string fake_colmap(const fs::path& dir, const std::string& body) {
    const fs::path bin = dir / "bin";
    fs::create_directories(bin);
    write_text(bin / "colmap", "#!/bin/sh\n" + body + "\n");
    ::chmod((bin / "colmap").c_str(), 0755);
    return "PATH=" + quoted(bin) + ":/usr/bin:/bin";
}

void expect_no_dataset(const fs::path& out) {
    EXPECT_FALSE(fs::exists(out / "transforms_train.json"));
    EXPECT_FALSE(fs::exists(out / "transforms_test.json"));
    EXPECT_FALSE(fs::exists(out / "points.ply"));
}

TEST(PosesCli, EmptyOrMissingFolder) {
    const ScratchDir scratch;
    fs::create_directories(scratch / "empty");
    write_text(scratch / "empty" / "notes.txt", "not a photo");
    const CliResult empty = run_cli(
        "nerf poses " + quoted(scratch / "empty") + " -o " + quoted(scratch / "out"), scratch);
    EXPECT_EQ(empty.exit_code, 1);
    EXPECT_NE(empty.err.find("pliant: error: "), std::string::npos) << empty.err;
    EXPECT_NE(empty.err.find("no photos"), std::string::npos) << empty.err;
    const CliResult missing = run_cli(
        "nerf poses " + quoted(scratch / "nope") + " -o " + quoted(scratch / "out"), scratch);
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.err.find("does not exist"), std::string::npos) << missing.err;
    expect_no_dataset(scratch / "out");
    // An output "folder" that is a file.
    write_photos(scratch / "photos", 3, 32, 24);
    write_text(scratch / "file", "x");
    const std::string env = fake_colmap(scratch.path(), "exit 0");
    const CliResult file_out =
        run_cli("nerf poses " + quoted(scratch / "photos") + " -o " + quoted(scratch / "file"),
                scratch, env);
    EXPECT_EQ(file_out.exit_code, 1);
    EXPECT_NE(file_out.err.find("cannot create the output directory"), std::string::npos)
        << file_out.err;
    EXPECT_EQ(run_cli("nerf poses " + quoted(scratch / "empty"), scratch).exit_code, 2);
    EXPECT_EQ(run_cli("nerf poses x -o y --test-every -1", scratch).exit_code, 2);
    EXPECT_EQ(run_cli("nerf poses x -o y --matcher vocab", scratch).exit_code, 2);
}

TEST(PosesCli, UnreadablePhotosAreNamedBeforeColmapRuns) {
    const ScratchDir scratch;
    const fs::path photos = scratch / "photos";
    write_photos(photos, 4, 32, 24);
    write_text(photos / "broken.jpg", "\xff\xd8\xff this is no JPEG");
    write_text(photos / "empty.PNG", "");
    // COLMAP must not be started: the stand-in fails the test by leaving a mark.
    const std::string env =
        fake_colmap(scratch.path(), "touch " + quoted(scratch / "ran") + "; exit 1");
    const CliResult r =
        run_cli("nerf poses " + quoted(photos) + " -o " + quoted(scratch / "out"), scratch, env);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("2 of 6 photos cannot be read"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("broken.jpg"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("empty.PNG"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(scratch / "ran"));
    expect_no_dataset(scratch / "out");
}

TEST(PosesCli, PhotosOfDifferentSizes) {
    const ScratchDir scratch;
    const fs::path photos = scratch / "photos";
    write_photos(photos, 3, 32, 24);
    render::Image odd(24, 32);
    io::write_png(photos / "zz_rotated.png", odd);
    const CliResult r =
        run_cli("nerf poses " + quoted(photos) + " -o " + quoted(scratch / "out"), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("zz_rotated.png is 24 x 32 but photo_0.png is 32 x 24"), std::string::npos)
        << r.err;
}

TEST(PosesCli, ColmapMissingSaysHowToInstallIt) {
    const ScratchDir scratch;
    write_photos(scratch / "photos", 3, 32, 24);
    fs::create_directories(scratch / "bin");
    const CliResult r =
        run_cli("nerf poses " + quoted(scratch / "photos") + " -o " + quoted(scratch / "out"),
                scratch, "PATH=" + quoted(scratch / "bin"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("apt-get install colmap"), std::string::npos) << r.err;
    expect_no_dataset(scratch / "out");
}

TEST(PosesCli, FailingColmapStageShowsTheEndOfItsLog) {
    const ScratchDir scratch;
    write_photos(scratch / "photos", 3, 32, 24);
    const std::string env =
        fake_colmap(scratch.path(), "echo \"stand-in: $1 cannot open the database\" >&2; exit 3");
    const CliResult r =
        run_cli("nerf poses " + quoted(scratch / "photos") + " -o " + quoted(scratch / "out"),
                scratch, env);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("COLMAP feature_extractor failed (exit code 3)"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("stand-in: feature_extractor cannot open the database"), std::string::npos)
        << r.err;
    EXPECT_NE(read_text(scratch / "out" / "colmap" / "log.txt").find("stand-in"),
              std::string::npos);
    expect_no_dataset(scratch / "out");
}

TEST(PosesCli, NoModelSaysWhatUsuallyHelps) {
    const ScratchDir scratch;
    write_photos(scratch / "photos", 3, 32, 24);
    const std::string env = fake_colmap(scratch.path(), "exit 0");  // every stage "succeeds"
    const CliResult r =
        run_cli("nerf poses " + quoted(scratch / "photos") + " -o " + quoted(scratch / "out"),
                scratch, env);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("COLMAP registered none of the 3 photos"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("more overlap"), std::string::npos) << r.err;
    expect_no_dataset(scratch / "out");
}

TEST(PosesCli, SigintKillsColmapAndExits130) {
    const ScratchDir scratch;
    write_photos(scratch / "photos", 3, 32, 24);
    // The stand-in records its pid, then sleeps; it must be gone after pliant exits.
    fake_colmap(scratch.path(), "echo $$ > " + quoted(scratch / "child.pid") + "; exec sleep 60");
    const std::string path_env = (scratch / "bin").string() + ":/usr/bin:/bin";
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::setenv("PATH", path_env.c_str(), 1);
        const std::string photos = (scratch / "photos").string();
        const std::string out = (scratch / "out").string();
        const std::string err = (scratch / "err.txt").string();
        std::freopen(err.c_str(), "w", stderr);
        std::freopen("/dev/null", "w", stdout);
        ::execl(PLIANT_CLI, PLIANT_CLI, "nerf", "poses", photos.c_str(), "-o", out.c_str(),
                nullptr);
        ::_exit(127);
    }
    for (int i = 0; i < 200 && !fs::exists(scratch / "child.pid"); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ASSERT_TRUE(fs::exists(scratch / "child.pid"));
    ::kill(pid, SIGINT);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 130) << read_text(scratch / "err.txt");
    EXPECT_NE(read_text(scratch / "err.txt").find("stopped during features"), std::string::npos)
        << read_text(scratch / "err.txt");
    const int child = std::stoi(read_text(scratch / "child.pid"));
    EXPECT_NE(::kill(child, 0), 0) << "the stand-in COLMAP (pid " << child << ") still runs";
    expect_no_dataset(scratch / "out");
}

}  // namespace
}  // namespace pliant::test
