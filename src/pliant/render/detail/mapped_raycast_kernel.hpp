// The per-pixel kernel of render::MappedRayCaster (render/mapped_raycast.hpp documents the
// algorithm): the composite march of raycast_kernel.hpp in the deformed (target) frame, every
// sample taken from the rest (source) volume at the source grid coordinate an InverseMap gives.
// A pure function of the pixel index over trivially copyable data (GPU-style).
//
// Map cells: node cell q (per axis) of the map holds the target grid coordinates [B·q, B·q + B)
// (B = node_voxels); a sample at target grid coordinate t (clamped to [0, n − 1] as locate()
// clamps) is interpolated in node cell q = min(⌊t / B⌋, cells − 1) with fraction t / B − q.
// The occupancy test of a sample is that same cell, and empty-space jumps leave a cube of empty
// cells through its far planes pulled in by the ray's margin, as raycast_kernel.hpp's jump(); in
// a visible cell, a sample in an empty sub-cell (sub_cell_of(): the half of the cell along each
// axis its fraction lies in) jumps past that sub-cell the same way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "pliant/core/host_device.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"

namespace pliant::render::detail {

// The stored source gradient (MappedRayCaster's constructor): per source voxel i, along each
// axis a, the central difference of the shaded value (the scalar, or α) D_a(i) =
// v(min(i + e_a, n − 1)) − v(max(i − e_a, 0)) (the index clamped as locate() clamps a sample,
// so D_a(i) is shade()'s difference v(g + e_a) − v(g − e_a) at g = i), rounded to int16 with
// |D| ≤ the values' range (1 for α, LUT_SIZE − 1 for lookup coordinates) at 32767 (steps of
// 1/32767 in α, 1/8 of a lookup entry; the scale cancels in the normalized normal), then a 0:
// 4 values, 8 bytes per voxel, so a lane's x-adjacent voxel pair is one 16-byte load.
using GradientValue = std::int16_t;

// A shaded rgba8 source packs each voxel's bytes and its stored gradient in one record: r, g,
// b, α (bytes 0–3), then the gradient's 4 GradientValues (bytes 4–11: x, y, z, 0), then the
// largest α byte of the voxel's 3³ neighbourhood (the grid's voxels within one step along each
// axis; byte 12, the adaptive step's second level, thin_level()) and 3 bytes of 0, so that a
// lane's x-adjacent voxel pair of a row is one 32-byte load that holds both (MappedKernel::rgba8
// at byte 0, MappedKernel::gradient at byte 4 of the first record).
inline constexpr std::int64_t PACKED_VOXEL_BYTES = 16;
inline constexpr std::int64_t PACKED_WIDE_ALPHA = 12;  // the neighbourhood's α byte

// Occupancy bits of a map cell.
inline constexpr std::uint8_t MAP_CELL_VALID = 1;    // its 8 nodes hold source coordinates
inline constexpr std::uint8_t MAP_CELL_VISIBLE = 2;  // some sample in it may have opacity

// The opacity-adaptive step's coarsest level: runs of at most 2^MAX_THIN_LEVELS steps
// (thin_level()).
inline constexpr int MAX_THIN_LEVELS = 2;

struct MappedKernel {
    // Camera, the target frame (n, inv_spacing, grid_offset, clamp bounds) and the options;
    // its volume fields are unused.
    RayCastKernel target;
    // The source volume as a RayCaster prepares it (values, alpha, lookup table, step opacity);
    // its camera and macro-cell fields are unused.
    RayCastKernel source;
    const float* nodes = nullptr;             // 3 floats per node (InverseMap::node_coordinates())
    const float* nodes4 = nullptr;            // the same padded to 4 floats (x, y, z, 0) per node
    std::int64_t node_stride[3] = {0, 0, 0};  // in nodes: 1, nx, nx·ny
    int cells[3] = {0, 0, 0};                 // map cells per axis: nodes − 1
    float b = 4.0f;                           // node_voxels
    float inv_b = 0.25f;
    float half_b = 2.0f;                      // node_voxels / 2: a sub-cell's edge
    const std::uint8_t* occupancy = nullptr;  // per map cell: MAP_CELL_* bits
    // Per map cell: bit sub_cell_of() set when some sample in that sub-cell may have opacity
    // (0 for a cell that is not visible).
    const std::uint8_t* sub_occupied = nullptr;
    const std::uint8_t* empty_cube[8] = {};  // per octant, per map cell (empty_cubes())
    // The slabs of the visible map cells in target grid coordinates t (VISIBLE_SLABS: e_k · t
    // for the 3 axes and the 4 diagonals, set_visible_cells()), widened by VISIBLE_BOX_MARGIN per
    // axis; empty (lo > hi) when no cell is visible. With skipping, a sample outside them lies
    // in a cell that is not visible.
    float visible_lo[7] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    float visible_hi[7] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    float source_hi[3] = {0.0f, 0.0f, 0.0f};  // the source box [−0.5, n − 0.5] per axis
    // Shading: the stored source gradient, 4 GradientValue per source voxel (source_gradient());
    // null when not shading.
    const GradientValue* gradient = nullptr;
    // An rgba8 source: its bytes (r, g, b, α per voxel), read in place of source.values (null:
    // the floats of source.values), each corner premultiplied as it is read (rgba8_voxel()).
    const std::uint8_t* rgba8 = nullptr;
    // Bytes from one voxel's r to the next's (4; PACKED_VOXEL_BYTES when the voxels are packed
    // with their gradient) and GradientValues from one voxel's gradient to the next's (4;
    // PACKED_VOXEL_BYTES / 2 packed).
    std::int64_t rgba8_stride = 4;
    std::int64_t gradient_stride = 4;
    // The opacity-adaptive step (an rgba8 source; thin_levels 0: off, mapped_march()): a ray
    // is marched in runs of 2^l steps, l ≤ thin_levels, each represented by one sample at the
    // run's middle, while the largest α byte of the 8 voxels every sample reads (l = 1), and of
    // their neighbourhoods (l = 2), stays below thin_limit[l − 1] = thin_alpha / 2^(l − 1)
    // (thin_level()).
    int thin_levels = 0;
    float thin_limit[MAX_THIN_LEVELS] = {};
};
static_assert(std::is_trivially_copyable_v<MappedKernel>);

// A sample's map cell and the fraction within it.
struct MapCell {
    int q[3];
    float f[3];
    std::int64_t index;  // cell index (x fastest)
};

PLIANT_HOST_DEVICE inline MapCell locate_map(const MappedKernel& m, Vec3f g) {
    MapCell c{};
    for (int a = 0; a < 3; ++a) {
        const float x = clampf(g[a], 0.0f, m.target.g_max[a]) * m.inv_b;
        c.q[a] = std::min(static_cast<int>(x), m.cells[a] - 1);
        c.f[a] = x - static_cast<float>(c.q[a]);
    }
    c.index = c.q[0] + static_cast<std::int64_t>(m.cells[0]) *
                           (c.q[1] + static_cast<std::int64_t>(m.cells[1]) * c.q[2]);
    return c;
}

// The sub-cell of a sample in map cell c: its 2³ halves, s_a = 1 where the fraction f_a ≥ 1/2;
// bit s_x + 2 s_y + 4 s_z of MappedKernel::sub_occupied.
PLIANT_HOST_DEVICE inline int sub_cell_of(const MapCell& c) {
    return (c.f[0] >= 0.5f ? 1 : 0) | (c.f[1] >= 0.5f ? 2 : 0) | (c.f[2] >= 0.5f ? 4 : 0);
}

PLIANT_HOST_DEVICE inline bool sub_cell_occupied(const MappedKernel& m, const MapCell& c) {
    return ((m.sub_occupied[c.index] >> sub_cell_of(c)) & 1) != 0;
}

// The source grid coordinate of the sample in map cell c (trilinear in the 8 nodes) and, when
// jacobian is not null, its derivatives along the map cell's axes: jacobian[a] = B ∂g/∂t_a
// (B = node_voxels; shading normalizes the gradient, so the common factor B cancels).
PLIANT_HOST_DEVICE inline Vec3f map_coordinate(const MappedKernel& m, const MapCell& c,
                                               Vec3f* jacobian) {
    const float* p = m.nodes + 3 * (c.q[0] + m.node_stride[1] * c.q[1] + m.node_stride[2] * c.q[2]);
    const std::int64_t dx = 3, dy = 3 * m.node_stride[1], dz = 3 * m.node_stride[2];
    const std::int64_t off[8] = {0, dx, dy, dy + dx, dz, dz + dx, dz + dy, dz + dy + dx};
    const float fx = c.f[0], fy = c.f[1], fz = c.f[2];
    Vec3f out;
    for (int ch = 0; ch < 3; ++ch) {
        float v[8];
        for (int i = 0; i < 8; ++i) {
            v[i] = p[off[i] + ch];
        }
        const float e0 = lerp(v[0], v[1], fx);
        const float e1 = lerp(v[2], v[3], fx);
        const float e2 = lerp(v[4], v[5], fx);
        const float e3 = lerp(v[6], v[7], fx);
        const float f0 = lerp(e0, e1, fy);
        const float f1 = lerp(e2, e3, fy);
        out[ch] = lerp(f0, f1, fz);
        if (jacobian != nullptr) {
            jacobian[0][ch] =
                lerp(lerp(v[1] - v[0], v[3] - v[2], fy), lerp(v[5] - v[4], v[7] - v[6], fy), fz);
            jacobian[1][ch] = lerp(e1 - e0, e3 - e2, fz);
            jacobian[2][ch] = f1 - f0;
        }
    }
    return out;
}

// Channel value c of an rgba8 voxel as RayCaster's float copy holds it: c / 255 (exact in
// [0, 1], so its clamp changes nothing).
PLIANT_HOST_DEVICE inline float unit8(std::uint8_t c) {
    return static_cast<float>(c) / 255.0f;
}

// The 4 values of rgba8 voxel p in units of 1/255² (colour) and 1/255 (α): α·r, α·g, α·b, α
// for the bytes c, α (each product exact: at most 255², an integer below 2^24).
PLIANT_HOST_DEVICE inline void rgba8_voxel(const std::uint8_t* p, float out[4]) {
    const float a = static_cast<float>(p[3]);
    out[0] = static_cast<float>(p[0]) * a;
    out[1] = static_cast<float>(p[1]) * a;
    out[2] = static_cast<float>(p[2]) * a;
    out[3] = a;
}

// interpolate_rgba() of an rgba8 source at t in the units of rgba8_voxel(): the same trilinear
// operations on the corners' premultiplied values (RayCaster's float copy holds them divided by
// 255² and 255: the same values up to rounding, without a conversion per corner). max_alpha:
// the largest α byte of the 8 corners; wide_alpha: the largest of their neighbourhoods' (the
// packed records' PACKED_WIDE_ALPHA byte: every voxel within one step of the corners), +∞
// without packed records.
PLIANT_HOST_DEVICE inline Sample interpolate_rgba8(const MappedKernel& m, const Trilinear& t,
                                                   float& max_alpha, float& wide_alpha) {
    const RayCastKernel& s = m.source;
    const std::int64_t stride = m.rgba8_stride;
    const std::uint8_t* p = m.rgba8 + stride * voxel_index(s, t);
    const std::int64_t dx = stride * s.d[0], dy = stride * s.d[1], dz = stride * s.d[2];
    const std::int64_t corner[8] = {0, dx, dy, dy + dx, dz, dz + dx, dz + dy, dz + dy + dx};
    float v[8][4];
    for (int i = 0; i < 8; ++i) {
        rgba8_voxel(p + corner[i], v[i]);
    }
    max_alpha = v[0][3];
    for (int i = 1; i < 8; ++i) {
        max_alpha = std::max(max_alpha, v[i][3]);
    }
    wide_alpha = std::numeric_limits<float>::infinity();
    if (stride == PACKED_VOXEL_BYTES) {
        wide_alpha = 0.0f;
        for (const std::int64_t c : corner) {
            wide_alpha = std::max(wide_alpha, static_cast<float>(p[c + PACKED_WIDE_ALPHA]));
        }
    }
    float out[4];
    for (int c = 0; c < 4; ++c) {
        const float c00 = lerp(v[0][c], v[1][c], t.fx);
        const float c10 = lerp(v[2][c], v[3][c], t.fx);
        const float c01 = lerp(v[4][c], v[5][c], t.fx);
        const float c11 = lerp(v[6][c], v[7][c], t.fx);
        out[c] = lerp(lerp(c00, c10, t.fy), lerp(c01, c11, t.fy), t.fz);
    }
    return {out[0], out[1], out[2], out[3]};
}

// classify<true>() of the source at t, its values from the rgba8 bytes when m.rgba8 is set
// (interpolate_rgba8(): the opacity α / 255, the straight colour α·c / (255 α)); max_alpha and
// wide_alpha as interpolate_rgba8()'s (rgba8), else +∞.
PLIANT_HOST_DEVICE inline Sample classify_rgba_source(const MappedKernel& m, const Trilinear& t,
                                                      float& max_alpha, float& wide_alpha) {
    if (m.rgba8 == nullptr) {
        max_alpha = std::numeric_limits<float>::infinity();
        wide_alpha = max_alpha;
        return classify<true>(m.source, t);
    }
    const Sample s = interpolate_rgba8(m, t, max_alpha, wide_alpha);
    const float a = clampf(s.a * (1.0f / 255.0f), 0.0f, 1.0f);
    if (!(a > 0.0f)) {
        return {0.0f, 0.0f, 0.0f, 0.0f};
    }
    const float a_step = rgba_step_opacity(a, m.source.step_over_unit);
    const float inv = 1.0f / (s.a * 255.0f);
    return {s.r * inv, s.g * inv, s.b * inv, a_step};
}

// Whether source grid coordinate g lies in the source box (outside it the source is 0, as the
// resampler samples it).
PLIANT_HOST_DEVICE inline bool in_source(const MappedKernel& m, Vec3f g) {
    return g.x >= -0.5f && g.x <= m.source_hi[0] && g.y >= -0.5f && g.y <= m.source_hi[1] &&
           g.z >= -0.5f && g.z <= m.source_hi[2];
}

// The source gradient at the sample located at t: the trilinear interpolation (t's corner and
// fractions, the operations of interpolate_rgba()) of the stored per-voxel differences
// (GradientValue), converted to float exactly. The central difference of a trilinear
// interpolant one voxel apart is the trilinear interpolation of the per-voxel differences, so
// this is shade()'s gradient in the source frame, up to the quantization (the clamped border
// included: on [0, 1] both are v(1 + f) − v(0)).
PLIANT_HOST_DEVICE inline Vec3f source_gradient(const MappedKernel& m, const Trilinear& t) {
    const RayCastKernel& s = m.source;
    const std::int64_t stride = m.gradient_stride;
    const GradientValue* p = m.gradient + stride * voxel_index(s, t);
    const std::int64_t dx = stride * s.d[0], dy = stride * s.d[1], dz = stride * s.d[2];
    Vec3f out;
    for (int c = 0; c < 3; ++c) {
        const float c00 = lerp(static_cast<float>(p[c]), static_cast<float>(p[dx + c]), t.fx);
        const float c10 =
            lerp(static_cast<float>(p[dy + c]), static_cast<float>(p[dy + dx + c]), t.fx);
        const float c01 =
            lerp(static_cast<float>(p[dz + c]), static_cast<float>(p[dz + dx + c]), t.fx);
        const float c11 =
            lerp(static_cast<float>(p[dz + dy + c]), static_cast<float>(p[dz + dy + dx + c]), t.fx);
        out[c] = lerp(lerp(c00, c10, t.fy), lerp(c01, c11, t.fy), t.fz);
    }
    return out;
}

// The gradient along the target's grid axis a by the chain rule, up to the factor B common to
// the 3 axes: the source gradient d (per source voxel) times B ∂g/∂t_a (jac_a,
// map_coordinate()), then the target's 1 / spacing_a (shade()'s scale).
PLIANT_HOST_DEVICE inline float target_gradient(Vec3f d, Vec3f jac_a, float inv_spacing_a) {
    return ((d.x * jac_a.x + d.y * jac_a.y) + d.z * jac_a.z) * inv_spacing_a;
}

// The classified sample of map cell c (straight colour, opacity for a full step), shaded when
// the options ask: the gradient of the shaded value in the target frame, the stored source
// gradient at g (source_gradient()) through the map's Jacobian (target_gradient()), then
// 0.3 + 0.7 |n · dir| as shade(). Zero opacity outside the source box. max_alpha: the largest
// α byte of the source voxels the sample reads, wide_alpha that of their neighbourhoods
// (classify_rgba_source()); both 0 outside the source box, +∞ for sources other than rgba8.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Sample mapped_classify(const MappedKernel& m, const MapCell& c, Vec3f dir,
                                                 float& max_alpha, float& wide_alpha) {
    const RayCastKernel& s = m.source;
    Vec3f jac[3];
    const Vec3f g = map_coordinate(m, c, m.target.shading ? jac : nullptr);
    if (!in_source(m, g)) {
        max_alpha = 0.0f;
        wide_alpha = 0.0f;
        return {0.0f, 0.0f, 0.0f, 0.0f};
    }
    const Trilinear t = locate(s, g);
    Sample out;
    if constexpr (IS_RGBA) {
        out = classify_rgba_source(m, t, max_alpha, wide_alpha);
    } else {
        max_alpha = std::numeric_limits<float>::infinity();
        wide_alpha = max_alpha;
        out = classify<false>(s, t);
    }
    if (out.a > 0.0f && m.target.shading) {
        const Vec3f d = source_gradient(m, t);
        const Vec3f& inv = m.target.inv_spacing;
        const float gx = target_gradient(d, jac[0], inv.x);
        const float gy = target_gradient(d, jac[1], inv.y);
        const float gz = target_gradient(d, jac[2], inv.z);
        const float len2 = gx * gx + gy * gy + gz * gz;
        if (len2 > 1e-30f) {
            const float cosine = std::fabs(gx * dir.x + gy * dir.y + gz * dir.z) / std::sqrt(len2);
            const float f = 0.3f + 0.7f * cosine;
            out.r *= f;
            out.g *= f;
            out.b *= f;
        }
    }
    return out;
}

