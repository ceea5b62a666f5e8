// Volume: a regular grid of voxels with its placement in the world, owning its data.
//
// Conventions (docs/conventions.md): voxel (i, j, k) is centred at
//   origin + D · ((i + 0.5) sx, (j + 0.5) sy, (k + 0.5) sz),
// where D is the direction (columns: the world directions of the i, j and k axes, orthonormal;
// the identity by default). An axis-aligned volume (D = I) covers the box
// [origin, origin + dims · spacing]; an oriented one covers that box turned by D about `origin`,
// the corner of voxel (0, 0, 0). i runs fastest in memory, then j, then k (x fastest, as NIfTI and
// NRRD store them). Spacing and origin are in world units (millimetres for medical data, metres in
// cloth scenes: whatever the file says). Medical files are read into one world frame, NIfTI's
// RAS+ (+x toward the patient's right, +y anterior, +z superior); io/ readers convert DICOM's and
// NRRD's LPS.
//
// Orientation: the readers keep a file's direction cosines (io/volume_io.hpp), re-indexed so that
// each grid axis is the one nearest to +x, +y, +z (flips and axis swaps are exact and free), so D
// is the identity unless the grid is truly oblique. The ray caster renders an oriented volume in
// world space (render/raycast.hpp); tet grids and the resampling of deformed meshes work in the
// grid's frame and need an axis-aligned volume: volume/reorient.hpp resamples an oriented one.
//
// Voxel types: scalar u8, i16, u16, f32 (one channel: intensity, CT Hounsfield units, …) and
// RGBA u8, f32 (four channels, interleaved r, g, b, a per voxel: colour and opacity, opacity per
// unit distance, see volume/transfer_function.hpp). Data is stored natively (little-endian on
// every supported machine) as bytes, typed views by values<T>().
//
// Memory: 256³ RGBA u8 is 64 MiB, RGBA f32 256 MiB. allocate() refuses sizes beyond a limit
// (default MAX_BYTES, configurable per call) with InvalidInput instead of asking the kernel for
// memory it cannot give, so a lying file header fails before allocation.
//
// Kernels take Volume by const reference (or its spans); only io reads and writes files.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::volume {

enum class VoxelType : std::uint8_t { u8, i16, u16, f32, rgba8, rgba32f };

// Channels per voxel: 1 for scalars, 4 for RGBA.
constexpr int channels(VoxelType type) {
    return type == VoxelType::rgba8 || type == VoxelType::rgba32f ? 4 : 1;
}
// Bytes of one channel.
constexpr std::size_t bytes_per_channel(VoxelType type) {
    switch (type) {
        case VoxelType::u8:
        case VoxelType::rgba8:
            return 1;
        case VoxelType::i16:
        case VoxelType::u16:
            return 2;
        case VoxelType::f32:
        case VoxelType::rgba32f:
            return 4;
    }
    return 0;
}
constexpr std::size_t bytes_per_voxel(VoxelType type) {
    return bytes_per_channel(type) * static_cast<std::size_t>(channels(type));
}
// "u8", "i16", "u16", "f32", "rgba8", "rgba32f".
std::string_view name(VoxelType type);

// The C++ type of one channel.
template <VoxelType T>
using channel_t = std::conditional_t<
    T == VoxelType::u8 || T == VoxelType::rgba8, std::uint8_t,
    std::conditional_t<T == VoxelType::i16, std::int16_t,
                       std::conditional_t<T == VoxelType::u16, std::uint16_t, float>>>;

using Dims = std::array<std::int64_t, 3>;

// The world directions of the grid's i, j and k axes (direction[a] is column a of the rotation
// world_from_grid), unit length and orthogonal (a rotation, or a rotation with a reflection).
using Direction = std::array<Vec3d, 3>;
inline constexpr Direction IDENTITY_DIRECTION{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};

// Largest |dot| between two columns and largest ||column| − 1| set_direction accepts.
inline constexpr double DIRECTION_TOLERANCE = 1e-6;

