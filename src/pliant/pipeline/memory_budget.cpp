#include "pliant/pipeline/memory_budget.hpp"

#include <fmt/format.h>
#include <unistd.h>

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

// "104 MB", "127.4 GB".
std::string human_bytes(double bytes) {
    return bytes >= 1e9 ? fmt::format("{:.1f} GB", bytes / 1e9)
                        : fmt::format("{:.0f} MB", bytes / 1e6);
}

}  // namespace

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
        human_bytes(static_cast<double>(triangles) * static_cast<double>(per_triangle)),
        per_triangle, human_bytes(static_cast<double>(memory_bytes))));
}

}  // namespace pliant::pipeline
