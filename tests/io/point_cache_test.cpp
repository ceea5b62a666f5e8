// Point caches, read back with independent readers written here from the formats (header, times,
// size and every value; tests/io/point_cache_bytes.hpp): MDD, big-endian (LightWave's layout, as
// Blender's import_mdd.py reads it), and PC2, little-endian. Bad arguments and failures leave no
// file and keep an earlier one whole.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/point_cache_bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/mdd.hpp"
#include "pliant/io/pc2.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_cache_points;
using test::fill_constant;
using test::float_at;
using test::int_at;
using test::read_bytes;
using test::RecordingSource;
using test::TempDir;
using test::write_bytes;

// The message of the InvalidInput that `call` throws ("no error" if none).
template <typename Call>
std::string invalid_input_message(const Call& call) {
    try {
        call();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "no error";
}

// What both writers refuse, checked through write(path, num_points, num_frames, source): counts
// outside [0, 2^31 - 1] and a non-finite position (with their messages) leave no file; a failure
// mid-stream keeps an earlier file whole and leaves no temporary; a missing directory is IoError.
template <typename Write>
void expect_refusals_leave_no_file(const std::string& name, const std::string& frame_word,
                                   const Write& write) {
    const TempDir dir;
    const auto path = dir / name;
    const auto fill = fill_constant;
    EXPECT_THROW(write(path, -1, 2, fill), InvalidInput);
    EXPECT_THROW(write(path, 2, std::int64_t{1} << 31, fill), InvalidInput);
    EXPECT_EQ(invalid_input_message([&] { write(path, 5, -2, fill); }),
              fmt::format("{}: expected at most 2^31 - 1 points and {}s, got 5 points and -2 {}s",
                          path.string(), frame_word, frame_word));
    EXPECT_TRUE(dir.entries().empty());

    write_bytes(path, "earlier");
    const auto not_finite_at_3 = [](std::int64_t f, std::span<Vec3f> out) {
        for (Vec3f& p : out) {
            p = {0.0f, 0.0f, f == 3 ? std::numeric_limits<float>::infinity() : 1.0f};
        }
    };
    EXPECT_EQ(invalid_input_message([&] { write(path, 3, 5, not_finite_at_3); }),
              fmt::format("{}: {} 3: a position is not finite", path.string(), frame_word));
    const auto killed_at_2 = [](std::int64_t f, std::span<Vec3f>) {
        if (f == 2) {
            throw std::runtime_error("killed");
        }
    };
    EXPECT_THROW(write(path, 3, 5, killed_at_2), std::runtime_error);
    EXPECT_EQ(read_bytes(path), "earlier");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{name}));
    EXPECT_THROW(write(dir / "missing" / name, 1, 1, fill), IoError);
}

constexpr std::endian MDD_ORDER = std::endian::big;

TEST(Mdd, HeaderTimesAndFramesReadBack) {
    const TempDir dir;
    constexpr std::int64_t FRAMES = 4;
    constexpr std::int64_t POINTS = 5;
    RecordingSource source{POINTS, {}};
    write_mdd(dir / "c.mdd", POINTS, FRAMES, 24.0, source);
    EXPECT_EQ(source.asked, (std::vector<std::int64_t>{0, 1, 2, 3}));
    const std::string bytes = read_bytes(dir / "c.mdd");
    ASSERT_EQ(bytes.size(), 8u + 4u * FRAMES + 12u * FRAMES * POINTS);
    EXPECT_EQ(int_at(bytes, 0, MDD_ORDER), FRAMES);
    EXPECT_EQ(int_at(bytes, 4, MDD_ORDER), POINTS);
    for (std::int64_t f = 0; f < FRAMES; ++f) {
        EXPECT_EQ(float_at(bytes, 8 + 4 * f, MDD_ORDER), static_cast<float>(f / 24.0)) << f;
    }
    expect_cache_points(bytes, 8 + 4 * FRAMES, FRAMES, POINTS, MDD_ORDER);
}

TEST(Mdd, EmptyCache) {
    const TempDir dir;
    write_mdd(dir / "e.mdd", 0, 0, 30.0, [](std::int64_t, std::span<Vec3f>) {});
    EXPECT_EQ(read_bytes(dir / "e.mdd"), std::string(8, '\0'));
}

TEST(Mdd, BadFrameRateLeavesNoFile) {
    const TempDir dir;
    const auto path = dir / "c.mdd";
    const auto fill = fill_constant;
    EXPECT_THROW(write_mdd(path, 2, 2, 0.0, fill), InvalidInput);
    EXPECT_THROW(write_mdd(path, 2, 2, std::numeric_limits<double>::quiet_NaN(), fill),
                 InvalidInput);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Mdd, BadArgumentsAndFailuresLeaveNoFile) {
    expect_refusals_leave_no_file(
        "c.mdd", "frame", [](const auto& path, auto points, auto frames, const auto& source) {
            write_mdd(path, points, frames, 24.0, source);
        });
}

constexpr std::endian PC2_ORDER = std::endian::little;

TEST(Pc2, HeaderAndSamplesReadBack) {
    const TempDir dir;
    constexpr std::int64_t SAMPLES = 3;
    constexpr std::int64_t POINTS = 4;
    RecordingSource source{POINTS, {}};
    write_pc2(dir / "c.pc2", POINTS, SAMPLES, 7.0, source);
    EXPECT_EQ(source.asked, (std::vector<std::int64_t>{0, 1, 2}));
    const std::string bytes = read_bytes(dir / "c.pc2");
    ASSERT_EQ(bytes.size(), 32u + 12u * SAMPLES * POINTS);
    EXPECT_EQ(bytes.substr(0, 12), std::string("POINTCACHE2\0", 12));
    EXPECT_EQ(int_at(bytes, 12, PC2_ORDER), 1);
    EXPECT_EQ(int_at(bytes, 16, PC2_ORDER), POINTS);
    EXPECT_EQ(float_at(bytes, 20, PC2_ORDER), 7.0f);
    EXPECT_EQ(float_at(bytes, 24, PC2_ORDER), 1.0f);
    EXPECT_EQ(int_at(bytes, 28, PC2_ORDER), SAMPLES);
    expect_cache_points(bytes, 32, SAMPLES, POINTS, PC2_ORDER);
}

TEST(Pc2, BadArgumentsAndFailuresLeaveNoFile) {
    expect_refusals_leave_no_file(
        "c.pc2", "sample", [](const auto& path, auto points, auto samples, const auto& source) {
            write_pc2(path, points, samples, 0.0, source);
        });
}

}  // namespace
}  // namespace pliant::io
