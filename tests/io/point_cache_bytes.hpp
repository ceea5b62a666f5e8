// Reading point caches back for the MDD and PC2 tests (tests/io/point_cache_test.cpp):
// 32-bit words decoded byte by byte in the file's byte order (no host byte order involved), and
// the positions the tests write.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::io::test {

// The 32-bit word at byte `at` of `bytes`, stored in `order`.
inline std::uint32_t word_at(const std::string& bytes, std::size_t at, std::endian order) {
    std::uint32_t w = 0;
    for (std::size_t k = 0; k < 4; ++k) {
        const std::size_t byte = order == std::endian::big ? k : 3 - k;
        w = (w << 8) | static_cast<std::uint32_t>(static_cast<unsigned char>(bytes.at(at + byte)));
    }
    return w;
}
inline std::int32_t int_at(const std::string& bytes, std::size_t at, std::endian order) {
    return std::bit_cast<std::int32_t>(word_at(bytes, at, order));
}
inline float float_at(const std::string& bytes, std::size_t at, std::endian order) {
    return std::bit_cast<float>(word_at(bytes, at, order));
}

// Position `v` of frame `f`: distinct, with values that are not round in binary (v / 3) and a
// tiny one (1e-30) to catch a lossy conversion.
inline Vec3f cache_point(std::int64_t f, std::size_t v) {
    return {0.1f * static_cast<float>(v) - 3.0f * static_cast<float>(f),
            std::ldexp(1.0f, static_cast<int>(v)) / 3.0f, -1e-30f * static_cast<float>(f + 1)};
}

// A frame source for the writers: fills cache_point(f, v) and records which frames it was asked
// for (the writers ask for each frame once, in order, with room for `num_points` positions).
struct RecordingSource {
    std::int64_t num_points = 0;
    std::vector<std::int64_t> asked;
    void operator()(std::int64_t f, std::span<Vec3f> out) {
        asked.push_back(f);
        EXPECT_EQ(out.size(), static_cast<std::size_t>(num_points)) << "frame " << f;
        for (std::size_t v = 0; v < out.size(); ++v) {
            out[v] = cache_point(f, v);
        }
    }
};

// A frame source that sets every position to (1, 2, 3).
inline void fill_constant(std::int64_t /*f*/, std::span<Vec3f> out) {
    for (Vec3f& p : out) {
        p = {1.0f, 2.0f, 3.0f};
    }
}

// Expects `num_frames` × `num_points` float32 (x, y, z) from byte `first` of `bytes` to be
// cache_point(f, v), frame by frame.
inline void expect_cache_points(const std::string& bytes, std::size_t first,
                                std::int64_t num_frames, std::int64_t num_points,
                                std::endian order) {
    for (std::int64_t f = 0; f < num_frames; ++f) {
        for (std::size_t v = 0; v < static_cast<std::size_t>(num_points); ++v) {
            const std::size_t at = first + 12 * (static_cast<std::size_t>(f * num_points) + v);
            const Vec3f p = cache_point(f, v);
            EXPECT_EQ(float_at(bytes, at, order), p.x) << "frame " << f << " point " << v;
            EXPECT_EQ(float_at(bytes, at + 4, order), p.y) << "frame " << f << " point " << v;
            EXPECT_EQ(float_at(bytes, at + 8, order), p.z) << "frame " << f << " point " << v;
        }
    }
}

}  // namespace pliant::io::test
