// Faults injected around real runs of the pliant commands (docs/reliability.md, "Faults around
// outputs"; ctest label faults):
//   - a read-only output directory: a tmpfs mounted read-only (EROFS), and a directory of mode
//     0555 written by an unprivileged user (EACCES; root ignores permission bits, so as root the
//     command runs as `nobody` through setpriv);
//   - inputs that change while they are read: another process truncates the input to half and
//     writes it whole again, over and over, while the command runs (each run must give a complete
//     result or a clear error); a FIFO as an input is refused, not waited on;
//   - SIGKILL at seeded random moments (the process group: pliant and its ffmpeg), after which
//     every file under a final name must be complete (meshes, volumes and PNGs parse, MP4s
//     decode, stats.json parses and names only frames that exist), leftovers may only be
//     temporary files (`*.tmp-*`), and a later run into the same directory must succeed and
//     write what an uninterrupted run writes;
//   - a full disk: a small tmpfs.
// Each command must say `pliant: error:` naming the file, exit 1 and leave nothing partial. The
// mounts need root (CAP_SYS_ADMIN); without it those cases are skipped with the reason.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "integration/run_cli.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/checkpoint.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"

namespace pliant::test {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

// A tmpfs mounted at `dir` (created) for the lifetime of the object; ok() is false (and why()
// says why) when the mount failed, e.g. without CAP_SYS_ADMIN.
class Tmpfs {
public:
    Tmpfs(const fs::path& dir, const std::string& options, bool read_only) : m_dir(dir) {
        fs::create_directories(dir);
        const unsigned long flags = read_only ? static_cast<unsigned long>(MS_RDONLY) : 0UL;
        if (::mount("tmpfs", dir.c_str(), "tmpfs", flags, options.c_str()) == 0) {
            m_mounted = true;
        } else {
            m_why = std::string("mount -t tmpfs -o ") + options + (read_only ? ",ro " : " ") +
                    dir.string() + ": " + std::strerror(errno);
        }
    }
    Tmpfs(const Tmpfs&) = delete;
    Tmpfs& operator=(const Tmpfs&) = delete;
    ~Tmpfs() {
        if (m_mounted) {
            ::umount2(m_dir.c_str(), MNT_DETACH);
        }
    }
    bool ok() const { return m_mounted; }
    const std::string& why() const { return m_why; }

private:
    fs::path m_dir;
    bool m_mounted = false;
    std::string m_why;
};

// Every file under `dir`, relative to it.
std::vector<std::string> files_under(const fs::path& dir) {
    std::vector<std::string> names;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        return names;
    }
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
        if (!entry.is_directory()) {
            names.push_back(fs::relative(entry.path(), dir).string());
        }
    }
    std::sort(names.begin(), names.end());
    return names;
}

bool is_temporary(const std::string& name) {
    return name.find(".tmp-") != std::string::npos;
}

// ffmpeg decodes every frame of the MP4 without an error.
bool video_decodes(const fs::path& path) {
    const std::string command = io::find_ffmpeg().string() + " -v error -xerror -i " +
                                quoted(path) + " -f null - >/dev/null 2>&1";
    return std::system(command.c_str()) == 0;
}

// What is wrong with the files under `dir` (empty: nothing): each file under a final name must
// be complete, in the format its name says; only temporary files may be partial.
std::vector<std::string> incomplete_outputs(const fs::path& dir) {
    std::vector<std::string> problems;
    for (const std::string& name : files_under(dir)) {
        if (is_temporary(name)) {
            continue;
        }
        const fs::path path = dir / name;
        const std::string extension = path.extension().string();
        try {
            if (extension == ".obj" || extension == ".ply") {
                io::read_mesh(path);
            } else if (extension == ".nrrd" || extension == ".gz") {
                io::read_volume(path);
            } else if (extension == ".png") {
                io::read_png(path);
            } else if (extension == ".mp4") {
                if (!video_decodes(path)) {
                    problems.push_back(name + ": does not decode");
                }
            } else if (extension == ".json") {
                const nlohmann::json json = nlohmann::json::parse(read_text(path));
                // A cloth run's stats: every frame it lists is on disk.
                if (json.contains("frames") && json["frames"].is_array()) {
                    for (const nlohmann::json& frame : json["frames"]) {
                        char file[32];
                        std::snprintf(file, sizeof file, "frame_%04d.obj",
                                      frame.at("frame").get<int>());
                        if (!fs::exists(path.parent_path() / "frames" / file)) {
                            problems.push_back(name + ": lists " + file + ", which is missing");
                        }
                    }
                }
            } else if (extension == ".bin" && name.ends_with("checkpoint.bin")) {
                // A checkpoint (--checkpoint-every): its header, size and CRC hold.
                const std::string bytes = read_text(path);
                io::decode_checkpoint(
                    std::as_bytes(std::span<const char>(bytes.data(), bytes.size())), name);
            } else {
                problems.push_back(name + ": unexpected file");
            }
        } catch (const std::exception& e) {
            problems.push_back(name + ": " + e.what());
        }
    }
    return problems;
}

