#include "pliant/io/mdd.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <ostream>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/byte_order.hpp"
#include "pliant/io/detail/point_cache.hpp"

namespace pliant::io {
namespace {

constexpr bool SWAP = detail::needs_swap(std::endian::big);

template <typename T>
void put(std::vector<char>& buffer, T value) {
    const std::size_t at = buffer.size();
    buffer.resize(at + sizeof(T));
    detail::store(buffer.data() + at, value, SWAP);
}

}  // namespace

void write_mdd(const std::filesystem::path& path, std::int64_t num_points, std::int64_t num_frames,
               double frames_per_second, FunctionRef<void(std::int64_t, std::span<Vec3f>)> frame) {
    detail::check_point_cache_counts(path, num_points, num_frames, "frame");
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
        detail::for_each_point_cache_frame(
            path, num_points, num_frames, "frame", frame,
            [&](std::int64_t /*f*/, std::span<const Vec3f> points) {
                for (const Vec3f& p : points) {
                    put(buffer, p.x);
                    put(buffer, p.y);
                    put(buffer, p.z);
                }
                out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                buffer.clear();
            });
        out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    });
}

}  // namespace pliant::io