// Target grid units per axis MappedKernel's slabs of the visible cells are widened by (far above
// the float rounding of sample positions below a few thousand).
inline constexpr float VISIBLE_BOX_MARGIN = 1.0f / 16.0f;

// The directions e_k of the visible cells' slabs: the 3 axes, then the 4 diagonals (a 14-sided
// polytope around the visible cells; a box alone leaves its corners, empty around a rounded
// body, to the empty-cube jumps).
inline constexpr int VISIBLE_SLABS = 7;
inline constexpr int SLAB_SIGNS[VISIBLE_SLABS][3] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1},  {1, 1, 1},
                                                     {1, 1, -1}, {1, -1, 1}, {1, -1, -1}};

// The extents of a set of map cells along the slabs: per slab k the smallest and largest
// L_k(c) = Σ_a (s_ka > 0 ? c_a : s_ka < 0 ? −c_a − 1 : 0) over the cells c (s = SLAB_SIGNS),
// so that every point t of cell c (B target voxels per cell) has e_k · t in [B L_k(c),
// B (L_k(c) + |s_k|₁)].
struct VisibleCells {
    std::int64_t lo[VISIBLE_SLABS];
    std::int64_t hi[VISIBLE_SLABS];
    VisibleCells() {
        for (int k = 0; k < VISIBLE_SLABS; ++k) {
            lo[k] = std::numeric_limits<std::int64_t>::max();
            hi[k] = std::numeric_limits<std::int64_t>::min();
        }
    }
    bool empty() const { return lo[0] > hi[0]; }
    void add(const std::int64_t c[3]) {
        for (int k = 0; k < VISIBLE_SLABS; ++k) {
            std::int64_t l = 0;
            for (int a = 0; a < 3; ++a) {
                l += SLAB_SIGNS[k][a] > 0 ? c[a] : SLAB_SIGNS[k][a] < 0 ? -c[a] - 1 : 0;
            }
            lo[k] = std::min(lo[k], l);
            hi[k] = std::max(hi[k], l);
        }
    }
    void merge(const VisibleCells& o) {
        for (int k = 0; k < VISIBLE_SLABS; ++k) {
            lo[k] = std::min(lo[k], o.lo[k]);
            hi[k] = std::max(hi[k], o.hi[k]);
        }
    }
};