// Runs `pliant args...` in its own process group with stdout and stderr to `log`, sends SIGKILL
// to the group after `delay` (unless it ended first) and waits for it. Returns true when it was
// killed, false when it exited by itself first.
bool run_and_kill(const std::vector<std::string>& args, const fs::path& log,
                  std::chrono::microseconds delay) {
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::setpgid(0, 0);
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            ::dup2(fd, 1);
            ::dup2(fd, 2);
        }
        std::vector<char*> argv;
        std::string cli = PLIANT_CLI;
        argv.push_back(cli.data());
        std::vector<std::string> copy = args;
        for (std::string& a : copy) {
            argv.push_back(a.data());
        }
        argv.push_back(nullptr);
        ::execv(cli.c_str(), argv.data());
        ::_exit(127);
    }
    ::setpgid(pid, pid);  // also here: the kill below must not precede the child's own setpgid
    const auto deadline = std::chrono::steady_clock::now() + delay;
    int status = 0;
    while (std::chrono::steady_clock::now() < deadline) {
        if (::waitpid(pid, &status, WNOHANG) == pid) {
            return false;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    ::kill(-pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    return WIFSIGNALED(status);
}

// The arguments as one shell string for run_cli.
std::string shell_args(const std::vector<std::string>& args) {
    std::string text;
    for (const std::string& a : args) {
        text += test::quoted(fs::path(a)) + " ";
    }
    return text;
}

// The files of `dir` other than stats.json and MP4s (timings, encoder), with their bytes.
std::map<std::string, std::string> deterministic_outputs(const fs::path& dir) {
    std::map<std::string, std::string> files;
    for (const std::string& name : files_under(dir)) {
        const fs::path path(name);
        // stats.json and checkpoints hold timings; MP4s are not bitwise reproducible.
        if (path.filename() != "stats.json" && path.filename() != "checkpoint.bin" &&
            path.extension() != ".mp4" && !is_temporary(name)) {
            files[name] = read_text(dir / name);
        }
    }
    return files;
}

// A scratch volume (a 32³ sphere, float) written by `pliant volume generate`.
fs::path make_volume(const ScratchDir& scratch, int dims = 32) {
    const fs::path volume = scratch / "in.nrrd";
    const CliResult r = run_cli(
        "volume generate sphere " + quoted(volume) + " --dims " + std::to_string(dims), scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return volume;
}

// A small cloth scene: a 16 × 16-quad sheet falling on a sphere and on an OBJ box (the mesh
// obstacle `box.obj` beside the scene).
fs::path make_cloth_scene(const ScratchDir& scratch, const std::string& mesh = "box.obj") {
    write_text(scratch / "box.obj",
               "v -0.2 -0.2 -0.5\nv 0.2 -0.2 -0.5\nv 0.2 0.2 -0.5\nv -0.2 0.2 -0.5\n"
               "v -0.2 -0.2 -0.3\nv 0.2 -0.2 -0.3\nv 0.2 0.2 -0.3\nv -0.2 0.2 -0.3\n"
               "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
               "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
    const fs::path scene = scratch / "scene.json";
    write_text(scene, R"({
        "cloth": {"grid": {"size": [1.0, 1.0], "quads": [16, 16]}, "translate": [0, 0, 0.3]},
        "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.2}},
                      {"mesh": {"file": ")" +
                          mesh + R"("}}],
        "fps": 24, "frames": 12, "substeps": 8
    })");
    return scene;
}

// ---------------------------------------------------------------------------------------------
// A read-only output directory.

struct Writer {
    const char* what;
    std::string args;    // the whole command line, output under the read-only directory
    std::string output;  // what the error must name
};

std::vector<Writer> writers_into(const fs::path& ro, const fs::path& volume, const fs::path& scene,
                                 const fs::path& dataset) {
    const std::string in = quoted(volume);
    return {
        {"cloth", "cloth " + quoted(scene) + " --frames 2 --no-preview --out " + quoted(ro / "c"),
         (ro / "c").string()},
        {"cloth into the directory itself",
         "cloth " + quoted(scene) + " --frames 2 --no-preview --out " + quoted(ro), ro.string()},
        {"deform", "deform " + in + " --driver rotate --frames 1 -o " + quoted(ro / "d.nrrd"),
         (ro / "d.nrrd").string()},
        {"render", "render " + in + " --size 32x32 -o " + quoted(ro / "r.png"),
         (ro / "r.png").string()},
        {"render --orbit", "render " + in + " --size 32x32 --orbit 4 -o " + quoted(ro / "o.mp4"),
         (ro / "o.mp4").string()},
        {"volume convert", "volume convert " + in + " " + quoted(ro / "v.nii.gz"),
         (ro / "v.nii.gz").string()},
        {"nerf train",
         "nerf train " + quoted(dataset / "transforms_train.json") +
             " --iterations 20 --resolution 8 -o " + quoted(ro / "n.nrrd"),
         (ro / "n.nrrd").string()},
        {"dataset", "dataset " + in + " --views 2 --size 16x16 -o " + quoted(ro / "ds"),
         (ro / "ds").string()},
    };
}

// Checks every writer against the read-only directory `ro`; `environment` goes before the
// command (run_cli).
void expect_clear_errors(const std::vector<Writer>& writers, const fs::path& ro,
                         const ScratchDir& scratch, const std::string& environment) {
    for (const Writer& w : writers) {
        SCOPED_TRACE(w.what);
        const CliResult r = run_cli(w.args, scratch, environment);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_EQ(r.err.rfind("pliant: error: ", 0), 0U) << r.err;
        EXPECT_NE(r.err.find(w.output), std::string::npos) << r.err;
        EXPECT_EQ(files_under(ro), std::vector<std::string>{});
    }
}

fs::path make_dataset(const ScratchDir& scratch, const fs::path& volume) {
    const CliResult r = run_cli(
        "dataset " + quoted(volume) + " --views 4 --size 16x16 -o " + quoted(scratch / "ds"),
        scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return scratch / "ds";
}

TEST(Faults, ReadOnlyFileSystemIsAClearErrorAndWritesNothing) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 16);
    const fs::path scene = make_cloth_scene(scratch);
    const fs::path dataset = make_dataset(scratch, volume);
    const fs::path ro = scratch / "ro";
    const Tmpfs mount(ro, "size=1m", /*read_only=*/true);
    if (!mount.ok()) {
        GTEST_SKIP() << "cannot mount a read-only tmpfs (needs root): " << mount.why();
    }
    expect_clear_errors(writers_into(ro, volume, scene, dataset), ro, scratch, "");
}

TEST(Faults, DirectoryWithoutWritePermissionIsAClearErrorAndWritesNothing) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 16);
    const fs::path scene = make_cloth_scene(scratch);
    const fs::path dataset = make_dataset(scratch, volume);
    const fs::path ro = scratch / "ro";
    fs::create_directories(ro);
    fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                            fs::perms::group_exec | fs::perms::others_read |
                            fs::perms::others_exec);
    std::string environment;
    if (::geteuid() == 0) {
        // Root ignores the mode: run as nobody, who can read the inputs (0644 under a 0755
        // scratch directory) but not write into the 0555 one.
        if (std::system("setpriv --reuid=65534 --regid=65534 --clear-groups true") != 0) {
            GTEST_SKIP() << "running as root and `setpriv --reuid=65534` does not work here";
        }
        environment = "setpriv --reuid=65534 --regid=65534 --clear-groups";
    }
    expect_clear_errors(writers_into(ro, volume, scene, dataset), ro, scratch, environment);
}

