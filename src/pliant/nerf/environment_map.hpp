// EnvironmentMap: a learned background for rays that leave the scene box (the room around a
// captured object, the sky), so that the voxel field need not explain it. A colour per ray
// direction, composited behind the field: C = Σ_k w_k c_k + T_end · B(d) (detail/field_kernel.hpp
// with the per-ray background B(d); NeRF++'s and Plenoxels' "background at infinity", reduced to
// a texture over directions).
//
// Parameterization: an equirectangular texture of width × height texels (height = width / 2)
// over the unit direction d = (dx, dy, dz) in the dataset's frame:
//   φ = atan2(dy, dx) ∈ [−π, π],  θ = acos(dz) ∈ [0, π]  (+z is the pole; `nerf poses` puts the
//   cameras' mean up axis there),
//   texel coordinates u = (φ + π) / (2π) · width − 0.5 (wrapping around), v = θ / π · height − 0.5
//   (clamped to [0, height − 1]); texel (i, j) holds three raw values whose sigmoid is the straight
//   colour; B(d) = sigmoid of the bilinear interpolation of the 4 texels around (u, v) (raw
//   parameters interpolated, then activated, as the field's colours are).
// Gradient: ∂L/∂B = T_end · ∂L/∂C; ∂L/∂raw_q = (∂L/∂B ⊙ B (1 − B)) · bilinear weight of texel q.
//
// Memory: 12 bytes per texel (64 × 32: 24 KiB).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/bytes.hpp"

namespace pliant::nerf {

// The four texels and bilinear weights of one direction.
struct EnvironmentTexels {
    std::array<std::int32_t, 4> index{0, 0, 0, 0};
    std::array<float, 4> weight{0, 0, 0, 0};
};

class EnvironmentMap {
public:
    EnvironmentMap() = default;
    // width texels around (height = width / 2), every raw value color_raw. InvalidInput unless
    // width is even and in [2, 4096].
    EnvironmentMap(int width, float color_raw);

    bool empty() const { return m_width == 0; }
    int width() const { return m_width; }
    int height() const { return m_height; }
    std::int64_t num_texels() const { return static_cast<std::int64_t>(m_width) * m_height; }
    std::span<float> params() { return m_params; }  // 3 · num_texels, texel i + width · j
    std::span<const float> params() const { return m_params; }

    // d: a unit direction (not checked).
    EnvironmentTexels locate(const float d[3]) const;
    // The straight colour B(d) of the located texels.
    void color(const EnvironmentTexels& t, float rgb[3]) const;
    void color(const float d[3], float rgb[3]) const { color(locate(d), rgb); }

    // Checkpoints (core/bytes.hpp): width and the raw values. load_state: InvalidInput for a
    // truncated state or another width than `width`.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in, int width);

private:
    int m_width = 0;
    int m_height = 0;
    std::vector<float> m_params;
};

}  // namespace pliant::nerf
