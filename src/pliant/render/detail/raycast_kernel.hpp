// The ray caster's per-pixel kernel (render/raycast.hpp documents the algorithm): a pure function
// of the pixel index over a trivially copyable RayCastKernel (pointers into the RayCaster's
// arrays), GPU-style; and the chessboard distance transform of the macro-cell occupancy that
// drives its empty-space skipping.
//
// Grid coordinates: g = (p − origin) / spacing − 0.5, so voxel centre i is at g = i and the
// volume's box is [−0.5, n − 0.5]³. A trilinear sample at g reads the voxels i0 and i0 + 1 per
// axis, i0 = min(⌊clamp(g, 0, n − 1)⌋, n − 2) (its lower corner). Macro cell c (per axis) holds
// the samples whose lower corner is in [CELL·c, CELL·c + CELL − 1], so its footprint, the voxels
// those samples read, is exactly [CELL·c, CELL·c + CELL] ∩ [0, n − 1]: the occupancy test of a
// sample is exact (the same integer corner the sample reads from), and only the jumps over
// empty blocks of cells are geometric, kept inside the block by a margin (GridRay::margin).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/render/image.hpp"

namespace pliant::render::detail {

inline constexpr int LUT_SIZE = 4096;
inline constexpr int CELL = 4;        // macro cell edge, voxels (a power of two)
inline constexpr int CELL_SHIFT = 2;  // log2(CELL)
inline constexpr int SUB_CELL = 2;    // sub-cell edge (an occupancy bit each), CELL / 2
// Grid units a jump stops short of the far side of an empty block of cells, at least: far more
// than the float rounding of sample positions (≈ 1e-4 voxel for volumes of a few thousand voxels
// seen from nearby). A ray adds 2⁻¹⁸ (32 float epsilons) of the largest coordinate magnitude it
// computes, so a camera far from the volume keeps the margin above its rounding.
inline constexpr float SKIP_MARGIN = 1.0f / 32.0f;
// Bound on |trilinear value − the range of its 8 voxels|, in lookup entries, for the float lerps
// a + t·(b − a) of lookup coordinates in [0, LUT_SIZE − 1], t ∈ [0, 1]: each of the 3 levels
// of lerps adds at most 3 roundings of 2⁻²⁴ · 4096 ≈ 2.4e-4 (and a + t·0 = a exactly), plus the
// + 0.5 of the nearest entry: under 0.003, bounded here by 1/64 (the macro cells' occupancy
// test widens each cell's [min, max] by it, so no sample it skips could reach an opaque entry).
inline constexpr float LERP_ROUNDING = 1.0f / 64.0f;
inline constexpr int TILE = 16;       // pixels per tile edge
inline constexpr int MAX_CUBE = 255;  // largest stored empty-cube side, cells

// The lookup coordinate of a scalar voxel value x: (x − lo) · scale clamped to the table
// [0, LUT_SIZE − 1], 0 when not finite (scale = (LUT_SIZE − 1) / (hi − lo)).
inline float lookup_coordinate(double x, double lo, double scale) {
    const double s = (x - lo) * scale;
    return std::isfinite(s) ? static_cast<float>(std::clamp(s, 0.0, double{LUT_SIZE - 1})) : 0.0f;
}

// Everything a pixel needs, trivially copyable (pointers into the RayCaster's arrays).
struct RayCastKernel {
    // Camera.
    int width = 0, height = 0;
    bool is_perspective = true;
    Vec3f eye, forward, right, up;
    float inv_focal = 1.0f;
    // Grid coordinates g = world · inv_spacing + grid_offset (voxel centre i at g = i).
    Vec3f inv_spacing, grid_offset;
    int n[3] = {0, 0, 0};
    float g_max[3] = {0.0f, 0.0f, 0.0f};  // n − 1 per axis (the clamp of a sample)
    int max_i0[3] = {0, 0, 0};  // largest lower corner of a trilinear cell (n − 2, ≥ 0)
    std::int64_t stride[3] = {0, 0, 0};  // voxel index strides (1, nx, nx·ny)
    std::int64_t d[3] = {0, 0, 0};       // neighbour offsets in voxels (0 on axes of size 1)
    const float* values = nullptr;       // scalar lookup coordinates, or α·rgb, α
    const float* alpha = nullptr;        // RGBA shaded: α per voxel (values' 4th channel), or null
    const float* lut = nullptr;
    const float* lut_alpha = nullptr;
    // Macro cells.
    int cells[3] = {0, 0, 0};
    // Per octant o of ray directions (bit a set: the direction's component a is negative), per
    // cell: the side s (cells, ≤ MAX_CUBE) of the largest cube of empty cells with this cell as
    // its corner, extending towards o; 0 for an occupied cell.
    const std::uint8_t* empty_cube[8] = {};
    // Or null: for an orthographic camera whose direction has zero components (axis views), per
    // cell the largest of the cubes of the octants its rays may jump towards (all its rays share
    // the direction): what the march would take as the maximum over those octants, read once.
    const std::uint8_t* axis_cube = nullptr;
    // Per cell: bit (sx + 2 sy + 4 sz) set when the sub-cell of the samples with lower corner in
    // [CELL·c + SUB_CELL·s, CELL·c + SUB_CELL·s + 1] (footprint: 3³ voxels) is occupied.
    const std::uint8_t* sub_occupied = nullptr;
    const float* cell_max = nullptr;
    // Options.
    float step = 1.0f;
    float inv_step = 1.0f;
    float step_over_unit = 1.0f;  // RGBA opacity correction exponent
    float threshold = 0.99f;
    bool is_rgba = false;  // values hold α·rgb, α per voxel (else lookup coordinates)
    bool is_mip = false;
    bool shading = false;
    bool skipping = true;
    Color background;
    // Clipping plane in the kernel's frame: kept where dot(clip_normal, p) ≥ clip_offset.
    bool has_clip = false;
    Vec3f clip_normal;
    float clip_offset = 0.0f;
};
static_assert(std::is_trivially_copyable_v<RayCastKernel>);

struct PixelResult {
    Color color;
    std::int64_t samples = 0;
};

struct Sample {
    float r, g, b, a;
};

// min(max(v, lo), hi), branch-free (maxss/minss); NaN stays NaN.
PLIANT_HOST_DEVICE inline float clampf(float v, float lo, float hi) {
    const float above = v < lo ? lo : v;
    return hi < above ? hi : above;
}
PLIANT_HOST_DEVICE inline float lerp(float a, float b, float t) {
    return a + t * (b - a);
}

// Trilinear weights and the lower corner of grid point g (clamp to edge).
struct Trilinear {
    int ix, iy, iz;
    float fx, fy, fz;
};
PLIANT_HOST_DEVICE inline Trilinear locate(const RayCastKernel& k, Vec3f g) {
    const float x = clampf(g.x, 0.0f, k.g_max[0]);
    const float y = clampf(g.y, 0.0f, k.g_max[1]);
    const float z = clampf(g.z, 0.0f, k.g_max[2]);
    const int ix = std::min(static_cast<int>(x), k.max_i0[0]);
    const int iy = std::min(static_cast<int>(y), k.max_i0[1]);
    const int iz = std::min(static_cast<int>(z), k.max_i0[2]);
    return {ix,
            iy,
            iz,
            x - static_cast<float>(ix),
            y - static_cast<float>(iy),
            z - static_cast<float>(iz)};
}

PLIANT_HOST_DEVICE inline std::int64_t voxel_index(const RayCastKernel& k, const Trilinear& t) {
    return t.ix + k.stride[1] * t.iy + k.stride[2] * t.iz;
}

// The occupancy bit of the sub-cell holding the sample with lower corner t.
PLIANT_HOST_DEVICE inline int sub_cell_bit(const Trilinear& t) {
    return ((t.ix >> 1) & 1) | (((t.iy >> 1) & 1) << 1) | (((t.iz >> 1) & 1) << 2);
}

// The macro cell holding the sample with lower corner t.
PLIANT_HOST_DEVICE inline std::int64_t cell_of(const RayCastKernel& k, const Trilinear& t) {
    return (t.ix >> CELL_SHIFT) +
           static_cast<std::int64_t>(k.cells[0]) *
               ((t.iy >> CELL_SHIFT) +
                static_cast<std::int64_t>(k.cells[1]) * (t.iz >> CELL_SHIFT));
}

// The trilinear value at t of `values`, one float per voxel of k's grid (the scalars, or the α
// copy of an RGBA volume).
PLIANT_HOST_DEVICE inline float interpolate_float(const RayCastKernel& k, const float* values,
                                                  const Trilinear& t) {
    const float* p = values + voxel_index(k, t);
    const std::int64_t dx = k.d[0], dy = k.d[1], dz = k.d[2];
    const float c00 = lerp(p[0], p[dx], t.fx);
    const float c10 = lerp(p[dy], p[dy + dx], t.fx);
    const float c01 = lerp(p[dz], p[dz + dx], t.fx);
    const float c11 = lerp(p[dz + dy], p[dz + dy + dx], t.fx);
    return lerp(lerp(c00, c10, t.fy), lerp(c01, c11, t.fy), t.fz);
}

PLIANT_HOST_DEVICE inline float interpolate_scalar(const RayCastKernel& k, const Trilinear& t) {
    return interpolate_float(k, k.values, t);
}

PLIANT_HOST_DEVICE inline Sample interpolate_rgba(const RayCastKernel& k, const Trilinear& t) {
    const float* p = k.values + 4 * voxel_index(k, t);
    const std::int64_t dx = 4 * k.d[0], dy = 4 * k.d[1], dz = 4 * k.d[2];
    float out[4];
    for (int c = 0; c < 4; ++c) {
        const float c00 = lerp(p[c], p[dx + c], t.fx);
        const float c10 = lerp(p[dy + c], p[dy + dx + c], t.fx);
        const float c01 = lerp(p[dz + c], p[dz + dx + c], t.fx);
        const float c11 = lerp(p[dz + dy + c], p[dz + dy + dx + c], t.fx);
        out[c] = lerp(lerp(c00, c10, t.fy), lerp(c01, c11, t.fy), t.fz);
    }
    return {out[0], out[1], out[2], out[3]};
}

PLIANT_HOST_DEVICE inline float sample_scalar(const RayCastKernel& k, Vec3f g) {
    return interpolate_scalar(k, locate(k, g));
}

PLIANT_HOST_DEVICE inline Sample sample_rgba(const RayCastKernel& k, Vec3f g) {
    return interpolate_rgba(k, locate(k, g));
}

// The value shading differentiates: the scalar, or α.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline float shading_value(const RayCastKernel& k, Vec3f g) {
    if constexpr (IS_RGBA) {
        return sample_rgba(k, g).a;
    } else {
        return sample_scalar(k, g);
    }
}