// Sets m.visible_lo / visible_hi from the visible cells v (uses m.b and m.cells). The clamp of
// locate_map() puts samples beyond the grid into its border cells: an axis slab is open (−∞ /
// +∞) on a side where a visible cell lies at the grid's border, and the diagonal slabs are
// open when any does.
inline void set_visible_cells(MappedKernel& m, const VisibleCells& v) {
    const float inf = std::numeric_limits<float>::infinity();
    if (v.empty()) {
        for (int k = 0; k < VISIBLE_SLABS; ++k) {
            m.visible_lo[k] = inf;
            m.visible_hi[k] = -inf;
        }
        return;
    }
    bool border = false;
    for (int k = 0; k < VISIBLE_SLABS; ++k) {
        const int width =
            std::abs(SLAB_SIGNS[k][0]) + std::abs(SLAB_SIGNS[k][1]) + std::abs(SLAB_SIGNS[k][2]);
        const float margin = static_cast<float>(width) * VISIBLE_BOX_MARGIN;
        m.visible_lo[k] = static_cast<float>(v.lo[k]) * m.b - margin;
        m.visible_hi[k] = static_cast<float>(v.hi[k] + width) * m.b + margin;
        if (k < 3) {
            if (v.lo[k] == 0) {
                m.visible_lo[k] = -inf;
                border = true;
            }
            if (v.hi[k] == m.cells[k] - 1) {
                m.visible_hi[k] = inf;
                border = true;
            }
        } else if (border) {
            m.visible_lo[k] = -inf;
            m.visible_hi[k] = inf;
        }
    }
}