// ---------------------------------------------------------------------------------------------
// Inputs that change while they are read.

// Rewrites `path` in place over and over while it lives, as another program rewriting the file
// would: truncated to half its size, then written whole again from the start. A reader sees it
// whole, cut short, or growing back.
class Rewriter {
public:
    explicit Rewriter(const fs::path& path) {
        const std::string content = read_text(path);
        m_pid = ::fork();
        if (m_pid == 0) {
            const int fd = ::open(path.c_str(), O_WRONLY);
            const auto half = static_cast<off_t>(content.size() / 2);
            while (fd >= 0) {
                if (::ftruncate(fd, half) != 0 ||
                    ::pwrite(fd, content.data(), content.size(), 0) < 0) {
                    break;
                }
            }
            ::_exit(0);
        }
    }
    Rewriter(const Rewriter&) = delete;
    Rewriter& operator=(const Rewriter&) = delete;
    ~Rewriter() {
        if (m_pid > 0) {
            ::kill(m_pid, SIGKILL);
            ::waitpid(m_pid, nullptr, 0);
        }
    }

private:
    pid_t m_pid = -1;
};

// Runs `args` `runs` times while `input` is being rewritten. Each run must either succeed with
// its output complete, or fail with `pliant: error:`, exit 1 and no output. Returns how many
// failed (the rest succeeded).
int run_while_rewritten(const ScratchDir& scratch, const fs::path& input, const std::string& args,
                        const fs::path& out, int runs) {
    const Rewriter rewriter(input);
    int failed = 0;
    std::set<std::string> errors;
    for (int i = 0; i < runs; ++i) {
        SCOPED_TRACE("run " + std::to_string(i));
        fs::remove_all(out);
        fs::create_directories(out);
        const CliResult r = run_cli(args, scratch, "timeout 60");
        if (r.exit_code == 0) {
            EXPECT_FALSE(files_under(out).empty());
            EXPECT_EQ(incomplete_outputs(out), std::vector<std::string>{});
        } else {
            ++failed;
            errors.insert(r.err.substr(0, r.err.find('\n')));
            EXPECT_EQ(r.exit_code, 1) << r.err;
            EXPECT_NE(r.err.find("pliant: error: "), std::string::npos) << r.err;
            EXPECT_EQ(files_under(out), std::vector<std::string>{}) << r.err;
        }
    }
    std::printf("%d of %d runs refused the input, the others read it whole\n", failed, runs);
    for (const std::string& e : errors) {
        std::printf("  %s\n", e.c_str());
    }
    return failed;
}