// 0.3 + 0.7 |n · dir|, n the normalized world gradient at g; 1 when the gradient vanishes.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline float shade(const RayCastKernel& k, Vec3f g, Vec3f dir) {
    const float gx = (shading_value<IS_RGBA>(k, {g.x + 1.0f, g.y, g.z}) -
                      shading_value<IS_RGBA>(k, {g.x - 1.0f, g.y, g.z})) *
                     k.inv_spacing.x;
    const float gy = (shading_value<IS_RGBA>(k, {g.x, g.y + 1.0f, g.z}) -
                      shading_value<IS_RGBA>(k, {g.x, g.y - 1.0f, g.z})) *
                     k.inv_spacing.y;
    const float gz = (shading_value<IS_RGBA>(k, {g.x, g.y, g.z + 1.0f}) -
                      shading_value<IS_RGBA>(k, {g.x, g.y, g.z - 1.0f})) *
                     k.inv_spacing.z;
    const float len2 = gx * gx + gy * gy + gz * gz;
    if (!(len2 > 1e-30f)) {
        return 1.0f;
    }
    const float cosine = std::fabs(gx * dir.x + gy * dir.y + gz * dir.z) / std::sqrt(len2);
    return 0.3f + 0.7f * cosine;
}

// The opacity of a step for an interpolated RGBA opacity a ∈ (0, 1] per opacity unit:
// 1 − (1 − a)^(Δs/u), with e = Δs/u (the AVX2 march calls this too, for the same bits). The
// default step, half the opacity unit (e = 1/2), is 1 − √(1 − a) = a / (1 + √(1 − a)) (no
// cancellation for small a; correctly rounded square root and division, so the AVX2 march
// computes it 8 wide with the same bits); other steps go through log1p and expm1.
PLIANT_HOST_DEVICE inline float rgba_step_opacity_half(float a) {
    return a / (1.0f + std::sqrt(1.0f - a));
}
PLIANT_HOST_DEVICE inline float rgba_step_opacity(float a, float e) {
    if (a >= 1.0f) {
        return 1.0f;
    }
    return e == 0.5f ? rgba_step_opacity_half(a) : -std::expm1(e * std::log1p(-a));
}