class Volume {
public:
    // 16 GiB: above what this project's machines can hold twice.
    static constexpr std::size_t MAX_BYTES = std::size_t{16} << 30;

    Volume() = default;

    // A zero-filled volume. Throws InvalidInput when a dimension is < 1, a spacing is not finite
    // and > 0, the origin is not finite, or the data would exceed max_bytes (the message gives
    // the dims, the type and both sizes).
    static Volume allocate(const Dims& dims, VoxelType type, const Vec3d& spacing = {1, 1, 1},
                           const Vec3d& origin = {0, 0, 0}, std::size_t max_bytes = MAX_BYTES);

    const Dims& dims() const { return m_dims; }
    VoxelType type() const { return m_type; }
    const Vec3d& spacing() const { return m_spacing; }
    const Vec3d& origin() const { return m_origin; }
    void set_spacing(const Vec3d& spacing);  // finite, > 0; else InvalidInput
    void set_origin(const Vec3d& origin);    // finite; else InvalidInput

    const Direction& direction() const { return m_direction; }
    // InvalidInput (naming the columns) when the columns are not finite, unit length and
    // orthogonal within DIRECTION_TOLERANCE.
    void set_direction(const Direction& direction);
    // True when the direction is exactly the identity.
    bool is_axis_aligned() const { return m_direction == IDENTITY_DIRECTION; }

    std::int64_t num_voxels() const { return m_dims[0] * m_dims[1] * m_dims[2]; }
    std::size_t size_bytes() const { return m_data.size(); }
    bool empty() const { return m_data.empty(); }

    // The box [origin, origin + dims · spacing]: the world box the voxels cover when the volume
    // is axis-aligned; for an oriented volume, the box in the grid's own frame (what kernels that
    // ignore the direction see). world_bounds() covers an oriented volume in the world.
    AABBd bounds() const;
    // The smallest world box holding the (possibly turned) voxel box; bounds() when axis-aligned.
    AABBd world_bounds() const;
    // World position of the grid point (u, v, w) in voxel units (voxel (i, j, k)'s centre is
    // (i + 0.5, j + 0.5, k + 0.5)): origin + D · (u sx, v sy, w sz).
    Vec3d world_from_grid(const Vec3d& uvw) const;
    Vec3d voxel_center(std::int64_t i, std::int64_t j, std::int64_t k) const {
        if (is_axis_aligned()) {
            return {m_origin.x + (static_cast<double>(i) + 0.5) * m_spacing.x,
                    m_origin.y + (static_cast<double>(j) + 0.5) * m_spacing.y,
                    m_origin.z + (static_cast<double>(k) + 0.5) * m_spacing.z};
        }
        return world_from_grid({static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5,
                                static_cast<double>(k) + 0.5});
    }
    // Index of voxel (i, j, k) in voxels (multiply by channels for the channel index).
    std::int64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return i + m_dims[0] * (j + m_dims[1] * k);
    }

    std::span<std::byte> bytes() { return m_data; }
    std::span<const std::byte> bytes() const { return m_data; }

    // Typed view of all channels (num_voxels · channels values); InvalidInput when T is not the
    // volume's type.
    template <VoxelType T>
    std::span<channel_t<T>> values() {
        check_type(T);
        return {reinterpret_cast<channel_t<T>*>(m_data.data()),
                m_data.size() / sizeof(channel_t<T>)};
    }
    template <VoxelType T>
    std::span<const channel_t<T>> values() const {
        check_type(T);
        return {reinterpret_cast<const channel_t<T>*>(m_data.data()),
                m_data.size() / sizeof(channel_t<T>)};
    }

private:
    void check_type(VoxelType expected) const;

    Dims m_dims{0, 0, 0};
    VoxelType m_type = VoxelType::u8;
    Vec3d m_spacing{1.0, 1.0, 1.0};
    Vec3d m_origin{0.0, 0.0, 0.0};
    Direction m_direction = IDENTITY_DIRECTION;
    std::vector<std::byte> m_data;
};

}  // namespace pliant::volume
