// Checkpoints and --resume end to end: `pliant cloth` killed with SIGKILL at several points
// (after k frames appear, at fixed-seed random times, while a checkpoint is being written) and
// resumed writes frames bitwise identical to an uninterrupted run's and the same stats.json apart
// from timings; --resume without a checkpoint starts over; a corrupt, truncated or foreign
// checkpoint is a clear error naming the file.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "run_cli.hpp"

namespace pliant::test {
namespace {

void write(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// Two sheets falling onto a small sphere and onto each other: obstacle contact and
// self-collision (paths, candidates, contacts, the fail-safe) carry state from frame to frame.
constexpr const char* SCENE = R"({
    "cloth": {"grid": {"size": [0.6, 0.6], "quads": [12, 12]},
              "instances": [{"translate": [0, 0, 0.1]},
                            {"translate": [0.05, 0.03, 0.16], "rotate_degrees": [0, 0, 30]}]},
    "material": {"bend_compliance": 100},
    "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.08}},
                  {"plane": {"point": [0, 0, -0.08], "normal": [0, 0, 1]}}],
    "fps": 24, "frames": 16, "substeps": 10
})";
constexpr int FRAMES = 16;

std::string cloth_args(const ScratchDir& scratch, const std::string& scene, const std::string& out,
                       const std::string& extra) {
    return "cloth " + quoted(scratch / scene) + " --out " + quoted(scratch / out) +
           " --no-preview " + extra;
}

// Starts `pliant ARGS` (split on spaces; test paths hold none) in the background.
pid_t spawn(const std::string& args) {
    std::vector<std::string> words;
    std::size_t start = 0;
    while (start < args.size()) {
        const std::size_t end = args.find(' ', start);
        const std::string word =
            args.substr(start, end == std::string::npos ? std::string::npos : end - start);
        if (!word.empty()) {
            words.push_back(word[0] == '\'' ? word.substr(1, word.size() - 2) : word);
        }
        if (end == std::string::npos) {
            break;
        }
        start = end + 1;
    }
    const pid_t pid = ::fork();
    if (pid == 0) {
        std::vector<char*> argv;
        std::string cli = PLIANT_CLI;
        argv.push_back(cli.data());
        for (std::string& w : words) {
            argv.push_back(w.data());
        }
        argv.push_back(nullptr);
        std::freopen("/dev/null", "w", stdout);
        std::freopen("/dev/null", "w", stderr);
        ::execv(cli.c_str(), argv.data());
        ::_exit(127);
    }
    return pid;
}