// Classified sample with lower corner t: straight colour and opacity for one full step.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Sample classify(const RayCastKernel& k, const Trilinear& t) {
    if constexpr (IS_RGBA) {
        const Sample s = interpolate_rgba(k, t);
        const float a = clampf(s.a, 0.0f, 1.0f);
        if (!(a > 0.0f)) {
            return {0.0f, 0.0f, 0.0f, 0.0f};
        }
        const float a_step = rgba_step_opacity(a, k.step_over_unit);
        const float inv = 1.0f / s.a;
        return {s.r * inv, s.g * inv, s.b * inv, a_step};
    } else {
        const std::ptrdiff_t index = static_cast<int>(interpolate_scalar(k, t) + 0.5f);
        const float* e = k.lut + 4 * index;
        return {e[0], e[1], e[2], e[3]};
    }
}

// classify() at world point g, its colour shaded for a ray along dir when shading is on (only
// samples with opacity are shaded: the gradient costs six more lookups).
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Sample classify_shaded(const RayCastKernel& k, const Trilinear& t,
                                                 Vec3f g, Vec3f dir) {
    Sample s = classify<IS_RGBA>(k, t);
    if (s.a > 0.0f && k.shading) {
        const float f = shade<IS_RGBA>(k, g, dir);
        s.r *= f;
        s.g *= f;
        s.b *= f;
    }
    return s;
}