TEST(Faults, VolumeRewrittenWhileDeformReadsItGivesAResultOrAClearError) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 32);
    run_while_rewritten(scratch, volume,
                        "deform " + quoted(volume) + " --driver rotate --frames 1 -o " +
                            quoted(scratch / "out" / "d.nrrd"),
                        scratch / "out", 20);
}

TEST(Faults, DatasetImageRewrittenWhileNerfTrainReadsItGivesAResultOrAClearError) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 16);
    const fs::path dataset = make_dataset(scratch, volume);
    const fs::path image = dataset / "train" / "r_1.png";
    ASSERT_TRUE(fs::exists(image));
    run_while_rewritten(scratch, image,
                        "nerf train " + quoted(dataset / "transforms_train.json") +
                            " --iterations 5 --resolution 8 -o " +
                            quoted(scratch / "out" / "n.nrrd"),
                        scratch / "out", 10);
}

TEST(Faults, ObstacleMeshRewrittenWhileClothReadsItGivesAResultOrAClearError) {
    const ScratchDir scratch;
    const fs::path scene = make_cloth_scene(scratch);
    run_while_rewritten(
        scratch, scratch / "box.obj",
        "cloth " + quoted(scene) + " --frames 1 --no-preview --out " + quoted(scratch / "out"),
        scratch / "out", 20);
}

