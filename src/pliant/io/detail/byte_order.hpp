// Unaligned loads and stores of scalars in either byte order, for the binary PLY codec.
// load<T>(p, swap) reads sizeof(T) bytes at p (no alignment needed); `swap` reverses the bytes,
// i.e. it is true when the file's byte order differs from the host's. store<T> is the inverse.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace pliant::io::detail {

template <typename U>
requires std::is_unsigned_v<U>
constexpr U byteswap(U value) {
    U out = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i) {
        out = static_cast<U>((out << 8) | (value & 0xffu));
        value = static_cast<U>(value >> 8);
    }
    return out;
}

// The unsigned integer type with the size of T (1, 2, 4 or 8 bytes).
template <typename T>
using UnsignedBits = std::conditional_t<
    sizeof(T) == 1, std::uint8_t,
    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;

template <typename T>
inline T load(const char* p, bool swap) {
    using U = UnsignedBits<T>;
    static_assert(sizeof(U) == sizeof(T));
    U bits;
    std::memcpy(&bits, p, sizeof(U));
    if (swap) {
        bits = byteswap(bits);
    }
    return std::bit_cast<T>(bits);
}

template <typename T>
inline void store(char* p, T value, bool swap) {
    using U = UnsignedBits<T>;
    static_assert(sizeof(U) == sizeof(T));
    U bits = std::bit_cast<U>(value);
    if (swap) {
        bits = byteswap(bits);
    }
    std::memcpy(p, &bits, sizeof(U));
}

// True when data in the given byte order must be swapped on this host.
constexpr bool needs_swap(std::endian file_order) {
    return file_order != std::endian::native;
}

}  // namespace pliant::io::detail