// The samples [first, end) of ray r (num_full full samples) that may lie in the slabs of the
// visible cells (MappedKernel::visible_lo / visible_hi); with skipping, the others lie in cells
// that are not visible, which the march passes over without classifying them, so marching
// [first, end) alone gives the same colour and samples. The ray's parameter interval in the
// slabs, then the samples whose midpoints t_near + (m + ½)Δs lie in it, one more on each side
// (rounding). Returns the whole [0, num_full) when the interval is not finite.
PLIANT_HOST_DEVICE inline void visible_samples(const MappedKernel& m, const GridRay& r,
                                               std::int64_t num_full, std::int64_t& first,
                                               std::int64_t& end) {
    first = 0;
    end = num_full;
    double t0 = r.t_near;
    double t1 = r.t_far;
    for (int k = 0; k < VISIBLE_SLABS; ++k) {
        const double lo = m.visible_lo[k];
        const double hi = m.visible_hi[k];
        if (!(lo <= hi)) {
            first = end = num_full;  // no visible cell
            return;
        }
        double o = 0.0, d = 0.0;
        for (int a = 0; a < 3; ++a) {
            o += SLAB_SIGNS[k][a] * static_cast<double>(r.go[a]);
            d += SLAB_SIGNS[k][a] * static_cast<double>(r.gd[a]);
        }
        if (d == 0.0) {
            if (o < lo || o > hi) {
                first = end = num_full;
                return;
            }
            continue;
        }
        const double ta = (lo - o) / d;
        const double tb = (hi - o) / d;
        t0 = std::max(t0, std::min(ta, tb));
        t1 = std::min(t1, std::max(ta, tb));
    }
    if (t0 > t1) {
        first = end = num_full;  // the ray misses the slabs
        return;
    }
    if (!(t0 <= t1)) {
        return;  // NaN: the whole ray
    }
    const double step = m.target.step;
    const double x0 = (t0 - r.t_near) / step - 0.5;
    const double x1 = (t1 - r.t_near) / step - 0.5;
    if (std::isfinite(x0) && x0 > 1.0) {
        first = std::min(num_full, static_cast<std::int64_t>(std::min(x0, 1e18)) - 1);
    }
    if (std::isfinite(x1)) {
        end = x1 < 0.0 ? std::min<std::int64_t>(num_full, 2)
                       : std::min(num_full, static_cast<std::int64_t>(std::min(x1, 1e18)) + 2);
    }
    end = std::max(end, first);
}

