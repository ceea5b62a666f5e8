// AppendBuffer<T>: a growable array of small value types for hot output loops. Unlike
// std::vector it can hand out uninitialized room (grow) and take back how much was used
// (commit), so a kernel writes candidates unconditionally and advances by a 0/1 hit count —
// branch-free stream compaction. Capacity is kept across clear().
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <type_traits>
#include <utility>

namespace pliant {

template <typename T>
class AppendBuffer {
    static_assert(std::is_trivially_destructible_v<T> && std::is_default_constructible_v<T>);

public:
    AppendBuffer() = default;
    AppendBuffer(const AppendBuffer&) = delete;
    AppendBuffer& operator=(const AppendBuffer&) = delete;
    // A moved-from buffer is empty and usable.
    AppendBuffer(AppendBuffer&& other) noexcept
        : m_data(std::move(other.m_data)),
          m_size(std::exchange(other.m_size, 0)),
          m_capacity(std::exchange(other.m_capacity, 0)) {}
    AppendBuffer& operator=(AppendBuffer&& other) noexcept {
        m_data = std::move(other.m_data);
        m_size = std::exchange(other.m_size, 0);
        m_capacity = std::exchange(other.m_capacity, 0);
        return *this;
    }

    std::size_t size() const { return m_size; }
    bool empty() const { return m_size == 0; }
    void clear() { m_size = 0; }
    const T* begin() const { return m_data.get(); }
    const T* end() const { return m_data.get() + m_size; }
    const T& operator[](std::size_t i) const { return m_data[i]; }
    std::size_t capacity() const { return m_capacity; }

    // Room for n more elements after the current end (contents unspecified).
    T* grow(std::size_t n) {
        if (m_size + n > m_capacity) {
            const std::size_t capacity = std::max(m_size + n, 2 * m_capacity + 64);
            auto data = std::make_unique_for_overwrite<T[]>(capacity);
            std::copy(m_data.get(), m_data.get() + m_size, data.get());
            m_data = std::move(data);
            m_capacity = capacity;
        }
        return m_data.get() + m_size;
    }
    // Keeps n of the elements written after the end (n ≤ the last grow's n).
    void commit(std::size_t n) { m_size += n; }

    void push_back(const T& value) {
        *grow(1) = value;
        ++m_size;
    }
    template <typename... Args>
    void emplace_back(Args&&... args) {
        push_back(T{std::forward<Args>(args)...});
    }

private:
    std::unique_ptr<T[]> m_data;
    std::size_t m_size = 0;
    std::size_t m_capacity = 0;
};

}  // namespace pliant
