#include "pliant/io/pc2.hpp"

#include <fmt/format.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/point_cache.hpp"

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
    detail::check_point_cache_counts(path, num_points, num_samples, "sample");
    write_file_atomically(path, [&](std::ostream& out) {
        out.write("POINTCACHE2\0", 12);
        put<std::int32_t>(out, 1);
        put(out, static_cast<std::int32_t>(num_points));
        put(out, static_cast<float>(start_frame));
        put(out, 1.0F);
        put(out, static_cast<std::int32_t>(num_samples));
        detail::for_each_point_cache_frame(
            path, num_points, num_samples, "sample", sample,
            [&](std::int64_t /*s*/, std::span<const Vec3f> points) {
                out.write(reinterpret_cast<const char*>(points.data()),
                          static_cast<std::streamsize>(points.size() * sizeof(Vec3f)));
            });
    });
}

}  // namespace pliant::io