// jump() for map cells: the first sample past the cube of `side` empty map cells that has c as
// its corner and extends along the ray, at least n + 1.
PLIANT_HOST_DEVICE inline std::int64_t map_jump(const MappedKernel& m, const GridRay& r,
                                                const MapCell& c, int side, std::int64_t n,
                                                std::int64_t num_full) {
    float exit_pos[3], exit_neg[3];
    for (int a = 0; a < 3; ++a) {
        exit_pos[a] = static_cast<float>(c.q[a] + side) * m.b;
        exit_neg[a] = static_cast<float>(c.q[a] - side + 1) * m.b;
    }
    return sample_past_exit(r, exit_pos, exit_neg, m.target.inv_step, n, num_full);
}

// The first sample past the empty sub-cell that holds sample n (in map cell c), at least n + 1:
// map_jump() of a cube of one sub-cell, B / 2 target voxels wide, at sub-cell 2 q + s.
PLIANT_HOST_DEVICE inline std::int64_t sub_cell_jump(const MappedKernel& m, const GridRay& r,
                                                     const MapCell& c, std::int64_t n,
                                                     std::int64_t num_full) {
    float exit_pos[3], exit_neg[3];
    const int s = sub_cell_of(c);
    for (int a = 0; a < 3; ++a) {
        const int sub = 2 * c.q[a] + ((s >> a) & 1);
        exit_pos[a] = static_cast<float>(sub + 1) * m.half_b;
        exit_neg[a] = static_cast<float>(sub - 1 + 1) * m.half_b;
    }
    return sample_past_exit(r, exit_pos, exit_neg, m.target.inv_step, n, num_full);
}

