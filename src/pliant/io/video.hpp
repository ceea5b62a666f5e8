// MP4 video through the ffmpeg command-line tool (Debian package `ffmpeg`, optional at run time).
//
// ffmpeg_available(): true when an executable regular file named `ffmpeg` is found in a directory
// of $PATH (empty entries are ignored; without $PATH, /usr/local/bin:/usr/bin:/bin). Nothing is
// run and no shell is involved. find_ffmpeg() returns that path ("" when absent).
//
// VideoWriter(path, width, height, fps) starts ffmpeg (posix_spawn with an argument vector, no
// shell) reading raw RGB24 frames from a socket on its standard input:
//   ffmpeg -hide_banner -nostats -loglevel error -y -f rawvideo -pix_fmt rgb24 -s WxH -r FPS -i -
//          -an -c:v libx264 -pix_fmt yuv420p -crf 20 -movflags +faststart -f mp4 file:<tmp>
// where <tmp> is `<path>.tmp-<pid>-<n>` beside the target (same file system, so the final rename
// is atomic). The container is always MP4, whatever the extension of `path`.
//   - Odd sizes: libx264 with yuv420p needs even dimensions, so a width × height stream with an
//     odd side is encoded at the next even size, the last column and/or row of every frame
//     repeated (the video is (width + width % 2) × (height + height % 2)).
//   - write(frame): frame must be a render::Image of exactly width × height (InvalidInput
//     otherwise). Blocks while ffmpeg encodes (the socket buffer is small).
//   - finish(): closes ffmpeg's input, waits for it, checks that it exited with status 0, and
//     renames the temporary file onto `path`. At least one frame must have been written
//     (InvalidInput otherwise, and nothing is written).
//   - Errors: IoError "<path>: …" when ffmpeg is not on $PATH, the target's directory does not
//     exist, ffmpeg cannot be started, ffmpeg exits early or with a nonzero status (the message
//     carries the tail of ffmpeg's standard error), or the rename fails. After any error the
//     writer is closed: ffmpeg is reaped, the temporary file removed, later calls throw.
//   - A writer destroyed before finish() (e.g. during stack unwinding) kills ffmpeg (SIGKILL),
//     reaps it and removes the temporary file: no partial video is left at `path`.
// ffmpeg's standard error goes to an unlinked temporary file (no pipe to drain, so no deadlock);
// its standard output to /dev/null. Writes use send(MSG_NOSIGNAL), so an ffmpeg that dies does not
// raise SIGPIPE in the caller. Not thread safe; one writer per thread.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pliant/render/image.hpp"

namespace pliant::io {

std::filesystem::path find_ffmpeg();
bool ffmpeg_available();

struct VideoOptions {
    int crf = 20;  // libx264 constant rate factor, 0 (lossless) … 51
};

class VideoWriter {
public:
    // width, height in [1, 16384]; fps finite in (0, 1000]. Throws InvalidInput for those, IoError
    // as listed above.
    VideoWriter(std::filesystem::path path, int width, int height, double fps,
                VideoOptions options = {});
    ~VideoWriter();
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    void write(const render::Image& frame);
    void finish();

    int width() const { return m_width; }
    int height() const { return m_height; }
    std::int64_t num_frames() const { return m_num_frames; }
    bool is_open() const { return m_pid > 0; }
    const std::filesystem::path& path() const { return m_path; }

private:
    // Kills (when `kill_first`) or waits for ffmpeg; returns its wait status.
    int reap(bool kill_first);
    // Closes everything after a failure and throws IoError with ffmpeg's stderr tail.
    [[noreturn]] void fail(const std::string& what);
    std::string stderr_tail() const;
    void close_input();
    void remove_temporary();

    std::filesystem::path m_path;
    std::filesystem::path m_tmp_path;
    int m_width = 0, m_height = 0;
    int m_encoded_width = 0, m_encoded_height = 0;
    pid_t m_pid = -1;
    int m_input_fd = -1;   // our end of ffmpeg's standard input
    int m_stderr_fd = -1;  // ffmpeg's standard error (unlinked temporary file)
    std::int64_t m_num_frames = 0;
    std::vector<std::uint8_t> m_padded;  // frame buffer for odd sizes
};

}  // namespace pliant::io
