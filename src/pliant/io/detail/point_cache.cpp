#include "pliant/io/detail/point_cache.hpp"

#include <fmt/format.h>

#include <limits>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::io::detail {

void check_point_cache_counts(const std::filesystem::path& path, std::int64_t num_points,
                              std::int64_t num_frames, const char* frame_word) {
    constexpr std::int64_t MAX = std::numeric_limits<std::int32_t>::max();
    if (num_points < 0 || num_points > MAX || num_frames < 0 || num_frames > MAX) {
        throw InvalidInput(
            fmt::format("{}: expected at most 2^31 - 1 points and {}s, got {} points and {} {}s",
                        path.string(), frame_word, num_points, num_frames, frame_word));
    }
}

void for_each_point_cache_frame(const std::filesystem::path& path, std::int64_t num_points,
                                std::int64_t num_frames, const char* frame_word,
                                FunctionRef<void(std::int64_t, std::span<Vec3f>)> source,
                                FunctionRef<void(std::int64_t, std::span<const Vec3f>)> sink) {
    std::vector<Vec3f> points(static_cast<std::size_t>(num_points));
    for (std::int64_t f = 0; f < num_frames; ++f) {
        source(f, points);
        for (const Vec3f& p : points) {
            if (!is_finite(p)) {
                throw InvalidInput(fmt::format("{}: {} {}: a position is not finite", path.string(),
                                               frame_word, f));
            }
        }
        sink(f, points);
    }
}

}  // namespace pliant::io::detail
