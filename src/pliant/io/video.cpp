#include "pliant/io/video.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <system_error>

#include "pliant/core/error.hpp"
#include "pliant/io/child_process.hpp"

extern char** environ;  // NOLINT: POSIX, passed to the child process

namespace pliant::io {

namespace {

constexpr int MAX_SIZE = 16384;
constexpr std::size_t STDERR_TAIL_BYTES = 2000;

std::filesystem::path temporary_path_for(const std::filesystem::path& path) {
    static std::atomic<std::uint64_t> counter{0};
    std::filesystem::path tmp = path;
    tmp += fmt::format(".tmp-{}-{}", static_cast<long>(::getpid()),
                       counter.fetch_add(1, std::memory_order_relaxed));
    return tmp;
}

std::string errno_text(int error) {
    return std::strerror(error);
}

}  // namespace

std::filesystem::path find_ffmpeg() {
    return find_program("ffmpeg");
}

bool ffmpeg_available() {
    return !find_ffmpeg().empty();
}

VideoWriter::VideoWriter(std::filesystem::path path, int width, int height, double fps,
                         VideoOptions options)
    : m_path(std::move(path)), m_width(width), m_height(height) {
    // Step 1: arguments, then the environment (ffmpeg, target directory).
    if (width < 1 || width > MAX_SIZE || height < 1 || height > MAX_SIZE) {
        throw InvalidInput(
            fmt::format("VideoWriter: {}: frame size {} x {}, expected width and "
                        "height in [1, {}]",
                        m_path.string(), width, height, MAX_SIZE));
    }
    if (!(fps > 0.0 && fps <= 1000.0)) {
        throw InvalidInput(fmt::format("VideoWriter: {}: fps {}, expected a value in (0, 1000]",
                                       m_path.string(), fps));
    }
    if (options.crf < 0 || options.crf > 51) {
        throw InvalidInput(
            fmt::format("VideoWriter: {}: crf {}, expected 0 to 51", m_path.string(), options.crf));
    }
    if (!m_path.has_filename()) {
        throw IoError(
            fmt::format("{}: cannot write a video, expected a file name, got a "
                        "directory path",
                        m_path.string()));
    }
    const std::filesystem::path ffmpeg = find_ffmpeg();
    if (ffmpeg.empty()) {
        throw IoError(
            fmt::format("{}: cannot write MP4: ffmpeg not found on PATH (install the "
                        "Debian package ffmpeg, see scripts/install-deps)",
                        m_path.string()));
    }
    const std::filesystem::path dir =
        m_path.parent_path().empty() ? std::filesystem::path(".") : m_path.parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        throw IoError(fmt::format("{}: cannot write a video, directory {} does not exist",
                                  m_path.string(), dir.string()));
    }
    m_encoded_width = width + width % 2;
    m_encoded_height = height + height % 2;
    m_tmp_path = temporary_path_for(m_path);

    // Step 2: ffmpeg's standard error → an unlinked temporary file we can read back.
    std::string stderr_name = (std::filesystem::temp_directory_path() / "pliant-ffmpeg-XXXXXX");
    m_stderr_fd = ::mkostemp(stderr_name.data(), O_CLOEXEC);
    if (m_stderr_fd < 0) {
        const int error = errno;
        throw IoError(fmt::format("{}: cannot create a temporary file for ffmpeg's messages: {}",
                                  m_path.string(), errno_text(error)));
    }
    ::unlink(stderr_name.c_str());

    // Step 3: a socket pair for standard input (send with MSG_NOSIGNAL: no SIGPIPE).
    int sockets[2] = {-1, -1};
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
        const int error = errno;
        ::close(m_stderr_fd);
        m_stderr_fd = -1;
        throw IoError(fmt::format("{}: cannot create ffmpeg's input socket: {}", m_path.string(),
                                  errno_text(error)));
    }
    ::shutdown(sockets[0], SHUT_RD);  // we only write
    m_input_fd = sockets[0];

    // Step 4: spawn ffmpeg with an argument vector (no shell). "file:" keeps a name that starts
    // with '-' or contains ':' from being read as an option or a protocol.
    const std::vector<std::string> args = {ffmpeg.string(),
                                           "-hide_banner",
                                           "-nostats",
                                           "-loglevel",
                                           "error",
                                           "-y",
                                           "-f",
                                           "rawvideo",
                                           "-pix_fmt",
                                           "rgb24",
                                           "-s",
                                           fmt::format("{}x{}", m_encoded_width, m_encoded_height),
                                           "-r",
                                           fmt::format("{}", fps),
                                           "-i",
                                           "-",
                                           "-an",
                                           "-c:v",
                                           "libx264",
                                           "-pix_fmt",
                                           "yuv420p",
                                           "-crf",
                                           fmt::format("{}", options.crf),
                                           "-movflags",
                                           "+faststart",
                                           "-f",
                                           "mp4",
                                           "file:" + m_tmp_path.string()};
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (const std::string& a : args) {
        argv.push_back(const_cast<char*>(a.c_str()));
    }
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, sockets[1], STDIN_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, m_stderr_fd, STDERR_FILENO);
    // ffmpeg gets its own process group: a Ctrl-C in the terminal (SIGINT to the foreground
    // group) reaches pliant, which stops cleanly and finishes the video, and not ffmpeg.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
    pid_t pid = -1;
    const int spawn_error =
        ::posix_spawn(&pid, ffmpeg.c_str(), &actions, &attributes, argv.data(), environ);
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    ::close(sockets[1]);
    if (spawn_error != 0) {
        close_input();
        ::close(m_stderr_fd);
        m_stderr_fd = -1;
        throw IoError(fmt::format("{}: cannot start {}: {}", m_path.string(), ffmpeg.string(),
                                  errno_text(spawn_error)));
    }
    m_pid = pid;
}

