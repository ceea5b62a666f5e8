#include "pliant/volume/volume.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "pliant/core/error.hpp"

namespace pliant::volume {

std::string_view name(VoxelType type) {
    switch (type) {
        case VoxelType::u8:
            return "u8";
        case VoxelType::i16:
            return "i16";
        case VoxelType::u16:
            return "u16";
        case VoxelType::f32:
            return "f32";
        case VoxelType::rgba8:
            return "rgba8";
        case VoxelType::rgba32f:
            return "rgba32f";
    }
    return "unknown";
}

Volume Volume::allocate(const Dims& dims, VoxelType type, const Vec3d& spacing, const Vec3d& origin,
                        std::size_t max_bytes) {
    for (int axis = 0; axis < 3; ++axis) {
        if (dims[static_cast<std::size_t>(axis)] < 1) {
            throw InvalidInput(
                fmt::format("volume: dims must be >= 1 on every axis, got {} x {} x {}", dims[0],
                            dims[1], dims[2]));
        }
    }
    // Bytes = dims product × bytes per voxel, checked against max_bytes without overflow.
    const auto per_voxel = static_cast<long double>(bytes_per_voxel(type));
    const long double bytes = static_cast<long double>(dims[0]) *
                              static_cast<long double>(dims[1]) *
                              static_cast<long double>(dims[2]) * per_voxel;
    if (bytes > static_cast<long double>(max_bytes)) {
        throw InvalidInput(fmt::format(
            "volume: {} x {} x {} voxels of {} need {:.4g} bytes, more than the limit of {} bytes",
            dims[0], dims[1], dims[2], name(type), static_cast<double>(bytes), max_bytes));
    }
    Volume volume;
    volume.m_dims = dims;
    volume.m_type = type;
    volume.set_spacing(spacing);
    volume.set_origin(origin);
    volume.m_data.resize(static_cast<std::size_t>(bytes));
    return volume;
}

void Volume::set_spacing(const Vec3d& spacing) {
    if (!is_finite(spacing) || !(spacing.x > 0.0) || !(spacing.y > 0.0) || !(spacing.z > 0.0)) {
        throw InvalidInput(fmt::format("volume: spacing must be finite and > 0, got ({}, {}, {})",
                                       spacing.x, spacing.y, spacing.z));
    }
    m_spacing = spacing;
}

void Volume::set_origin(const Vec3d& origin) {
    if (!is_finite(origin)) {
        throw InvalidInput(fmt::format("volume: origin must be finite, got ({}, {}, {})", origin.x,
                                       origin.y, origin.z));
    }
    m_origin = origin;
}

void Volume::set_direction(const Direction& direction) {
    const auto text = [&] {
        return fmt::format("({}, {}, {}) ({}, {}, {}) ({}, {}, {})", direction[0].x, direction[0].y,
                           direction[0].z, direction[1].x, direction[1].y, direction[1].z,
                           direction[2].x, direction[2].y, direction[2].z);
    };
    for (std::size_t a = 0; a < 3; ++a) {
        if (!is_finite(direction[a]) ||
            !(std::abs(std::sqrt(dot(direction[a], direction[a])) - 1.0) <= DIRECTION_TOLERANCE)) {
            throw InvalidInput(fmt::format(
                "volume: direction columns must be finite unit vectors, got {}", text()));
        }
        for (std::size_t b = a + 1; b < 3; ++b) {
            if (!(std::abs(dot(direction[a], direction[b])) <= DIRECTION_TOLERANCE)) {
                throw InvalidInput(fmt::format(
                    "volume: direction columns must be orthogonal, got {} (columns {} and {}: "
                    "dot {})",
                    text(), a, b, dot(direction[a], direction[b])));
            }
        }
    }
    m_direction = direction;
}

Vec3d Volume::world_from_grid(const Vec3d& uvw) const {
    const Vec3d local{uvw.x * m_spacing.x, uvw.y * m_spacing.y, uvw.z * m_spacing.z};
    if (is_axis_aligned()) {
        return m_origin + local;
    }
    return m_origin + m_direction[0] * local.x + m_direction[1] * local.y +
           m_direction[2] * local.z;
}

AABBd Volume::world_bounds() const {
    if (is_axis_aligned()) {
        return bounds();
    }
    AABBd box;
    for (int corner = 0; corner < 8; ++corner) {
        box.extend(world_from_grid({(corner & 1) != 0 ? static_cast<double>(m_dims[0]) : 0.0,
                                    (corner & 2) != 0 ? static_cast<double>(m_dims[1]) : 0.0,
                                    (corner & 4) != 0 ? static_cast<double>(m_dims[2]) : 0.0}));
    }
    return box;
}

AABBd Volume::bounds() const {
    const Vec3d size{static_cast<double>(m_dims[0]) * m_spacing.x,
                     static_cast<double>(m_dims[1]) * m_spacing.y,
                     static_cast<double>(m_dims[2]) * m_spacing.z};
    return AABBd{m_origin, m_origin + size};
}

void Volume::check_type(VoxelType expected) const {
    if (expected != m_type) {
        throw InvalidInput(fmt::format("volume: expected voxels of type {}, the volume has {}",
                                       name(expected), name(m_type)));
    }
}

}  // namespace pliant::volume