// A FIFO (or another special file) as an input: refused at once, not waited on.
TEST(Faults, FifoInputsAreRefusedWithoutWaiting) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 16);
    const fs::path dataset = make_dataset(scratch, volume);
    const fs::path scene = make_cloth_scene(scratch, "fifo.obj");
    for (const char* name : {"fifo.nrrd", "fifo.obj", "fifo.png"}) {
        ASSERT_EQ(::mkfifo((scratch / name).c_str(), 0644), 0) << std::strerror(errno);
    }
    nlohmann::json transforms = nlohmann::json::parse(read_text(dataset / "transforms_train.json"));
    transforms["frames"][0]["file_path"] = (scratch / "fifo.png").string();
    write_text(dataset / "transforms_train.json", transforms.dump(2));
    fs::create_directories(scratch / "out");
    const Writer readers[] = {
        {"deform",
         "deform " + quoted(scratch / "fifo.nrrd") + " --driver rotate --frames 1 -o " +
             quoted(scratch / "out" / "d.nrrd"),
         "fifo.nrrd"},
        {"nerf train",
         "nerf train " + quoted(dataset / "transforms_train.json") +
             " --iterations 5 --resolution 8 -o " + quoted(scratch / "out" / "n.nrrd"),
         "fifo.png"},
        {"cloth",
         "cloth " + quoted(scene) + " --frames 1 --no-preview --out " + quoted(scratch / "out"),
         "fifo.obj"},
    };
    for (const Writer& w : readers) {
        SCOPED_TRACE(w.what);
        const CliResult r = run_cli(w.args, scratch, "timeout 60");
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_EQ(r.err.rfind("pliant: error: ", 0), 0U) << r.err;
        EXPECT_NE(r.err.find(w.output), std::string::npos) << r.err;
        EXPECT_EQ(files_under(scratch / "out"), std::vector<std::string>{});
    }
}

// ---------------------------------------------------------------------------------------------
// SIGKILL at seeded random moments.

// Runs `args` (outputs under `out`) once uninterrupted as the reference, then for each of 10
// seeds: kills it at a random moment within the first 4/5 of the reference run, checks what it
// left, runs it again to the end into the same directory and checks that the outputs are the
// reference's.
void kill_at_random_points(const ScratchDir& scratch, const std::vector<std::string>& args,
                           const fs::path& out) {
    fs::create_directories(out);
    const auto start = std::chrono::steady_clock::now();
    const CliResult reference = run_cli(shell_args(args), scratch);
    const auto duration = std::chrono::duration_cast<std::chrono::microseconds>(
        std::chrono::steady_clock::now() - start);
    ASSERT_EQ(reference.exit_code, 0) << reference.err;
    const std::map<std::string, std::string> expected = deterministic_outputs(out);
    std::set<std::string> final_names;
    for (const std::string& name : files_under(out)) {
        final_names.insert(name);
    }
    int killed = 0;
    for (unsigned seed = 1; seed <= 10; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        fs::remove_all(out);
        fs::create_directories(out);
        std::mt19937 random(seed);
        const auto delay = std::chrono::microseconds(
            std::uniform_int_distribution<std::int64_t>(0, duration.count() * 4 / 5)(random));
        killed += run_and_kill(args, scratch / "killed.log", delay) ? 1 : 0;
        EXPECT_EQ(incomplete_outputs(out), std::vector<std::string>{});
        // A later run over what the killed one left.
        const CliResult again = run_cli(shell_args(args), scratch);
        ASSERT_EQ(again.exit_code, 0) << again.err;
        EXPECT_EQ(incomplete_outputs(out), std::vector<std::string>{});
        EXPECT_EQ(deterministic_outputs(out), expected);
        for (const std::string& name : files_under(out)) {
            EXPECT_TRUE(final_names.count(name) == 1 || is_temporary(name)) << name;
        }
    }
    // The delays fall within the run: most kills land before it ends.
    EXPECT_GT(killed, 0);
    std::printf("killed %d of 10 runs before they ended (reference run: %lld ms)\n", killed,
                static_cast<long long>(duration.count() / 1000));
}

TEST(Faults, ClothKilledAtRandomPointsLeavesOnlyCompleteFiles) {
    const ScratchDir scratch;
    const fs::path scene = make_cloth_scene(scratch);
    kill_at_random_points(
        scratch,
        {"cloth", scene.string(), "--preview-size", "64x48", "--out", (scratch / "out").string()},
        scratch / "out");
}