// The ray through pixel (i, j)'s centre, as Camera::ray computes it (in float).
PLIANT_HOST_DEVICE inline void pixel_ray(const RayCastKernel& k, int i, int j, Vec3f& origin,
                                         Vec3f& dir) {
    const float cx =
        (static_cast<float>(i) + 0.5f - 0.5f * static_cast<float>(k.width)) * k.inv_focal;
    const float cy =
        (0.5f * static_cast<float>(k.height) - (static_cast<float>(j) + 0.5f)) * k.inv_focal;
    if (k.is_perspective) {
        const Vec3f v = k.forward + cx * k.right + cy * k.up;
        origin = k.eye;
        dir = v / std::sqrt(dot(v, v));
    } else {
        origin = k.eye + cx * k.right + cy * k.up;
        dir = k.forward;
    }
}

// A ray in grid coordinates, t in world distance, clipped to the volume's box.
struct GridRay {
    Vec3f go, gd;
    float inv_gd[3];
    float t_near, t_far;
    float margin;  // grid units a jump stops short of a block's far planes
};

// Step 1: the ray in grid coordinates clipped to the box [−0.5, n − 0.5]³; false when it misses.
PLIANT_HOST_DEVICE inline bool clip_ray(const RayCastKernel& k, Vec3f origin, Vec3f dir,
                                        GridRay& r) {
    r.go = {origin.x * k.inv_spacing.x + k.grid_offset.x,
            origin.y * k.inv_spacing.y + k.grid_offset.y,
            origin.z * k.inv_spacing.z + k.grid_offset.z};
    r.gd = {dir.x * k.inv_spacing.x, dir.y * k.inv_spacing.y, dir.z * k.inv_spacing.z};
    const float inf = std::numeric_limits<float>::infinity();
    r.t_near = 0.0f;
    r.t_far = inf;
    for (int a = 0; a < 3; ++a) {
        const float o = r.go[a];
        const float dv = r.gd[a];
        const float lo = -0.5f;
        const float hi = static_cast<float>(k.n[a]) - 0.5f;
        if (dv == 0.0f) {
            r.inv_gd[a] = inf;
            if (o < lo || o > hi) {
                return false;
            }
            continue;
        }
        r.inv_gd[a] = 1.0f / dv;
        float t0 = (lo - o) * r.inv_gd[a];
        float t1 = (hi - o) * r.inv_gd[a];
        if (t0 > t1) {
            std::swap(t0, t1);
        }
        r.t_near = std::max(r.t_near, t0);
        r.t_far = std::min(r.t_far, t1);
    }
    if (k.has_clip) {
        // a + t·s ≥ 0 along the ray: a lower bound on t when s > 0, an upper bound when s < 0.
        const float a = dot(k.clip_normal, origin) - k.clip_offset;
        const float s = dot(k.clip_normal, dir);
        if (s > 0.0f) {
            r.t_near = std::max(r.t_near, -a / s);
        } else if (s < 0.0f) {
            r.t_far = std::min(r.t_far, -a / s);
        } else if (a < 0.0f) {
            return false;
        }
    }
    if (!(r.t_near < r.t_far)) {
        return false;
    }
    const float magnitude =
        std::max({std::fabs(r.go.x), std::fabs(r.go.y), std::fabs(r.go.z)}) +
        r.t_far * std::max({std::fabs(r.gd.x), std::fabs(r.gd.y), std::fabs(r.gd.z)});
    r.margin = SKIP_MARGIN + magnitude * (1.0f / 262144.0f);
    return true;
}