VideoWriter::~VideoWriter() {
    if (m_pid > 0) {
        close_input();
        reap(true);
        remove_temporary();
    }
    close_input();
    if (m_stderr_fd >= 0) {
        ::close(m_stderr_fd);
    }
}

void VideoWriter::write(const render::Image& frame) {
    if (m_pid <= 0) {
        throw IoError(
            fmt::format("{}: the video writer is closed (finished or failed)", m_path.string()));
    }
    if (frame.width != m_width || frame.height != m_height || !frame.is_consistent()) {
        throw InvalidInput(fmt::format(
            "VideoWriter::write: {}: frame {} is {} x {} ({} bytes), "
            "expected {} x {} ({} bytes)",
            m_path.string(), m_num_frames, frame.width, frame.height, frame.pixels.size(), m_width,
            m_height, 3 * static_cast<std::size_t>(m_width) * static_cast<std::size_t>(m_height)));
    }
    const std::uint8_t* data = frame.pixels.data();
    std::size_t size = frame.pixels.size();
    if (m_encoded_width != m_width || m_encoded_height != m_height) {
        // Repeat the last column and row up to the even size.
        const auto row_in = 3 * static_cast<std::size_t>(m_width);
        const auto row_out = 3 * static_cast<std::size_t>(m_encoded_width);
        m_padded.resize(row_out * static_cast<std::size_t>(m_encoded_height));
        for (int y = 0; y < m_encoded_height; ++y) {
            const std::uint8_t* src =
                frame.pixels.data() + row_in * static_cast<std::size_t>(std::min(y, m_height - 1));
            std::uint8_t* dst = m_padded.data() + row_out * static_cast<std::size_t>(y);
            std::memcpy(dst, src, row_in);
            if (m_encoded_width != m_width) {
                std::memcpy(dst + row_in, src + row_in - 3, 3);
            }
        }
        data = m_padded.data();
        size = m_padded.size();
    }
    while (size > 0) {
        const ssize_t n = ::send(m_input_fd, data, size, MSG_NOSIGNAL);
        if (n < 0) {
            const int error = errno;
            if (error == EINTR) {
                continue;
            }
            fail(fmt::format("ffmpeg stopped reading frames at frame {} ({})", m_num_frames,
                             errno_text(error)));
        }
        data += n;
        size -= static_cast<std::size_t>(n);
    }
    ++m_num_frames;
}

void VideoWriter::finish() {
    if (m_pid <= 0) {
        throw IoError(
            fmt::format("{}: the video writer is closed (finished or failed)", m_path.string()));
    }
    if (m_num_frames == 0) {
        close_input();
        reap(true);
        remove_temporary();
        throw InvalidInput(
            fmt::format("VideoWriter::finish: {}: no frames were written, expected "
                        "at least 1",
                        m_path.string()));
    }
    close_input();
    const int status = reap(false);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        fail(WIFEXITED(status) ? fmt::format("ffmpeg exited with status {}", WEXITSTATUS(status))
                               : fmt::format("ffmpeg ended by signal {}",
                                             WIFSIGNALED(status) ? WTERMSIG(status) : -1));
    }
    std::error_code ec;
    std::filesystem::rename(m_tmp_path, m_path, ec);
    if (ec) {
        remove_temporary();
        throw IoError(fmt::format("{}: cannot replace the file with {}: {}", m_path.string(),
                                  m_tmp_path.string(), ec.message()));
    }
}

int VideoWriter::reap(bool kill_first) {
    int status = -1;
    if (m_pid > 0) {
        if (kill_first) {
            ::kill(m_pid, SIGKILL);
        }
        while (::waitpid(m_pid, &status, 0) < 0 && errno == EINTR) {
        }
        m_pid = -1;
    }
    return status;
}

void VideoWriter::fail(const std::string& what) {
    close_input();
    reap(true);
    remove_temporary();
    const std::string tail = stderr_tail();
    throw IoError(fmt::format("{}: writing MP4 through ffmpeg failed: {}{}{}", m_path.string(),
                              what, tail.empty() ? "" : "; ffmpeg says: ", tail));
}

std::string VideoWriter::stderr_tail() const {
    if (m_stderr_fd < 0) {
        return {};
    }
    const off_t size = ::lseek(m_stderr_fd, 0, SEEK_END);
    if (size <= 0) {
        return {};
    }
    const auto count = std::min<std::size_t>(static_cast<std::size_t>(size), STDERR_TAIL_BYTES);
    std::string text(count, '\0');
    const ssize_t n = ::pread(m_stderr_fd, text.data(), count, size - static_cast<off_t>(count));
    text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) {
        text.pop_back();
    }
    return text;
}

void VideoWriter::close_input() {
    if (m_input_fd >= 0) {
        ::close(m_input_fd);
        m_input_fd = -1;
    }
}

void VideoWriter::remove_temporary() {
    std::error_code ignored;
    std::filesystem::remove(m_tmp_path, ignored);
}

}  // namespace pliant::io
