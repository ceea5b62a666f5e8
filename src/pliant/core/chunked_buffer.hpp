// ChunkedBuffer<T>: variable-length parallel output made deterministic. Each fixed chunk of a
// parallel_for_chunks loop appends to its own AppendBuffer; gather() concatenates them in chunk
// order, so the result does not depend on the number of threads or on scheduling. Capacity is kept
// between uses (no per-item allocation once warmed up).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "pliant/core/append_buffer.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {

template <typename T>
class ChunkedBuffer {
public:
    // Prepares count empty chunks, keeping the capacity of earlier ones.
    void reset(std::int64_t count) {
        if (m_chunks.size() < static_cast<std::size_t>(count)) {
            m_chunks.resize(static_cast<std::size_t>(count));
        }
        m_count = static_cast<std::size_t>(count);
        for (std::size_t c = 0; c < m_count; ++c) {
            m_chunks[c].clear();
        }
    }
    AppendBuffer<T>& chunk(std::int64_t c) { return m_chunks[static_cast<std::size_t>(c)]; }
    const AppendBuffer<T>& chunk(std::int64_t c) const {
        return m_chunks[static_cast<std::size_t>(c)];
    }
    std::int64_t num_chunks() const { return static_cast<std::int64_t>(m_count); }

    std::size_t size() const {
        std::size_t total = 0;
        for (std::size_t c = 0; c < m_count; ++c) {
            total += m_chunks[c].size();
        }
        return total;
    }

    // Bytes held by all chunks (capacity).
    std::size_t memory_bytes() const {
        std::size_t total = m_chunks.capacity() * sizeof(AppendBuffer<T>);
        for (const AppendBuffer<T>& c : m_chunks) {
            total += c.capacity() * sizeof(T);
        }
        return total;
    }

    // out = chunk 0 ‖ chunk 1 ‖ … (copies in parallel).
    void gather(std::vector<T>& out) const {
        std::vector<std::size_t> offsets(m_count + 1, 0);
        for (std::size_t c = 0; c < m_count; ++c) {
            offsets[c + 1] = offsets[c] + m_chunks[c].size();
        }
        out.resize(offsets.back());
        detail::run_chunks(static_cast<std::int64_t>(m_count), [&](std::int64_t c) {
            const auto& src = m_chunks[static_cast<std::size_t>(c)];
            std::copy(
                src.begin(), src.end(),
                out.begin() + static_cast<std::ptrdiff_t>(offsets[static_cast<std::size_t>(c)]));
        });
    }

private:
    std::vector<AppendBuffer<T>> m_chunks;
    std::size_t m_count = 0;
};

}  // namespace pliant
