// What the point-cache writers (mdd.cpp, pc2.cpp) share: the count limits and the frame loop
// that asks the caller for each frame's positions and refuses a non-finite one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "pliant/core/function_ref.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::io::detail {

// Throws InvalidInput "<path>: expected at most 2^31 - 1 points and <frames>s, got <n> points
// and <m> <frames>s" unless both counts are in [0, 2^31 - 1]; `frame_word` is "frame" or
// "sample".
void check_point_cache_counts(const std::filesystem::path& path, std::int64_t num_points,
                              std::int64_t num_frames, const char* frame_word);

// For f = 0 … num_frames - 1 in order: source(f, points) fills `num_points` positions, which are
// checked (InvalidInput "<path>: <frame_word> <f>: a position is not finite") and passed to
// sink(f, points).
void for_each_point_cache_frame(const std::filesystem::path& path, std::int64_t num_points,
                                std::int64_t num_frames, const char* frame_word,
                                FunctionRef<void(std::int64_t, std::span<Vec3f>)> source,
                                FunctionRef<void(std::int64_t, std::span<const Vec3f>)> sink);

}  // namespace pliant::io::detail