// SIGKILLs pid as soon as `ready()` holds (polled every 200 µs) or the process ends; returns
// whether it was killed before it ended.
template <typename Ready>
bool kill_when(pid_t pid, const Ready& ready) {
    int status = 0;
    for (;;) {
        if (::waitpid(pid, &status, WNOHANG) == pid) {
            return false;
        }
        if (ready()) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            return true;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
}

std::vector<std::string> file_names(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

// stats.json without the wall-clock times (and the resume's own note).
nlohmann::json without_timings(nlohmann::json stats) {
    for (const char* key : {"mean_ms_per_frame", "preview_ms_per_frame", "resumed_after_frame",
                            "checkpoint_ms", "checkpoint_bytes"}) {
        stats.erase(key);
    }
    for (nlohmann::json& frame : stats.at("frames")) {
        for (const char* key :
             {"ms", "step_ms", "refit_ms", "traverse_ms", "narrow_ms", "response_ms", "check_ms",
              "write_ms", "gather_ms", "project_ms", "ccd_ms", "ogc_detect_ms"}) {
            frame.erase(key);
        }
    }
    return stats;
}

// Every frame file and stats.json of `run` equal those of `reference` (frames byte for byte).
void expect_same_run(const std::filesystem::path& reference, const std::filesystem::path& run) {
    const std::vector<std::string> names = file_names(reference / "frames");
    ASSERT_EQ(names.size(), static_cast<std::size_t>(FRAMES + 1));
    ASSERT_EQ(file_names(run / "frames"), names);
    for (const std::string& name : names) {
        EXPECT_TRUE(read_text(reference / "frames" / name) == read_text(run / "frames" / name))
            << name << " differs";
    }
    EXPECT_EQ(without_timings(nlohmann::json::parse(read_text(run / "stats.json"))),
              without_timings(nlohmann::json::parse(read_text(reference / "stats.json"))));
}

class ClothResume : public ::testing::Test {
protected:
    virtual std::string scene() const { return SCENE; }

    void SetUp() override {
        write(scratch / "scene.json", scene());
        const CliResult r = run_cli(
            cloth_args(scratch, "scene.json", "reference", "--checkpoint-every 0"), scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        ASSERT_FALSE(std::filesystem::exists(scratch / "reference" / "checkpoint.bin"));
        // The scene exercises self-collision: the sheets touch (OGC: pairs within its radius).
        const nlohmann::json stats =
            nlohmann::json::parse(read_text(scratch / "reference" / "stats.json"));
        int contacts = 0;
        for (const nlohmann::json& frame : stats.at("frames")) {
            contacts += frame.at("contacts").get<int>() + frame.value("ogc_close_pairs", 0);
        }
        ASSERT_GT(contacts, 0);
    }

    // Resumes `out` until it completes (at most `attempts` runs).
    void resume(const std::string& out) {
        const CliResult r = run_cli(
            cloth_args(scratch, "scene.json", out, "--checkpoint-every 2 --resume"), scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
    }

    ScratchDir scratch;
};

TEST_F(ClothResume, KilledAfterKFramesResumesBitwiseIdentical) {
    for (const int k : {1, 4, 9, 14}) {
        SCOPED_TRACE("killed once frame " + std::to_string(k) + " appeared");
        const std::string out = "killed_" + std::to_string(k);
        const std::filesystem::path frame =
            scratch / out / "frames" / fmt::format("frame_{:04d}.obj", k);
        const pid_t pid = spawn(cloth_args(scratch, "scene.json", out, "--checkpoint-every 2"));
        ASSERT_GT(pid, 0);
        EXPECT_TRUE(kill_when(pid, [&] { return std::filesystem::exists(frame); }));
        ASSERT_FALSE(std::filesystem::exists(scratch / out / "stats.json"));
        resume(out);
        expect_same_run(scratch / "reference", scratch / out);
        const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / out / "stats.json"));
        EXPECT_EQ(stats.at("frames").size(), static_cast<std::size_t>(FRAMES));
        // Frame 2's checkpoint is written before frame 3 starts.
        if (k >= 3) {
            EXPECT_TRUE(stats.contains("resumed_after_frame"));
        }
    }
}

// The same with the Vertex Block Descent stepper (cloth/vbd_stepper.hpp).
class ClothResumeVBD : public ClothResume {
protected:
    std::string scene() const override {
        std::string text = SCENE;
        text.insert(text.rfind('}'), R"(, "solver": {"type": "vbd", "iterations": 5})");
        return text;
    }
};

TEST_F(ClothResumeVBD, KilledAfterKFramesResumesBitwiseIdentical) {
    for (const int k : {1, 4, 9}) {
        SCOPED_TRACE("killed once frame " + std::to_string(k) + " appeared");
        const std::string out = "killed_" + std::to_string(k);
        const std::filesystem::path frame =
            scratch / out / "frames" / fmt::format("frame_{:04d}.obj", k);
        const pid_t pid = spawn(cloth_args(scratch, "scene.json", out, "--checkpoint-every 2"));
        ASSERT_GT(pid, 0);
        EXPECT_TRUE(kill_when(pid, [&] { return std::filesystem::exists(frame); }));
        resume(out);
        expect_same_run(scratch / "reference", scratch / out);
    }
}

// The same with OGC contact (cloth/ogc_contact.hpp).
class ClothResumeOGC : public ClothResume {
protected:
    std::string scene() const override {
        std::string text = SCENE;
        text.insert(text.rfind('}'),
                    R"(, "solver": {"type": "vbd", "iterations": 5}, "contact": "ogc")");
        return text;
    }
};

TEST_F(ClothResumeOGC, KilledAfterKFramesResumesBitwiseIdentical) {
    for (const int k : {1, 4, 9}) {
        SCOPED_TRACE("killed once frame " + std::to_string(k) + " appeared");
        const std::string out = "killed_" + std::to_string(k);
        const std::filesystem::path frame =
            scratch / out / "frames" / fmt::format("frame_{:04d}.obj", k);
        const pid_t pid = spawn(cloth_args(scratch, "scene.json", out, "--checkpoint-every 2"));
        ASSERT_GT(pid, 0);
        EXPECT_TRUE(kill_when(pid, [&] { return std::filesystem::exists(frame); }));
        resume(out);
        expect_same_run(scratch / "reference", scratch / out);
    }
}

TEST_F(ClothResume, KilledAtRandomTimesAndResumedTwiceIsIdentical) {
    // Fixed seed: the same kill points on every run of the test (as far as the timing allows).
    std::mt19937 random(20261129);
    std::uniform_int_distribution<int> delay_ms(30, 400);
    for (int trial = 0; trial < 3; ++trial) {
        SCOPED_TRACE("trial " + std::to_string(trial));
        const std::string out = "random_" + std::to_string(trial);
        // Killed, then killed again while resuming, then resumed to the end.
        for (int kill = 0; kill < 2; ++kill) {
            const pid_t pid = spawn(
                cloth_args(scratch, "scene.json", out,
                           "--checkpoint-every 3" + std::string(kill > 0 ? " --resume" : "")));
            ASSERT_GT(pid, 0);
            const auto deadline =
                std::chrono::steady_clock::now() + std::chrono::milliseconds(delay_ms(random));
            kill_when(pid, [&] { return std::chrono::steady_clock::now() >= deadline; });
        }
        resume(out);
        expect_same_run(scratch / "reference", scratch / out);
    }
}

TEST_F(ClothResume, KilledWhileWritingACheckpointLeavesNoTemporaryFiles) {
    // Polls for the checkpoint's temporary file and kills the run while it exists; a run whose
    // writes are too quick to catch is killed after its third frame.
    const std::string out = "mid_write";
    const pid_t pid = spawn(cloth_args(scratch, "scene.json", out, "--checkpoint-every 1"));
    ASSERT_GT(pid, 0);
    kill_when(pid, [&] {
        std::error_code ec;
        for (const auto& entry : std::filesystem::directory_iterator(scratch / out, ec)) {
            if (entry.path().filename().string().find(".tmp-") != std::string::npos) {
                return true;
            }
        }
        return std::filesystem::exists(scratch / out / "frames" / "frame_0003.obj");
    });
    // A temporary file as a killed writer leaves it, also among the frames.
    write(scratch / out / "frames" / "frame_0002.obj.tmp-999999-7", "v 0 0");
    write(scratch / out / "checkpoint.bin.tmp-999999-8", "PLNT");
    resume(out);
    expect_same_run(scratch / "reference", scratch / out);
    for (const std::filesystem::path& dir : {scratch / out, scratch / out / "frames"}) {
        for (const std::string& name : file_names(dir)) {
            EXPECT_EQ(name.find(".tmp-"), std::string::npos) << name;
        }
    }
}

TEST_F(ClothResume, ResumeWithoutACheckpointStartsOver) {
    const CliResult r = run_cli(cloth_args(scratch, "scene.json", "fresh", "--resume"), scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("no checkpoint"), std::string::npos) << r.err;
    expect_same_run(scratch / "reference", scratch / "fresh");
}

TEST_F(ClothResume, CheckpointingDoesNotChangeTheFrames) {
    const CliResult r =
        run_cli(cloth_args(scratch, "scene.json", "every", "--checkpoint-every 1"), scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_same_run(scratch / "reference", scratch / "every");
    // A complete run's last checkpoint is its last frame: resuming it simulates nothing, and
    // resuming with more frames extends it.
    const CliResult again = run_cli(
        cloth_args(scratch, "scene.json", "every", "--checkpoint-every 1 --resume"), scratch);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    expect_same_run(scratch / "reference", scratch / "every");
}

// A tmpfs of `size` mounted on `dir` (root only); unmounted when it goes out of scope.
class SmallDisk {
public:
    SmallDisk(const std::filesystem::path& dir, const std::string& size) : m_dir(dir) {
        std::filesystem::create_directories(dir);
        m_mounted = ::geteuid() == 0 && std::system(("mount -t tmpfs -o size=" + size + " tmpfs " +
                                                     quoted(dir) + " 2>/dev/null")
                                                        .c_str()) == 0;
    }
    SmallDisk(const SmallDisk&) = delete;
    SmallDisk& operator=(const SmallDisk&) = delete;
    ~SmallDisk() {
        if (m_mounted) {
            std::system(("umount " + quoted(m_dir)).c_str());
        }
    }
    bool mounted() const { return m_mounted; }

private:
    std::filesystem::path m_dir;
    bool m_mounted = false;
};

TEST_F(ClothResume, FullDiskStopsCleanlyAndResumesOnceThereIsSpace) {
    const SmallDisk disk(scratch / "disk", "4m");
    if (!disk.mounted()) {
        GTEST_SKIP() << "needs root and a tmpfs mount (mount -t tmpfs) to fill a disk for real";
    }
    // Most of the disk taken: the run fills the rest after a few frames.
    {
        std::ofstream filler(scratch / "disk" / "filler", std::ios::binary);
        const std::string block(1 << 16, 'x');
        for (int i = 0; i < 52; ++i) {
            filler << block;
        }
    }
    const std::string out = "disk/out";
    const CliResult full =
        run_cli(cloth_args(scratch, "scene.json", out, "--checkpoint-every 2"), scratch);
    ASSERT_EQ(full.exit_code, 1) << full.err;
    EXPECT_NE(full.err.find("No space left on device"), std::string::npos) << full.err;
    EXPECT_NE(full.err.find("--resume"), std::string::npos) << full.err;
    // stats.json describes exactly the frames on disk; nothing partial or temporary is left.
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / out / "stats.json"));
    ASSERT_FALSE(stats.at("error").is_null());
    const std::size_t frames = stats.at("frames").size();
    EXPECT_LT(frames, static_cast<std::size_t>(FRAMES));
    std::vector<std::string> expected;
    for (std::size_t f = 0; f <= frames; ++f) {
        expected.push_back(fmt::format("frame_{:04d}.obj", f));
        EXPECT_TRUE(read_text(scratch / out / "frames" / expected.back()) ==
                    read_text(scratch / "reference" / "frames" / expected.back()))
            << expected.back();
    }
    EXPECT_EQ(file_names(scratch / out / "frames"), expected);
    for (const std::string& name : file_names(scratch / out)) {
        EXPECT_EQ(name.find(".tmp-"), std::string::npos) << name;
    }
    // Space freed: the run resumes and ends as an uninterrupted one.
    std::filesystem::remove(scratch / "disk" / "filler");
    resume(out);
    expect_same_run(scratch / "reference", scratch / out);
}

class ClothResumeErrors : public ClothResume {
protected:
    // A run of 6 frames into `out` with a checkpoint at frame 6.
    std::filesystem::path checkpointed(const std::string& out) {
        const CliResult r = run_cli(
            cloth_args(scratch, "scene.json", out, "--frames 6 --checkpoint-every 3"), scratch);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        return scratch / out / "checkpoint.bin";
    }
    void expect_refused(const std::string& out, const std::string& scene,
                        const std::string& message) {
        const std::string stats_before = read_text(scratch / out / "stats.json");
        const CliResult r = run_cli(cloth_args(scratch, scene, out, "--resume"), scratch);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(r.err.find("pliant: error: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find((scratch / out / "checkpoint.bin").string()), std::string::npos)
            << r.err;
        EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
        EXPECT_EQ(read_text(scratch / out / "stats.json"), stats_before);  // nothing written
    }
};

TEST_F(ClothResumeErrors, CorruptCheckpointIsAnErrorNamingTheFile) {
    const std::filesystem::path file = checkpointed("corrupt");
    std::string bytes = read_text(file);
    ASSERT_GT(bytes.size(), 100u);
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x40);
    write(file, bytes);
    expect_refused("corrupt", "scene.json", "checksum");
}

TEST_F(ClothResumeErrors, TruncatedCheckpointIsAnErrorNamingTheFile) {
    const std::filesystem::path file = checkpointed("truncated");
    const std::string bytes = read_text(file);
    write(file, bytes.substr(0, bytes.size() / 3));
    expect_refused("truncated", "scene.json", "truncated");
    write(file, bytes.substr(0, 20));
    expect_refused("truncated", "scene.json", "truncated");
    write(file, "not a checkpoint at all, but long enough to hold a header and more");
    expect_refused("truncated", "scene.json", "not a pliant checkpoint");
}

TEST_F(ClothResumeErrors, CheckpointOfAnotherSceneIsAnError) {
    checkpointed("other");
    std::string other = SCENE;
    other.replace(other.find("0.08"), 4, "0.09");
    write(scratch / "other.json", other);
    expect_refused("other", "other.json", "belongs to another run");
}

// `pliant deform` killed once its checkpoint appears and resumed writes the same volume as an
// uninterrupted run; kinematic (twist) and rest-state (bubble) drivers.
TEST(DeformResume, KilledAndResumedWritesTheSameVolume) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 64", scratch)
            .exit_code,
        0);
    for (const std::string driver : {"twist", "bubble"}) {
        SCOPED_TRACE(driver);
        const std::string args = "deform " + quoted(scratch / "s.nrrd") + " --driver " + driver +
                                 " --frames 30 --checkpoint-every 4 -o ";
        const CliResult reference =
            run_cli(args + quoted(scratch / (driver + "_reference.nrrd")), scratch);
        ASSERT_EQ(reference.exit_code, 0) << reference.err;
        const std::filesystem::path out = scratch / (driver + ".nrrd");
        const std::filesystem::path checkpoint = scratch / (driver + ".nrrd.checkpoint.bin");
        const pid_t pid = spawn(args + quoted(out));
        ASSERT_GT(pid, 0);
        const bool killed = kill_when(pid, [&] { return std::filesystem::exists(checkpoint); });
        const CliResult resumed = run_cli(args + quoted(out) + " --resume", scratch);
        ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
        if (killed) {
            EXPECT_NE(resumed.err.find("resuming after frame"), std::string::npos) << resumed.err;
        }
        EXPECT_TRUE(read_text(out) == read_text(scratch / (driver + "_reference.nrrd")));
        EXPECT_FALSE(std::filesystem::exists(checkpoint));  // removed once complete
    }
}

