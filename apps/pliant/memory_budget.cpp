#include "memory_budget.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <limits>

#include "pliant/core/error.hpp"

namespace pliant::cli {

std::uint64_t physical_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES);
    const long page_size = ::sysconf(_SC_PAGESIZE);
    if (pages <= 0 || page_size <= 0) {
        return 0;
    }
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
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
        "{}: {} triangles need at least {:.1f} GB to simulate ({} bytes per triangle), more than "
        "the {:.1f} GB of memory this machine has",
        what, triangles, static_cast<double>(triangles) * static_cast<double>(per_triangle) / 1e9,
        per_triangle, static_cast<double>(memory_bytes) / 1e9));
}

}  // namespace pliant::cli