// The end of a composite ray through the map after its march (end_composite() through the map):
// the shortened last segment when the ray is not opaque and that sample's cell is valid (visible,
// and its sub-cell too, when skipping), then the background behind. Adds the last sample, when
// classified, to `samples`.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Color mapped_end(const MappedKernel& m, const PixelRay& p, Accumulated c,
                                           std::int64_t& samples) {
    const RayCastKernel& k = m.target;
    const GridRay& r = p.r;
    const float partial = p.length - static_cast<float>(p.num_segments - 1) * k.step;
    if (!(c.a > k.threshold) && partial > 0.0f) {
        const float tm =
            r.t_near + static_cast<float>(p.num_segments - 1) * k.step + 0.5f * partial;
        const MapCell cell = locate_map(m, r.go + tm * r.gd);
        const std::uint8_t need = k.skipping ? MAP_CELL_VISIBLE : MAP_CELL_VALID;
        if ((m.occupancy[cell.index] & need) != 0 && (!k.skipping || sub_cell_occupied(m, cell))) {
            ++samples;
            float max_alpha = 0.0f, wide_alpha = 0.0f;
            const Sample s = mapped_classify<IS_RGBA>(m, cell, p.dir, max_alpha, wide_alpha);
            composite_last(s, partial, k.step, c);
        }
    }
    return over_background(k, c);
}