// The index of the first sample that may lie outside a box along ray r, at least n + 1: the box's
// far plane along axis a is at exit_pos[a] where r.gd[a] > 0 and at exit_neg[a] where
// r.gd[a] < 0 (grid coordinates). The far planes are pulled in by the ray's margin, so every
// sample strictly between n and the result lies inside the box despite rounding.
PLIANT_HOST_DEVICE inline std::int64_t sample_past_exit(const GridRay& r, const float exit_pos[3],
                                                        const float exit_neg[3], float inv_step,
                                                        std::int64_t n, std::int64_t num_full) {
    float t_exit = r.t_far;
    for (int a = 0; a < 3; ++a) {
        if (r.gd[a] > 0.0f) {
            t_exit = std::min(t_exit, (exit_pos[a] - r.margin - r.go[a]) * r.inv_gd[a]);
        } else if (r.gd[a] < 0.0f) {
            t_exit = std::min(t_exit, (exit_neg[a] + r.margin - r.go[a]) * r.inv_gd[a]);
        }
    }
    // Samples m with midpoint t_near + (m + 0.5)Δs before t_exit: m < x = (t_exit − t_near)/Δs −
    // 0.5, so the first one past is ⌈x⌉ (computed without a call to ceilf).
    const float x = (t_exit - r.t_near) * inv_step - 0.5f;
    if (!(x < static_cast<float>(num_full))) {
        return num_full;
    }
    std::int64_t n_end = 0;
    if (x > 0.0f) {
        n_end = static_cast<std::int64_t>(x);
        n_end += static_cast<float>(n_end) < x ? 1 : 0;
    }
    return std::max(n_end, n + 1);
}

// Empty-space jump from sample n (lower corner t, in an empty cell): the index of the first
// sample that may lie outside the cube of `side` cells (all empty) that has t's cell as its
// corner and extends along the ray's direction, at least n + 1 (sample_past_exit()). The cube's
// extent beyond the grid is harmless (the clamp maps samples there onto the grid's border cells,
// which are within the cube too).
PLIANT_HOST_DEVICE inline std::int64_t jump(const RayCastKernel& k, const GridRay& r,
                                            const Trilinear& t, int side, std::int64_t n,
                                            std::int64_t num_full) {
    const int c[3] = {t.ix >> CELL_SHIFT, t.iy >> CELL_SHIFT, t.iz >> CELL_SHIFT};
    float exit_pos[3], exit_neg[3];
    for (int a = 0; a < 3; ++a) {
        exit_pos[a] = static_cast<float>((c[a] + side) * CELL);
        exit_neg[a] = static_cast<float>((c[a] - side + 1) * CELL);
    }
    return sample_past_exit(r, exit_pos, exit_neg, k.inv_step, n, num_full);
}

// Adds a classified sample (straight colour, opacity a) behind the accumulated (c, acc).
PLIANT_HOST_DEVICE inline void composite(const Sample& s, float a, float& cr, float& cg, float& cb,
                                         float& acc) {
    const float w = (1.0f - acc) * a;
    cr += w * s.r;
    cg += w * s.g;
    cb += w * s.b;
    acc += w;
}

// Steps 1–2 of a pixel: its ray, clipped, and the segments of the clipped chord.
struct PixelRay {
    Vec3f dir;  // world direction of the ray (unit)
    GridRay r;
    float length = 0.0f;  // the clipped chord, world units
    std::int64_t num_segments = 0;
    std::int64_t num_full = 0;  // samples marched: every segment for MIP, all but the last else
};

// Step 1 and 2 for the ray (origin, unit dir): false when it misses the box (or the kept
// half-space).
PLIANT_HOST_DEVICE inline bool begin_ray(const RayCastKernel& k, Vec3f origin, Vec3f dir,
                                         PixelRay& p) {
    p.dir = dir;
    if (!clip_ray(k, origin, p.dir, p.r)) {
        return false;
    }
    // N segments of the step, samples at their midpoints; the last one shortened.
    p.length = p.r.t_far - p.r.t_near;
    p.num_segments =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(p.length / k.step)));
    p.num_full = k.is_mip ? p.num_segments : p.num_segments - 1;
    return true;
}

