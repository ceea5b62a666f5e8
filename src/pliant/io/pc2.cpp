#include "pliant/io/pc2.hpp"

#include <fmt/format.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"

namespace pliant::io {
namespace {

static_assert(std::endian::native == std::endian::little, "PC2 is little-endian");

template <typename T>
void put(std::ostream& out, T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out.write(bytes, sizeof(T));
}

}  // namespace

void write_pc2(const std::filesystem::path& path, std::int64_t num_points, std::int64_t num_samples,
               double start_frame, FunctionRef<void(std::int64_t, std::span<Vec3f>)> sample) {
    constexpr std::int64_t MAX = std::numeric_limits<std::int32_t>::max();
    if (num_points < 0 || num_points > MAX || num_samples < 0 || num_samples > MAX) {
        throw InvalidInput(
            fmt::format("{}: expected at most 2^31 - 1 points and samples, got {} "
                        "points and {} samples",
                        path.string(), num_points, num_samples));
    }
    write_file_atomically(path, [&](std::ostream& out) {
        out.write("POINTCACHE2\0", 12);
        put<std::int32_t>(out, 1);
        put(out, static_cast<std::int32_t>(num_points));
        put(out, static_cast<float>(start_frame));
        put(out, 1.0F);
        put(out, static_cast<std::int32_t>(num_samples));
        std::vector<Vec3f> points(static_cast<std::size_t>(num_points));
        for (std::int64_t s = 0; s < num_samples; ++s) {
            sample(s, points);
            for (const Vec3f& p : points) {
                if (!is_finite(p)) {
                    throw InvalidInput(
                        fmt::format("{}: sample {}: a position is not finite", path.string(), s));
                }
            }
            out.write(reinterpret_cast<const char*>(points.data()),
                      static_cast<std::streamsize>(points.size() * sizeof(Vec3f)));
        }
    });
}

}  // namespace pliant::io