// The opacity-adaptive step (MappedKernel::thin_levels > 0). A ray is marched in runs of 2^l
// segments, l = 0 … thin_levels: the run of segments n … n + 2^l − 1 (each of length Δs) is one
// sample at the run's middle t_near + (n + 2^l / 2)Δs (for l = 0 segment n's midpoint, as
// without the adaptive step), with the step opacity of 2^l Δs, α_2Δs = α_Δs (2 − α_Δs) applied
// l times (the opacity correction of RayCaster for a step 2^l times as long). The level a
// sample allows (thin_level()): 1 when every voxel it read has an α byte below thin_limit[0] =
// thin_alpha (the haze of a radiance field); 2 when, besides, every voxel within one voxel step
// of those has one below thin_limit[1] = thin_alpha / 2 (the packed records' neighbourhood byte:
// the voxels a run of 4 steps of half a voxel can read, also where its middle sample does not;
// a run twice as long asks for half the opacity, so that its error stays of the same order).
// The ray starts at the coarsest level; after a sample it wants the level that sample allows;
// it takes the level it wants while the run fits in its segments (level_at()). A sample that
// does not allow its own run's level is discarded (counted, not composited) and the run is
// marched again at the level it allows. So where the source is not thin the samples are those
// of the fixed step; where it is, a run of up to 4 steps is one sample (docs/journal/
// 2026-11-30-dense.md and 2026-11-30-thin-levels.md measure the PSNR against the fixed step).
// Empty-space skipping lands on the runs of the coarsest level that a march through the empty
// region would have taken had its samples all allowed that level (thin_jump()). With one level
// they do (samples in empty cells read only α = 0), so images are the same with and without
// skipping; the second level's neighbourhood can reach a visible voxel from an empty cell, so
// with it a march that classifies such samples may take finer runs there, and its samples after
// the region may differ in phase (tests: PSNR ≥ 65 dB between the two).
inline constexpr float THIN_ALPHA_BYTES = 32.0f;  // MappedRayCaster's default thin_alpha

// The coarsest level (0 … thin_levels) a sample allows whose 8 voxels' largest α byte is
// max_alpha and their neighbourhoods' wide_alpha (≥ max_alpha; mapped_classify()).
PLIANT_HOST_DEVICE inline int thin_level(const MappedKernel& m, float max_alpha, float wide_alpha) {
    static_assert(MAX_THIN_LEVELS == 2);
    const int first = m.thin_levels >= 1 && max_alpha < m.thin_limit[0] ? 1 : 0;
    const int second = m.thin_levels >= 2 && wide_alpha < m.thin_limit[1] ? 1 : 0;
    return first + second;
}

// The level of the run from segment n of a ray with `total` segments that wants level `want`:
// the coarsest l ≤ want whose run fits, n + 2^l ≤ total.
PLIANT_HOST_DEVICE inline int level_at(int want, std::int64_t n, std::int64_t total) {
    int level = want;
    while (level > 0 && n + (std::int64_t{1} << level) > total) {
        --level;
    }
    return level;
}

// The sample position of the run of 2^level segments from segment n (adaptive step).
PLIANT_HOST_DEVICE inline Vec3f adaptive_position(const RayCastKernel& k, const GridRay& r,
                                                  std::int64_t n, int level) {
    const float middle = 0.5f * static_cast<float>(std::int64_t{1} << level);
    return r.go + (r.t_near + (static_cast<float>(n) + middle) * k.step) * r.gd;
}

// The step opacity of a run of 2^level segments from that of one segment α_Δs.
PLIANT_HOST_DEVICE inline float run_opacity(float a, int level) {
    for (int l = 0; l < level; ++l) {
        a = a * (2.0f - a);
    }
    return a;
}

