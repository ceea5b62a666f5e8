#include "pliant/io/mdd.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <ostream>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/byte_order.hpp"

namespace pliant::io {
namespace {

constexpr bool SWAP = detail::needs_swap(std::endian::big);

template <typename T>
void put(std::vector<char>& buffer, T value) {
    char bytes[sizeof(T)];
    detail::store(bytes, value, SWAP);
    buffer.insert(buffer.end(), bytes, bytes + sizeof(T));
}

}  // namespace

void write_mdd(const std::filesystem::path& path, std::int64_t num_points, std::int64_t num_frames,
               double frames_per_second, FunctionRef<void(std::int64_t, std::span<Vec3f>)> frame) {
    constexpr std::int64_t MAX = std::numeric_limits<std::int32_t>::max();
    if (num_points < 0 || num_points > MAX || num_frames < 0 || num_frames > MAX) {
        throw InvalidInput(
            fmt::format("{}: expected at most 2^31 - 1 points and frames, got {} points and {} "
                        "frames",
                        path.string(), num_points, num_frames));
    }
    if (!std::isfinite(frames_per_second) || !(frames_per_second > 0.0)) {
        throw InvalidInput(fmt::format("{}: frames_per_second is {}, expected a finite value > 0",
                                       path.string(), frames_per_second));
    }
    write_file_atomically(path, [&](std::ostream& out) {
        std::vector<char> buffer;
        put(buffer, static_cast<std::int32_t>(num_frames));
        put(buffer, static_cast<std::int32_t>(num_points));
        for (std::int64_t f = 0; f < num_frames; ++f) {
            put(buffer, static_cast<float>(static_cast<double>(f) / frames_per_second));
            if (buffer.size() >= (std::size_t{1} << 20)) {
                out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                buffer.clear();
            }
        }
        std::vector<Vec3f> points(static_cast<std::size_t>(num_points));
        for (std::int64_t f = 0; f < num_frames; ++f) {
            frame(f, points);
            for (const Vec3f& p : points) {
                if (!is_finite(p)) {
                    throw InvalidInput(
                        fmt::format("{}: frame {}: a position is not finite", path.string(), f));
                }
                put(buffer, p.x);
                put(buffer, p.y);
                put(buffer, p.z);
            }
            out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            buffer.clear();
        }
        out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    });
}

}  // namespace pliant::io
