// PC2 point caches: read back with an independent little-endian reader written here from the
// format (header, size and every value); bad arguments and failures leave no file.
#include "pliant/io/pc2.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
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

// Little-endian 32-bit words, decoded byte by byte (no host byte order involved).
std::uint32_t word(const std::string& bytes, std::size_t at) {
    const auto b = [&](std::size_t k) {
        return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes.at(at + k)));
    };
    return b(0) | (b(1) << 8) | (b(2) << 16) | (b(3) << 24);
}
std::int32_t int_at(const std::string& bytes, std::size_t at) {
    return std::bit_cast<std::int32_t>(word(bytes, at));
}
float float_at(const std::string& bytes, std::size_t at) {
    return std::bit_cast<float>(word(bytes, at));
}

Vec3f point(std::int64_t s, std::size_t v) {
    return {0.1f * static_cast<float>(v) - 3.0f * static_cast<float>(s),
            std::ldexp(1.0f, static_cast<int>(v)) / 3.0f, -1e-30f * static_cast<float>(s + 1)};
}

TEST(Pc2, HeaderAndSamplesReadBack) {
    const TempDir dir;
    constexpr std::int64_t SAMPLES = 3;
    constexpr std::int64_t POINTS = 4;
    std::vector<std::int64_t> asked;
    write_pc2(dir / "c.pc2", POINTS, SAMPLES, 7.0, [&](std::int64_t s, std::span<Vec3f> out) {
        asked.push_back(s);
        ASSERT_EQ(out.size(), static_cast<std::size_t>(POINTS));
        for (std::size_t v = 0; v < out.size(); ++v) {
            out[v] = point(s, v);
        }
    });
    EXPECT_EQ(asked, (std::vector<std::int64_t>{0, 1, 2}));
    const std::string bytes = read_bytes(dir / "c.pc2");
    ASSERT_EQ(bytes.size(), 32u + 12u * SAMPLES * POINTS);
    EXPECT_EQ(bytes.substr(0, 12), std::string("POINTCACHE2\0", 12));
    EXPECT_EQ(int_at(bytes, 12), 1);
    EXPECT_EQ(int_at(bytes, 16), POINTS);
    EXPECT_EQ(float_at(bytes, 20), 7.0f);
    EXPECT_EQ(float_at(bytes, 24), 1.0f);
    EXPECT_EQ(int_at(bytes, 28), SAMPLES);
    for (std::int64_t s = 0; s < SAMPLES; ++s) {
        for (std::size_t v = 0; v < POINTS; ++v) {
            const std::size_t at = 32 + 12 * (s * POINTS + v);
            const Vec3f p = point(s, v);
            EXPECT_EQ(float_at(bytes, at), p.x);
            EXPECT_EQ(float_at(bytes, at + 4), p.y);
            EXPECT_EQ(float_at(bytes, at + 8), p.z);
        }
    }
}

TEST(Pc2, BadArgumentsAndFailuresLeaveNoFile) {
    const TempDir dir;
    const auto fill = [](std::int64_t, std::span<Vec3f> out) {
        for (Vec3f& p : out) {
            p = {1.0f, 2.0f, 3.0f};
        }
    };
    const auto path = dir / "c.pc2";
    EXPECT_THROW(write_pc2(path, -1, 2, 0.0, fill), InvalidInput);
    EXPECT_THROW(write_pc2(path, 2, std::int64_t{1} << 31, 0.0, fill), InvalidInput);
    try {
        write_pc2(path, 5, -2, 0.0, fill);
        ADD_FAILURE() << "-2 samples were accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(
            std::string(e.what()),
            path.string() +
                ": expected at most 2^31 - 1 points and samples, got 5 points and -2 samples");
    }
    EXPECT_TRUE(dir.entries().empty());

    // A failure mid-stream keeps the earlier file whole and leaves no temporary.
    write_bytes(path, "earlier");
    try {
        write_pc2(path, 3, 5, 0.0, [](std::int64_t s, std::span<Vec3f> out) {
            for (Vec3f& p : out) {
                p = {0.0f, s == 3 ? std::numeric_limits<float>::quiet_NaN() : 1.0f, 0.0f};
            }
        });
        ADD_FAILURE() << "a NaN position was written";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), path.string() + ": sample 3: a position is not finite");
    }
    EXPECT_THROW(write_pc2(path, 3, 5, 0.0,
                           [](std::int64_t s, std::span<Vec3f>) {
                               if (s == 2) {
                                   throw std::runtime_error("killed");
                               }
                           }),
                 std::runtime_error);
    EXPECT_EQ(read_bytes(path), "earlier");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"c.pc2"}));
    EXPECT_THROW(write_pc2(dir / "missing" / "c.pc2", 1, 1, 0.0, fill), IoError);
}

}  // namespace
}  // namespace pliant::io