// Step 1 and 2 for pixel (i, j).
PLIANT_HOST_DEVICE inline bool begin_pixel(const RayCastKernel& k, int i, int j, PixelRay& p) {
    Vec3f origin, dir;
    pixel_ray(k, i, j, origin, dir);
    return begin_ray(k, origin, dir, p);
}

// Grid position of sample m (the midpoint of segment m).
PLIANT_HOST_DEVICE inline Vec3f sample_position(const RayCastKernel& k, const GridRay& r,
                                                std::int64_t m) {
    return r.go + (r.t_near + (static_cast<float>(m) + 0.5f) * k.step) * r.gd;
}

// What a composite march has accumulated: opacity-weighted colour and opacity.
struct Accumulated {
    float r = 0.0f, g = 0.0f, b = 0.0f, a = 0.0f;
};

// Sample s composited behind c over the shortened last segment of a ray, of length `partial`
// (0 < partial ≤ step): opacity α = 1 − (1 − α_Δs)^(partial / Δs).
PLIANT_HOST_DEVICE inline void composite_last(const Sample& s, float partial, float step,
                                              Accumulated& c) {
    if (s.a > 0.0f) {
        const float ratio = partial / step;
        const float a = s.a >= 1.0f ? 1.0f : -std::expm1(ratio * std::log1p(-s.a));
        composite(s, a, c.r, c.g, c.b, c.a);
    }
}

// The colour of c in front of the kernel's background.
PLIANT_HOST_DEVICE inline Color over_background(const RayCastKernel& k, const Accumulated& c) {
    const float rest = 1.0f - c.a;
    return {c.r + rest * k.background.r, c.g + rest * k.background.g, c.b + rest * k.background.b};
}

// The end of a composite ray after its march of p.num_full samples (or its early termination):
// the shortened last segment, of length ℓ, with α = 1 − (1 − α_Δs)^(ℓ / Δs), then the background
// behind. Adds the last sample, when classified, to `samples`.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Color end_composite(const RayCastKernel& k, const PixelRay& p,
                                              Accumulated c, std::int64_t& samples) {
    const GridRay& r = p.r;
    const float partial = p.length - static_cast<float>(p.num_segments - 1) * k.step;
    if (!(c.a > k.threshold) && partial > 0.0f) {
        const float tm =
            r.t_near + static_cast<float>(p.num_segments - 1) * k.step + 0.5f * partial;
        const Vec3f g = r.go + tm * r.gd;
        const Trilinear t = locate(k, g);
        // A cell's cube is empty (non-zero) towards every octant alike: octant 0 decides.
        if (!k.skipping || k.empty_cube[0][cell_of(k, t)] == 0) {
            ++samples;
            const Sample s = classify_shaded<IS_RGBA>(k, t, g, p.dir);
            composite_last(s, partial, k.step, c);
        }
    }
    return over_background(k, c);
}

// The octant of a ray's direction (bit a set: component a negative) and its zero components
// (bit a set: component a is zero).
PLIANT_HOST_DEVICE inline int octant_of(const GridRay& r) {
    return (r.gd.x < 0.0f ? 1 : 0) | (r.gd.y < 0.0f ? 2 : 0) | (r.gd.z < 0.0f ? 4 : 0);
}
PLIANT_HOST_DEVICE inline int zero_axes_of(const GridRay& r) {
    return (r.gd.x == 0.0f ? 1 : 0) | (r.gd.y == 0.0f ? 2 : 0) | (r.gd.z == 0.0f ? 4 : 0);
}

