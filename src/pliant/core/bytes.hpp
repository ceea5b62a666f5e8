// Byte buffers for pliant's own binary state (checkpoints, io/checkpoint.hpp): ByteWriter appends
// values, ByteReader reads them back in the same order with every read bounds-checked.
//
//   ByteWriter w;
//   w.put(frame);                       // one trivially copyable value
//   w.put_vector(positions);            // u64 count, then the elements
//   ByteReader r(w.bytes(), "checkpoint.bin");
//   frame = r.get<int>("frame");
//   r.get_vector("positions", positions, num_vertices);   // InvalidInput unless #V elements
//
// Values are stored as their object representation (little-endian on every host pliant builds
// for; static_assert below), without padding or alignment between them. A read past the end, a
// count that does not fit in what is left, or a count that differs from the one expected throws
// InvalidInput naming the buffer (`source`) and the field. Not thread safe.
#pragma once

#include <fmt/format.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant {

static_assert(std::endian::native == std::endian::little,
              "pliant's binary formats are little-endian");

class ByteWriter {
public:
    template <typename T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* first = reinterpret_cast<const std::byte*>(&value);
        m_bytes.insert(m_bytes.end(), first, first + sizeof(T));
    }
    // The count (u64), then the elements.
    template <typename T>
    void put_vector(std::span<const T> values) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(static_cast<std::uint64_t>(values.size()));
        const auto* first = reinterpret_cast<const std::byte*>(values.data());
        m_bytes.insert(m_bytes.end(), first, first + values.size_bytes());
    }
    template <typename T>
    void put_vector(const std::vector<T>& values) {
        put_vector(std::span<const T>(values));
    }
    void put_string(std::string_view text) {
        put_vector(std::span<const char>(text.data(), text.size()));
    }
    void put_bytes(std::span<const std::byte> bytes) {
        m_bytes.insert(m_bytes.end(), bytes.begin(), bytes.end());
    }

    std::span<const std::byte> bytes() const { return m_bytes; }
    std::size_t size() const { return m_bytes.size(); }

private:
    std::vector<std::byte> m_bytes;
};

class ByteReader {
public:
    // bytes must outlive the reader; source names them in errors (a file name).
    ByteReader(std::span<const std::byte> bytes, std::string source)
        : m_bytes(bytes), m_source(std::move(source)) {}

    template <typename T>
    T get(std::string_view field) {
        static_assert(std::is_trivially_copyable_v<T>);
        require(field, sizeof(T), 1);
        T value;
        std::memcpy(&value, m_bytes.data() + m_position, sizeof(T));
        m_position += sizeof(T);
        return value;
    }
    // A bool stored by put(bool): InvalidInput unless 0 or 1.
    bool get_bool(std::string_view field) {
        const auto byte = get<std::uint8_t>(field);
        if (byte > 1) {
            throw InvalidInput(
                fmt::format("{}: {}: expected a boolean (0 or 1), got {}", m_source, field, byte));
        }
        return byte == 1;
    }
    // A vector stored by put_vector into `values`; with expected_count >= 0, InvalidInput unless
    // the stored count is that.
    template <typename T>
    void get_vector(std::string_view field, std::vector<T>& values,
                    std::int64_t expected_count = -1) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto count = get<std::uint64_t>(field);
        if (expected_count >= 0 && count != static_cast<std::uint64_t>(expected_count)) {
            throw InvalidInput(fmt::format("{}: {}: expected {} elements, got {}", m_source, field,
                                           expected_count, count));
        }
        require(field, sizeof(T), count);
        values.resize(count);
        if (count > 0) {
            std::memcpy(values.data(), m_bytes.data() + m_position, count * sizeof(T));
        }
        m_position += count * sizeof(T);
    }
    std::string get_string(std::string_view field) {
        std::vector<char> chars;
        get_vector(field, chars);
        return {chars.begin(), chars.end()};
    }
    // The next `count` bytes (a view into the buffer).
    std::span<const std::byte> get_bytes(std::string_view field, std::size_t count) {
        require(field, 1, count);
        const std::span<const std::byte> bytes = m_bytes.subspan(m_position, count);
        m_position += count;
        return bytes;
    }

    std::size_t position() const { return m_position; }
    std::size_t remaining() const { return m_bytes.size() - m_position; }
    const std::string& source() const { return m_source; }
    // InvalidInput unless every byte was read (a buffer written by a different layout).
    void expect_end() const {
        if (remaining() != 0) {
            throw InvalidInput(
                fmt::format("{}: {} bytes left over after the last field", m_source, remaining()));
        }
    }

private:
    void require(std::string_view field, std::size_t element_size, std::uint64_t count) const {
        const std::size_t left = remaining();
        if (count > left / element_size) {
            throw InvalidInput(
                fmt::format("{}: {}: truncated: needs {} x {} bytes at offset {}, {} bytes left",
                            m_source, field, count, element_size, m_position, left));
        }
    }

    std::span<const std::byte> m_bytes;
    std::string m_source;
    std::size_t m_position = 0;
};

}  // namespace pliant
