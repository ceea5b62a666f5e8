// Hand-built PLY data for the PLY reader tests (tests/io/ply_test.cpp, ply_polygons_test.cpp):
// binary values in a chosen byte order, and the three PLY formats to loop over.
#pragma once

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

#include "pliant/io/ply.hpp"

namespace pliant::io::test {

// Binary data built by hand, value by value, in a chosen byte order.
class Bytes {
public:
    explicit Bytes(std::endian order) : m_order(order) {}

    // Appends the values, all as type T.
    template <typename T, typename... Rest>
    Bytes& put(T first, Rest... rest) {
        put_one(first);
        (put_one(static_cast<T>(rest)), ...);
        return *this;
    }
    const std::string& str() const { return m_bytes; }

private:
    template <typename T>
    void put_one(T value) {
        unsigned char raw[sizeof(T)];
        std::memcpy(raw, &value, sizeof(T));
        if (m_order != std::endian::native) {
            std::reverse(raw, raw + sizeof(T));
        }
        m_bytes.append(reinterpret_cast<const char*>(raw), sizeof(T));
    }

    std::endian m_order;
    std::string m_bytes;
};

inline constexpr PlyFormat ALL_FORMATS[] = {PlyFormat::ascii, PlyFormat::binary_little_endian,
                                            PlyFormat::binary_big_endian};

}  // namespace pliant::io::test