// Steps 3–5 of a composite ray: march its p.num_full samples front to back from the first;
// one in an empty cell jumps over the cube of empty cells that its cell starts towards the ray's
// octant instead of being classified. Returns what was accumulated (the march stops when the
// opacity exceeds the threshold) and adds the classified samples to `samples`.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Accumulated march_composite(const RayCastKernel& k, const PixelRay& p,
                                                      std::int64_t& samples) {
    const GridRay& r = p.r;
    const int octant = octant_of(r);
    const std::uint8_t* empty_cube = k.axis_cube != nullptr ? k.axis_cube : k.empty_cube[octant];
    // A ray with a zero direction component never moves along it, so the cubes towards either
    // side of that axis are valid too: up to 3 more octants (axis views have two zero
    // components), and the largest of their cubes is jumped (k.axis_cube has it already).
    const std::uint8_t* more_cubes[3] = {nullptr, nullptr, nullptr};
    int num_more = 0;
    if (k.axis_cube == nullptr) {
        const int zero = zero_axes_of(r);
        for (int flip = 1; flip < 8; ++flip) {
            if ((flip & ~zero) == 0 && num_more < 3) {
                more_cubes[num_more++] = k.empty_cube[octant ^ flip];
            }
        }
    }
    Accumulated c;
    std::int64_t n = 0;
    while (n < p.num_full) {
        const Vec3f g = sample_position(k, r, n);
        const Trilinear t = locate(k, g);
        if (k.skipping) {
            const std::int64_t cell = cell_of(k, t);
            int side = empty_cube[cell];
            for (int m = 0; m < num_more && side > 0; ++m) {
                side = std::max<int>(side, more_cubes[m][cell]);
            }
            if (side > 0) {
                n = jump(k, r, t, side, n, p.num_full);
                continue;
            }
            if (((k.sub_occupied[cell] >> sub_cell_bit(t)) & 1) == 0) {
                ++n;  // an empty sub-cell of an occupied cell: this sample only
                continue;
            }
        }
        ++samples;
        const Sample s = classify_shaded<IS_RGBA>(k, t, g, p.dir);
        if (s.a > 0.0f) {
            composite(s, s.a, c.r, c.g, c.b, c.a);
            if (c.a > k.threshold) {
                break;
            }
        }
        ++n;
    }
    return c;
}

// The pixel of a MIP ray whose largest value (scalar) or α (RGBA) is `best` (−1: nothing
// sampled), RGBA: the interpolated opacity-weighted sample that had it.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Color end_mip(const RayCastKernel& k, float best,
                                        const Sample& best_sample) {
    if (best < 0.0f) {
        return k.background;
    }
    Sample s{};
    float a = 0.0f;
    if constexpr (IS_RGBA) {
        a = clampf(best_sample.a, 0.0f, 1.0f);
        const float inv = best_sample.a > 0.0f ? 1.0f / best_sample.a : 0.0f;
        s = {best_sample.r * inv, best_sample.g * inv, best_sample.b * inv, a};
    } else {
        const std::ptrdiff_t index = static_cast<int>(best + 0.5f);
        s = {k.lut[4 * index], k.lut[4 * index + 1], k.lut[4 * index + 2], 0.0f};
        a = k.lut_alpha[index];
    }
    return {s.r * a + (1.0f - a) * k.background.r, s.g * a + (1.0f - a) * k.background.g,
            s.b * a + (1.0f - a) * k.background.b};
}

// Steps 3–5 of a ray that begin_ray / begin_pixel set up.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE PixelResult raycast_begun(const RayCastKernel& k, const PixelRay& p) {
    PixelResult result{k.background, 0};
    const GridRay& r = p.r;
    const std::int64_t num_full = p.num_full;
    std::int64_t samples = 0;
    std::int64_t n = 0;

    if (k.is_mip) {
        // MIP: a sample in a cell whose largest value does not exceed the running maximum
        // jumps to the cell's end.
        float best = -1.0f;  // largest value (or α) so far
        Sample best_sample{0.0f, 0.0f, 0.0f, 0.0f};
        while (n < num_full) {
            const Trilinear t = locate(k, sample_position(k, r, n));
            if (k.skipping && k.cell_max[cell_of(k, t)] <= best) {
                n = jump(k, r, t, 1, n, num_full);
                continue;
            }
            ++samples;
            if constexpr (IS_RGBA) {
                const Sample s = interpolate_rgba(k, t);
                if (s.a > best) {
                    best = s.a;
                    best_sample = s;
                }
            } else {
                const float v = interpolate_scalar(k, t);
                best = v > best ? v : best;
            }
            ++n;
        }
        result.samples = samples;
        result.color = end_mip<IS_RGBA>(k, best, best_sample);
        return result;
    }

    const Accumulated c = march_composite<IS_RGBA>(k, p, samples);
    result.color = end_composite<IS_RGBA>(k, p, c, samples);
    result.samples = samples;
    return result;
}

template <bool IS_RGBA>
PLIANT_HOST_DEVICE PixelResult raycast_pixel(const RayCastKernel& k, int i, int j) {
    PixelRay p;
    if (!begin_pixel(k, i, j, p)) {
        return PixelResult{k.background, 0};
    }
    return raycast_begun<IS_RGBA>(k, p);
}