TEST(Faults, DeformKilledAtRandomPointsLeavesOnlyCompleteFiles) {
    if (!io::ffmpeg_available()) {
        GTEST_SKIP() << "ffmpeg is not installed: no MP4 to write";
    }
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 24);
    kill_at_random_points(scratch,
                          {"deform", volume.string(), "--driver", "twist", "--frames", "6", "-o",
                           (scratch / "out" / "d.nrrd").string(), "--render",
                           (scratch / "out" / "d.mp4").string(), "--size", "32x32"},
                          scratch / "out");
}

TEST(Faults, RenderOrbitKilledAtRandomPointsLeavesOnlyCompleteFiles) {
    if (!io::ffmpeg_available()) {
        GTEST_SKIP() << "ffmpeg is not installed: no MP4 to write";
    }
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 32);
    kill_at_random_points(scratch,
                          {"render", volume.string(), "--size", "48x48", "--orbit", "12", "-o",
                           (scratch / "out" / "o.mp4").string()},
                          scratch / "out");
}

TEST(Faults, VolumeConvertKilledAtRandomPointsLeavesOnlyCompleteFiles) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 96);
    kill_at_random_points(
        scratch, {"volume", "convert", volume.string(), (scratch / "out" / "v.nii.gz").string()},
        scratch / "out");
}

// ---------------------------------------------------------------------------------------------
// A full disk: a 64 KiB tmpfs.

TEST(Faults, FullTmpfsStopsWithAClearErrorAndNoPartialFile) {
    const ScratchDir scratch;
    const fs::path volume = make_volume(scratch, 64);  // 1 MiB of float voxels
    const fs::path scene = make_cloth_scene(scratch);
    const fs::path full = scratch / "full";
    const Tmpfs mount(full, "size=64k", /*read_only=*/false);
    if (!mount.ok()) {
        GTEST_SKIP() << "cannot mount a small tmpfs (needs root): " << mount.why();
    }
    const std::string in = quoted(volume);
    const Writer writers[] = {
        {"volume convert", "volume convert " + in + " " + quoted(full / "v.nrrd"), "v.nrrd"},
        {"render", "render " + in + " --size 1024x1024 -o " + quoted(full / "r.png"), "r.png"},
        {"deform", "deform " + in + " --driver rotate --frames 1 -o " + quoted(full / "d.nrrd"),
         "d.nrrd"},
    };
    for (const Writer& w : writers) {
        SCOPED_TRACE(w.what);
        const CliResult r = run_cli(w.args, scratch);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_EQ(r.err.rfind("pliant: error: ", 0), 0U) << r.err;
        EXPECT_NE(r.err.find(w.output), std::string::npos) << r.err;
        EXPECT_EQ(files_under(full), std::vector<std::string>{});
    }
    // Cloth: 40 frames of 289 vertices (about 12 KB each) do not fit. The run stops at the
    // frame that did not fit; the frames before it are complete and stats.json lists them.
    const CliResult r =
        run_cli("cloth " + quoted(scene) + " --frames 40 --no-preview --out " + quoted(full / "c"),
                scratch);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("pliant: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("frame_00"), std::string::npos) << r.err;
    EXPECT_EQ(incomplete_outputs(full / "c"), std::vector<std::string>{});
    for (const std::string& name : files_under(full / "c")) {
        EXPECT_FALSE(is_temporary(name)) << name;
    }
    ASSERT_TRUE(fs::exists(full / "c" / "stats.json"));
    const nlohmann::json stats = nlohmann::json::parse(read_text(full / "c" / "stats.json"));
    const std::size_t frames = stats.at("frames").size();
    EXPECT_GT(frames, 0U);
    EXPECT_LT(frames, 40U);
    EXPECT_EQ(stats.at("error").at("frame").get<std::size_t>(), frames + 1);
    // frame_0000 … frame_<frames>, nothing after.
    EXPECT_EQ(files_under(full / "c" / "frames").size(), frames + 1);
}

}  // namespace
}  // namespace pliant::test
