// Memory shared with a forked child (io/forked_call.hpp): an anonymous MAP_SHARED mapping made
// before the fork, so what the child writes into it the parent reads, with no copy through a
// pipe. Pages are allocated when first written (MAP_NORESERVE): mapping more than is written
// costs address space only. Zero-filled. Move-only; unmapped by the destructor.
#pragma once

#include <cstddef>
#include <span>

namespace pliant::io {

class SharedMemory {
public:
    SharedMemory() = default;
    // Throws IoError when the mapping cannot be made.
    explicit SharedMemory(std::size_t bytes);
    SharedMemory(const SharedMemory&) = delete;
    SharedMemory& operator=(const SharedMemory&) = delete;
    SharedMemory(SharedMemory&& other) noexcept;
    SharedMemory& operator=(SharedMemory&& other) noexcept;
    ~SharedMemory();

    std::span<std::byte> bytes() const { return {m_data, m_size}; }

private:
    std::byte* m_data = nullptr;
    std::size_t m_size = 0;
};

}  // namespace pliant::io
