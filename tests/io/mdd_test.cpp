// MDD point caches: read back with an independent big-endian reader written here from the format
// (LightWave's layout, as Blender's import_mdd.py reads it); header, times, size and every value.
#include "pliant/io/mdd.hpp"

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

#include "pliant/core/error.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::read_bytes;
using test::TempDir;
using test::write_bytes;

// Big-endian 32-bit words, decoded byte by byte (no host byte order involved).
std::uint32_t word(const std::string& bytes, std::size_t at) {
    const auto b = [&](std::size_t k) {
        return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes.at(at + k)));
    };
    return (b(0) << 24) | (b(1) << 16) | (b(2) << 8) | b(3);
}
std::int32_t int_at(const std::string& bytes, std::size_t at) {
    return std::bit_cast<std::int32_t>(word(bytes, at));
}
float float_at(const std::string& bytes, std::size_t at) {
    return std::bit_cast<float>(word(bytes, at));
}

Vec3f point(std::int64_t f, std::size_t v) {
    return {0.1f * static_cast<float>(v) - 3.0f * static_cast<float>(f),
            std::ldexp(1.0f, static_cast<int>(v)) / 3.0f, -1e-30f * static_cast<float>(f + 1)};
}

TEST(Mdd, HeaderTimesAndFramesReadBack) {
    const TempDir dir;
    constexpr std::int64_t FRAMES = 4;
    constexpr std::int64_t POINTS = 5;
    std::vector<std::int64_t> asked;
    write_mdd(dir / "c.mdd", POINTS, FRAMES, 24.0, [&](std::int64_t f, std::span<Vec3f> out) {
        asked.push_back(f);
        ASSERT_EQ(out.size(), static_cast<std::size_t>(POINTS));
        for (std::size_t v = 0; v < out.size(); ++v) {
            out[v] = point(f, v);
        }
    });
    EXPECT_EQ(asked, (std::vector<std::int64_t>{0, 1, 2, 3}));
    const std::string bytes = read_bytes(dir / "c.mdd");
    ASSERT_EQ(bytes.size(), 8u + 4u * FRAMES + 12u * FRAMES * POINTS);
    EXPECT_EQ(int_at(bytes, 0), FRAMES);
    EXPECT_EQ(int_at(bytes, 4), POINTS);
    for (std::int64_t f = 0; f < FRAMES; ++f) {
        EXPECT_EQ(float_at(bytes, 8 + 4 * f), static_cast<float>(f / 24.0)) << f;
    }
    for (std::int64_t f = 0; f < FRAMES; ++f) {
        for (std::size_t v = 0; v < POINTS; ++v) {
            const std::size_t at = 8 + 4 * FRAMES + 12 * (f * POINTS + v);
            const Vec3f p = point(f, v);
            EXPECT_EQ(float_at(bytes, at), p.x);
            EXPECT_EQ(float_at(bytes, at + 4), p.y);
            EXPECT_EQ(float_at(bytes, at + 8), p.z);
        }
    }
}

TEST(Mdd, EmptyCache) {
    const TempDir dir;
    write_mdd(dir / "e.mdd", 0, 0, 30.0, [](std::int64_t, std::span<Vec3f>) {});
    EXPECT_EQ(read_bytes(dir / "e.mdd"), std::string(8, '\0'));
}

TEST(Mdd, BadArgumentsAndFailuresLeaveNoFile) {
    const TempDir dir;
    const auto fill = [](std::int64_t, std::span<Vec3f> out) {
        for (Vec3f& p : out) {
            p = {1.0f, 2.0f, 3.0f};
        }
    };
    const auto path = dir / "c.mdd";
    EXPECT_THROW(write_mdd(path, -1, 2, 24.0, fill), InvalidInput);
    EXPECT_THROW(write_mdd(path, 2, std::int64_t{1} << 31, 24.0, fill), InvalidInput);
    EXPECT_THROW(write_mdd(path, 2, 2, 0.0, fill), InvalidInput);
    EXPECT_THROW(write_mdd(path, 2, 2, std::numeric_limits<double>::quiet_NaN(), fill),
                 InvalidInput);
    EXPECT_TRUE(dir.entries().empty());

    // A failure mid-stream keeps the earlier file whole and leaves no temporary.
    write_bytes(path, "earlier");
    EXPECT_THROW(
        write_mdd(path, 3, 5, 24.0,
                  [](std::int64_t f, std::span<Vec3f> out) {
                      for (Vec3f& p : out) {
                          p = {0.0f, 0.0f, f == 3 ? std::numeric_limits<float>::infinity() : 1.0f};
                      }
                  }),
        InvalidInput);
    EXPECT_THROW(write_mdd(path, 3, 5, 24.0,
                           [](std::int64_t f, std::span<Vec3f>) {
                               if (f == 2) {
                                   throw std::runtime_error("killed");
                               }
                           }),
                 std::runtime_error);
    EXPECT_EQ(read_bytes(path), "earlier");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"c.mdd"}));
    EXPECT_THROW(write_mdd(dir / "missing" / "c.mdd", 1, 1, 24.0, fill), IoError);
}

TEST(Mdd, ErrorsNameTheFileAndTheFrame) {
    const TempDir dir;
    const auto path = dir / "c.mdd";
    const auto message = [](const auto& call) {
        try {
            call();
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message([&] { write_mdd(path, 5, -2, 24.0, [](std::int64_t, std::span<Vec3f>) {}); }),
              path.string() +
                  ": expected at most 2^31 - 1 points and frames, got 5 points and -2 frames");
    EXPECT_EQ(message([&] {
                  write_mdd(path, 2, 3, 24.0, [](std::int64_t f, std::span<Vec3f> out) {
                      out[1] = {f == 1 ? std::numeric_limits<float>::infinity() : 0.0f, 0.0f, 0.0f};
                  });
              }),
              path.string() + ": frame 1: a position is not finite");
    EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace pliant::io