// The next segment of an adaptive march after a jump from the run that ends at first = n + span
// to past, the first segment past the empty region (map_jump(), sub_cell_jump(); at most end):
// a march whose samples there all allowed the coarsest level would have gone on from `first`
// in runs of `lattice` = 2^levels segments: the last start at or before past (the runs skipped
// end at or before past, so their samples lie in the region), at least `first`. From end on,
// the march ends either way (the samples there lie in no visible cell).
PLIANT_HOST_DEVICE inline std::int64_t thin_jump(std::int64_t first, std::int64_t lattice,
                                                 std::int64_t past, std::int64_t end) {
    if (past >= end) {
        return past;
    }
    return std::max(first, first + ((past - first) & ~(lattice - 1)));
}

// The march of a composite ray through the map (march_composite() through the map): its
// p.num_full samples front to back; a sample in an empty map cell jumps over the cube of empty
// cells its cell starts towards the ray's octant(s) (skipping), one in an empty sub-cell of a
// visible cell past that sub-cell (sub_cell_jump()), or, without skipping, a sample in
// a cell without a valid map (a node outside and away from the deformed body) is passed over,
// transparent and not counted. With the adaptive step (thin_alpha > 0) thin stretches are
// sampled in coarse samples (above; a ray's pairs start at even samples). Stops when the
// opacity exceeds the threshold. Adds the classified samples to `samples`.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Accumulated mapped_march(const MappedKernel& m, const PixelRay& p,
                                                   std::int64_t& samples) {
    const RayCastKernel& k = m.target;
    const GridRay& r = p.r;
    const int octant = octant_of(r);
    const std::uint8_t* cubes[4] = {m.empty_cube[octant], nullptr, nullptr, nullptr};
    int num_cubes = 1;
    const int zero = zero_axes_of(r);
    for (int flip = 1; flip < 8; ++flip) {
        if ((flip & ~zero) == 0 && num_cubes < 4) {
            cubes[num_cubes++] = m.empty_cube[octant ^ flip];
        }
    }
    const int levels = m.thin_levels;  // 0: the fixed step
    const std::int64_t lattice = std::int64_t{1} << levels;
    Accumulated c;
    std::int64_t n = 0;
    std::int64_t end = p.num_full;
    if (k.skipping) {
        visible_samples(m, r, p.num_full, n, end);
    }
    n &= ~(lattice - 1);  // the runs of the coarsest level from segment 0
    int want = levels;
    while (n < end) {
        const int level = level_at(want, n, p.num_full);
        const std::int64_t span = std::int64_t{1} << level;
        const MapCell cell = locate_map(m, adaptive_position(k, r, n, level));
        if (k.skipping) {
            int side = cubes[0][cell.index];
            for (int q = 1; q < num_cubes && side > 0; ++q) {
                side = std::max<int>(side, cubes[q][cell.index]);
            }
            const bool empty_sub_cell = side == 0 && !sub_cell_occupied(m, cell);
            if (side > 0 || empty_sub_cell) {
                const std::int64_t past = side > 0 ? map_jump(m, r, cell, side, n, end)
                                                   : sub_cell_jump(m, r, cell, n, end);
                n = levels > 0 ? thin_jump(n + span, lattice, past, end) : past;
                want = levels;
                continue;
            }
        } else if ((m.occupancy[cell.index] & MAP_CELL_VALID) == 0) {
            n += span;
            want = levels;
            continue;
        }
        ++samples;
        float max_alpha = 0.0f, wide_alpha = 0.0f;
        const Sample s = mapped_classify<IS_RGBA>(m, cell, p.dir, max_alpha, wide_alpha);
        want = thin_level(m, max_alpha, wide_alpha);
        if (want < level) {
            continue;  // the run again, at the level this sample allows
        }
        n += span;
        const float a = run_opacity(s.a, level);
        if (a > 0.0f) {
            composite(s, a, c.r, c.g, c.b, c.a);
            if (c.a > k.threshold) {
                break;
            }
        }
    }
    return c;
}

// A composite pixel through the map: mapped_march(), then mapped_end().
template <bool IS_RGBA>
PLIANT_HOST_DEVICE PixelResult mapped_pixel(const MappedKernel& m, int i, int j) {
    PixelRay p;
    if (!begin_pixel(m.target, i, j, p)) {
        return PixelResult{m.target.background, 0};
    }
    std::int64_t samples = 0;
    const Accumulated c = mapped_march<IS_RGBA>(m, p, samples);
    const Color color = mapped_end<IS_RGBA>(m, p, c, samples);
    return {color, samples};
}

}  // namespace pliant::render::detail