TEST(DeformResume, CorruptCheckpointAndVideoAreErrors) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 16", scratch)
            .exit_code,
        0);
    const std::string args = "deform " + quoted(scratch / "s.nrrd") +
                             " --driver twist --frames 4 -o " + quoted(scratch / "d.nrrd");
    write(scratch / "d.nrrd.checkpoint.bin", "PLNTCKPT but nothing else that a checkpoint holds");
    const CliResult corrupt = run_cli(args + " --resume", scratch);
    EXPECT_EQ(corrupt.exit_code, 1) << corrupt.err;
    EXPECT_NE(corrupt.err.find((scratch / "d.nrrd.checkpoint.bin").string()), std::string::npos)
        << corrupt.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "d.nrrd"));
    const CliResult video =
        run_cli(args + " --resume --render " + quoted(scratch / "d.mp4"), scratch);
    EXPECT_EQ(video.exit_code, 1) << video.err;
    EXPECT_NE(video.err.find("--resume cannot continue the video"), std::string::npos) << video.err;
}

// `pliant nerf train --iterations N` killed once its checkpoint appears and resumed exports the
// same volume as an uninterrupted run (iteration i's rays depend only on the seed and i).
TEST(NerfResume, KilledAndResumedTrainsTheSameVolume) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate rgba-test " + quoted(scratch / "rt.nrrd") + " --dims 24", scratch)
            .exit_code,
        0);
    ASSERT_EQ(run_cli("dataset " + quoted(scratch / "rt.nrrd") + " --views 12 --size 48x48 -o " +
                          quoted(scratch / "ds"),
                      scratch)
                  .exit_code,
              0);
    const std::string args = "nerf train " + quoted(scratch / "ds" / "transforms_train.json") +
                             " --iterations 600 --resolution 32 --batch 1024 "
                             "--export-resolution 32 --checkpoint-every 100 -o ";
    const CliResult reference = run_cli(args + quoted(scratch / "reference.nrrd"), scratch);
    ASSERT_EQ(reference.exit_code, 0) << reference.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "reference.nrrd.checkpoint.bin"));
    const std::filesystem::path checkpoint = scratch / "killed.nrrd.checkpoint.bin";
    const pid_t pid = spawn(args + quoted(scratch / "killed.nrrd"));
    ASSERT_GT(pid, 0);
    const bool killed = kill_when(pid, [&] { return std::filesystem::exists(checkpoint); });
    const CliResult resumed =
        run_cli(args + quoted(scratch / "killed.nrrd") + " --resume", scratch);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    if (killed) {
        EXPECT_NE(resumed.err.find("resuming from"), std::string::npos) << resumed.err;
    }
    EXPECT_TRUE(read_text(scratch / "killed.nrrd") == read_text(scratch / "reference.nrrd"));
    // Other training options: the checkpoint is not this run's.
    const pid_t again = spawn(args + quoted(scratch / "other.nrrd"));
    ASSERT_GT(again, 0);
    if (kill_when(again,
                  [&] { return std::filesystem::exists(scratch / "other.nrrd.checkpoint.bin"); })) {
        const CliResult other =
            run_cli(args + quoted(scratch / "other.nrrd") + " --resume --seed 7", scratch);
        EXPECT_EQ(other.exit_code, 1) << other.err;
        EXPECT_NE(other.err.find("belongs to another run"), std::string::npos) << other.err;
    }
}

}  // namespace
}  // namespace pliant::test
