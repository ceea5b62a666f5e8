#include "pliant/io/shared_memory.hpp"

#include <fmt/format.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "pliant/core/error.hpp"

namespace pliant::io {

SharedMemory::SharedMemory(std::size_t bytes) : m_size(bytes) {
    if (bytes == 0) {
        return;
    }
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                     MAP_SHARED | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED) {
        m_size = 0;
        throw IoError(
            fmt::format("cannot map {} bytes of shared memory: {}", bytes, std::strerror(errno)));
    }
    m_data = static_cast<std::byte*>(p);
}

SharedMemory::SharedMemory(SharedMemory&& other) noexcept
    : m_data(std::exchange(other.m_data, nullptr)), m_size(std::exchange(other.m_size, 0)) {}

SharedMemory& SharedMemory::operator=(SharedMemory&& other) noexcept {
    if (this != &other) {
        if (m_data != nullptr) {
            ::munmap(m_data, m_size);
        }
        m_data = std::exchange(other.m_data, nullptr);
        m_size = std::exchange(other.m_size, 0);
    }
    return *this;
}

SharedMemory::~SharedMemory() {
    if (m_data != nullptr) {
        ::munmap(m_data, m_size);
    }
}

}  // namespace pliant::io
