#include "pliant/pipeline/memory_budget.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <limits>

#include "pliant/core/error.hpp"

namespace pliant::pipeline {

namespace {

// The first number in `file` (0 when it cannot be read or is not a number, e.g. "max").
std::uint64_t read_limit(const char* file) {
    std::ifstream in(file);
    std::uint64_t value = 0;
    return in >> value ? value : 0;
}

}  // namespace

std::string format_bytes(double bytes) {
    // Three significant digits in MB; GB from what would round to 1000 MB.
    return bytes >= 999.5e6 ? fmt::format("{:.1f} GB", bytes / 1e9)
                            : fmt::format("{:.3g} MB", bytes / 1e6);
}

std::uint64_t memory_limit_bytes(double max_memory_mib) {
    if (max_memory_mib > 0.0) {
        const double bytes = max_memory_mib * 1024.0 * 1024.0;
        return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                               : static_cast<std::uint64_t>(bytes);
    }
    return available_memory_bytes();
}

std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b) {
    if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) {
        return std::numeric_limits<std::uint64_t>::max();
    }
    return a * b;
}

std::uint64_t saturating_sum(std::uint64_t a, std::uint64_t b) {
    return b > std::numeric_limits<std::uint64_t>::max() - a
               ? std::numeric_limits<std::uint64_t>::max()
               : a + b;
}

void require_memory(const std::string& what, std::uint64_t needed_bytes,
                    std::uint64_t limit_bytes) {
    if (limit_bytes == 0 || needed_bytes <= limit_bytes) {
        return;
    }
    throw InvalidInput(
        fmt::format("{} needs {}, more than the {} allowed by --max-memory (or "
                    "available)",
                    what, format_bytes(static_cast<double>(needed_bytes)),
                    format_bytes(static_cast<double>(limit_bytes))));
}

std::uint64_t image_bytes(std::int64_t width, std::int64_t height) {
    return saturating_product(
        saturating_product(static_cast<std::uint64_t>(std::max<std::int64_t>(width, 0)),
                           static_cast<std::uint64_t>(std::max<std::int64_t>(height, 0))),
        3);
}

namespace {

// The voxels of a grid of `dims` (saturating; a negative extent counts as 0).
std::uint64_t voxel_count(const volume::Dims& dims) {
    std::uint64_t voxels = 1;
    for (const std::int64_t d : dims) {
        voxels =
            saturating_product(voxels, static_cast<std::uint64_t>(std::max<std::int64_t>(d, 0)));
    }
    return voxels;
}

}  // namespace

std::uint64_t ray_cast_bytes(const volume::Dims& dims, int channels) {
    const std::uint64_t voxels = voxel_count(dims);
    // RGBA: 4 floats, and a fifth (α apart) when shaded; counted always (an upper bound).
    const std::uint64_t floats = channels == 4 ? 5 : 1;
    return saturating_sum(saturating_product(voxels, floats * sizeof(float)), voxels);
}

std::uint64_t mapped_ray_cast_bytes(const volume::Dims& dims, int channels) {
    const std::uint64_t voxels = voxel_count(dims);
    const std::uint64_t per_voxel = channels == 4 ? 24 : 12;
    return saturating_sum(saturating_product(voxels, per_voxel), voxels);
}

std::uint64_t available_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES);
    const long page_size = ::sysconf(_SC_PAGESIZE);
    std::uint64_t available = pages > 0 && page_size > 0 ? static_cast<std::uint64_t>(pages) *
                                                               static_cast<std::uint64_t>(page_size)
                                                         : 0;
    for (const char* limit_file :
         {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        const std::uint64_t limit = read_limit(limit_file);
        if (limit > 0 && (available == 0 || limit < available)) {
            available = limit;
        }
    }
    return available;
}

std::uint64_t ray_cast_need_bytes(const volume::Volume& source, std::int64_t width,
                                  std::int64_t height) {
    return saturating_sum(
        saturating_sum(source.size_bytes(),
                       ray_cast_bytes(source.dims(), volume::channels(source.type()))),
        image_bytes(width, height));
}

std::string ray_cast_what(const volume::Volume& source, std::int64_t width, std::int64_t height) {
    const volume::Dims& d = source.dims();
    return fmt::format("ray-casting a {}x{} image of the {} x {} x {} {} volume", width, height,
                       d[0], d[1], d[2], volume::name(source.type()));
}

std::uint64_t broad_phase_need_bytes(std::uint64_t triangles) {
    return saturating_product(triangles, BROAD_PHASE_BYTES_PER_TRIANGLE);
}

std::uint64_t deform_need_bytes(const volume::Volume& source, std::uint64_t cells,
                                std::int64_t width, std::int64_t height) {
    std::uint64_t bytes =
        saturating_sum(saturating_product(saturating_product(cells, 5), SOFT_BODY_BYTES_PER_TET),
                       source.size_bytes());
    if (width > 0 && height > 0) {
        const int channels = volume::channels(source.type());
        const std::uint64_t caster = std::max(ray_cast_bytes(source.dims(), channels),
                                              mapped_ray_cast_bytes(source.dims(), channels));
        bytes = saturating_sum(saturating_sum(bytes, saturating_sum(source.size_bytes(), caster)),
                               image_bytes(width, height));
    } else {
        bytes = saturating_sum(bytes, source.size_bytes());
    }
    return bytes;
}

void require_cloth_fits_in_memory(const std::string& what, std::uint64_t triangles,
                                  bool self_collision, std::uint64_t memory_bytes) {
    const std::uint64_t per_triangle =
        self_collision ? SELF_COLLIDING_CLOTH_BYTES_PER_TRIANGLE : CLOTH_BYTES_PER_TRIANGLE;
    const std::uint64_t most = std::numeric_limits<std::uint64_t>::max() / per_triangle;
    if (memory_bytes == 0 || (triangles <= most && triangles * per_triangle <= memory_bytes)) {
        return;
    }
    throw InvalidInput(fmt::format(
        "{}: {} triangles need at least {} to simulate ({} bytes per triangle), more than the {} "
        "of memory available",
        what, triangles,
        format_bytes(static_cast<double>(triangles) * static_cast<double>(per_triangle)),
        per_triangle, format_bytes(static_cast<double>(memory_bytes))));
}

}  // namespace pliant::pipeline
