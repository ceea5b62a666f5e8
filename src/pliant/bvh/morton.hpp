// Morton codes (Z-order) of points in a box: 10 bits per axis interleaved into 30 bits
// (Karras 2012, "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d Trees").
#pragma once

#include <cstdint>

#include "pliant/core/aabb.hpp"
#include "pliant/core/host_device.hpp"

namespace pliant::bvh {

inline constexpr int MORTON_BITS = 30;

// Spreads the low 10 bits of v so that bit k lands at bit 3k.
PLIANT_HOST_DEVICE constexpr std::uint32_t spread_bits_3(std::uint32_t v) {
    v &= 0x3ffu;
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

// Morton code of p quantized on a 1024³ grid over `bounds` (points outside are clamped, NaN maps to
// 0; an axis of zero extent maps to cell 0). x takes the highest bit of each triple.
PLIANT_HOST_DEVICE inline std::uint32_t morton_code(Vec3f p, Vec3f lo, Vec3f inv_extent) {
    const auto quantize = [](float u) {
        const float s = u * 1024.0f;
        return static_cast<std::uint32_t>(s > 0.0f ? (s < 1023.0f ? s : 1023.0f)
                                                   : 0.0f);  // NaN → 0
    };
    const std::uint32_t x = quantize((p.x - lo.x) * inv_extent.x);
    const std::uint32_t y = quantize((p.y - lo.y) * inv_extent.y);
    const std::uint32_t z = quantize((p.z - lo.z) * inv_extent.z);
    return (spread_bits_3(x) << 2) | (spread_bits_3(y) << 1) | spread_bits_3(z);
}

}  // namespace pliant::bvh