// A ray of the caller's (origin relative to the volume's origin, unit direction).
template <bool IS_RGBA>
PLIANT_HOST_DEVICE PixelResult raycast_ray(const RayCastKernel& k, Vec3f origin, Vec3f dir) {
    PixelRay p;
    if (!begin_ray(k, origin, dir, p)) {
        return PixelResult{k.background, 0};
    }
    return raycast_begun<IS_RGBA>(k, p);
}

// The empty cubes of `occupied` (cells[0] · cells[1] · cells[2] flags, x fastest) towards
// `octant` (bit a set: towards −a) into `side` (same shape): 0 for an occupied cell, else
// 1 + the smallest side among the 7 neighbours c + e, e ∈ {0, 1}³ \ {0} stepped towards the octant
// (cells outside the grid count as empty cubes of MAX_CUBE), capped at MAX_CUBE. Exact: the cube
// of side s at c is c and the 7 cubes of side s − 1 at those neighbours (the 3D form of the
// largest-empty-square recurrence). One serial pass in the order that visits those neighbours
// first, row by row: the 6 neighbours in the previous row and layer first (a loop the compiler
// vectorizes), then the one along the row. O(cells · 7).
inline void empty_cubes(std::span<const std::uint8_t> occupied, const int cells[3], int octant,
                        std::span<std::uint8_t> side) {
    const std::int64_t n[3] = {cells[0], cells[1], cells[2]};
    const int dir[3] = {(octant & 1) != 0 ? -1 : 1, (octant & 2) != 0 ? -1 : 1,
                        (octant & 4) != 0 ? -1 : 1};
    const auto row_of = [&](std::int64_t y, std::int64_t z) {
        return static_cast<std::size_t>(n[0] * (y + n[1] * z));
    };
    // A row of MAX_CUBE for neighbours outside the grid, and the row minimum of the 6 neighbours
    // off the row (with x and x + dir[0]), both over x ∈ [0, n[0]).
    std::vector<std::uint8_t> outside(static_cast<std::size_t>(n[0]), MAX_CUBE);
    std::vector<std::uint8_t> off_row(static_cast<std::size_t>(n[0]));
    const std::int64_t nx = n[0];
    for (std::int64_t zi = 0; zi < n[2]; ++zi) {
        const std::int64_t z = dir[2] > 0 ? n[2] - 1 - zi : zi;
        const bool has_z = z + dir[2] >= 0 && z + dir[2] < n[2];
        for (std::int64_t yi = 0; yi < n[1]; ++yi) {
            const std::int64_t y = dir[1] > 0 ? n[1] - 1 - yi : yi;
            const bool has_y = y + dir[1] >= 0 && y + dir[1] < n[1];
            const std::uint8_t* p = has_y ? &side[row_of(y + dir[1], z)] : outside.data();
            const std::uint8_t* q = has_z ? &side[row_of(y, z + dir[2])] : outside.data();
            const std::uint8_t* r =
                has_y && has_z ? &side[row_of(y + dir[1], z + dir[2])] : outside.data();
            // Neighbours at x, then at x + dir[0] (none past the row's end): each entry read
            // before it is overwritten.
            std::uint8_t* m = off_row.data();
            for (std::int64_t x = 0; x < nx; ++x) {
                m[x] = std::min({p[x], q[x], r[x]});
            }
            if (dir[0] > 0) {
                for (std::int64_t x = 0; x + 1 < nx; ++x) {
                    m[x] = std::min(m[x], m[x + 1]);
                }
            } else {
                for (std::int64_t x = nx - 1; x >= 1; --x) {
                    m[x] = std::min(m[x], m[x - 1]);
                }
            }
            // Along the row, towards −dir[0]: each cell after its neighbour at x + dir[0].
            std::uint8_t* out = &side[row_of(y, z)];
            const std::uint8_t* occ = &occupied[row_of(y, z)];
            int previous = MAX_CUBE;  // the cube at x + dir[0], MAX_CUBE outside
            for (std::int64_t xi = 0; xi < nx; ++xi) {
                const std::int64_t x = dir[0] > 0 ? nx - 1 - xi : xi;
                const int smallest = std::min<int>(previous, m[x]);
                const int value = occ[x] != 0 ? 0 : std::min(MAX_CUBE, smallest + 1);
                out[x] = static_cast<std::uint8_t>(value);
                previous = value;
            }
        }
    }
}

}  // namespace pliant::render::detail
