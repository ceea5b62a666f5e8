#include "pliant/io/video.hpp"

#include <gtest/gtest.h>
#include <stdio.h>
#include <stdlib.h>

#include <cstdio>
#include <string>

#include "pliant/core/error.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using render::Image;
using render::Rgb8;
using test::expect_io_error;
using test::TempDir;

Image frame(int w, int h, int t) {
    Image image(w, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            image.set(x, y,
                      {static_cast<std::uint8_t>(x * 4 + t * 9), static_cast<std::uint8_t>(y * 4),
                       static_cast<std::uint8_t>(t * 20)});
        }
    }
    return image;
}

// Runs ffprobe on `path` and returns its output: "<width>,<height>,<frames>" ("" on failure).
// The test's own temporary path is passed in single quotes (it holds no quote).
std::string probe(const std::filesystem::path& path) {
    const std::string command =
        "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
        "stream=width,height,nb_read_frames -of csv=p=0 '" +
        path.string() + "' 2>/dev/null";
    FILE* pipe = ::popen(command.c_str(), "r");
    if (pipe == nullptr) {
        return {};
    }
    std::string out;
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) {
        out += buffer;
    }
    ::pclose(pipe);
    while (!out.empty() && (out.back() == '\n' || out.back() == ',')) {
        out.pop_back();
    }
    return out;
}

#define PLIANT_SKIP_WITHOUT_FFMPEG()                                     \
    if (!ffmpeg_available()) {                                           \
        GTEST_SKIP() << "ffmpeg is not on PATH (Debian package ffmpeg)"; \
    }

TEST(Video, WritesAnMp4WithEveryFrame) {
    PLIANT_SKIP_WITHOUT_FFMPEG();
    const TempDir dir;
    {
        VideoWriter writer(dir / "out.mp4", 64, 48, 24.0);
        for (int t = 0; t < 10; ++t) {
            writer.write(frame(64, 48, t));
        }
        EXPECT_EQ(writer.num_frames(), 10);
        writer.finish();
        EXPECT_FALSE(writer.is_open());
    }
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.mp4"});
    EXPECT_EQ(probe(dir / "out.mp4"), "64,48,10");
}

TEST(Video, OddSizesArePaddedToEven) {
    PLIANT_SKIP_WITHOUT_FFMPEG();
    const TempDir dir;
    VideoWriter writer(dir / "odd.mp4", 33, 17, 12.5);
    for (int t = 0; t < 3; ++t) {
        writer.write(frame(33, 17, t));
    }
    writer.finish();
    EXPECT_EQ(probe(dir / "odd.mp4"), "34,18,3");
}

TEST(Video, UnfinishedWriterLeavesNoFile) {
    PLIANT_SKIP_WITHOUT_FFMPEG();
    const TempDir dir;
    {
        VideoWriter writer(dir / "partial.mp4", 32, 32, 24.0);
        writer.write(frame(32, 32, 0));
        writer.write(frame(32, 32, 1));
    }
    EXPECT_TRUE(dir.entries().empty());
    // An exception thrown while writing unwinds the same way.
    try {
        VideoWriter writer(dir / "thrown.mp4", 32, 32, 24.0);
        writer.write(frame(32, 32, 0));
        writer.write(frame(16, 32, 1));  // wrong size
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("frame 1 is 16 x 32"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Video, FinishWithoutFramesIsAnErrorAndLeavesNoFile) {
    PLIANT_SKIP_WITHOUT_FFMPEG();
    const TempDir dir;
    VideoWriter writer(dir / "empty.mp4", 32, 32, 24.0);
    EXPECT_THROW(writer.finish(), InvalidInput);
    EXPECT_TRUE(dir.entries().empty());
    EXPECT_THROW(writer.write(frame(32, 32, 0)), IoError);  // closed
}

TEST(Video, FfmpegFailureReportsItsMessage) {
    PLIANT_SKIP_WITHOUT_FFMPEG();
    const TempDir dir;
    // The target directory exists when ffmpeg starts but is gone when it opens its output after
    // the first frame: ffmpeg fails, and the error carries its stderr.
    const std::filesystem::path sub = dir / "sub";
    std::filesystem::create_directory(sub);
    VideoWriter writer(sub / "x.mp4", 32, 32, 24.0);
    std::filesystem::remove(sub);
    const std::string message = expect_io_error(
        [&] {
            for (int t = 0; t < 200; ++t) {
                writer.write(frame(32, 32, t));
            }
            writer.finish();
        },
        {"x.mp4", "ffmpeg"});
    EXPECT_NE(message.find("ffmpeg says"), std::string::npos) << message;
    EXPECT_FALSE(writer.is_open());
}

TEST(Video, BadArgumentsAndMissingDirectory) {
    const TempDir dir;
    EXPECT_THROW(VideoWriter(dir / "a.mp4", 0, 10, 24.0), InvalidInput);
    EXPECT_THROW(VideoWriter(dir / "a.mp4", 10, 10, 0.0), InvalidInput);
    EXPECT_THROW(VideoWriter(dir / "a.mp4", 10, 10, NAN), InvalidInput);
    if (ffmpeg_available()) {
        expect_io_error([&] { VideoWriter(dir / "no" / "a.mp4", 10, 10, 24.0); },
                        {"does not exist"});
    }
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Video, FfmpegIsLookedUpOnPath) {
    const char* saved = std::getenv("PATH");
    const std::string old = saved != nullptr ? saved : "";
    ::setenv("PATH", "/nonexistent-pliant-dir", 1);
    EXPECT_FALSE(ffmpeg_available());
    const TempDir dir;
    expect_io_error([&] { VideoWriter(dir / "a.mp4", 10, 10, 24.0); }, {"ffmpeg not found"});
    ::setenv("PATH", old.c_str(), 1);
    EXPECT_EQ(ffmpeg_available(), !find_ffmpeg().empty());
}

}  // namespace
}  // namespace pliant::io
