#include "pliant/render/raycast.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/core/host_device.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::render {
namespace detail {

constexpr int LUT_SIZE = 4096;
constexpr int CELL = 8;    // macro cell edge, voxels
constexpr int BORDER = 2;  // voxels around a cell in its footprint (trilinear + float slack)
constexpr int TILE = 16;   // pixels per tile edge

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
    int max_i0[3] = {0, 0, 0};      // largest lower corner of a trilinear cell (n − 2, ≥ 0)
    std::int64_t d[3] = {0, 0, 0};  // neighbour offsets in voxels (0 on axes of size 1)
    const float* values = nullptr;  // scalar lookup coordinates, or α·rgb, α
    const float* lut = nullptr;
    const float* lut_alpha = nullptr;
    // Macro cells.
    int cells[3] = {0, 0, 0};
    const std::uint8_t* occupied = nullptr;
    const float* cell_max = nullptr;
    // Options.
    float step = 1.0f;
    float step_over_unit = 1.0f;  // RGBA opacity correction exponent
    float threshold = 0.99f;
    bool is_mip = false;
    bool shading = false;
    bool skipping = true;
    Color background;
};
static_assert(std::is_trivially_copyable_v<RayCastKernel>);

struct PixelResult {
    Color color;
    std::int64_t samples = 0;
};

struct Sample {
    float r, g, b, a;
};

PLIANT_HOST_DEVICE inline float clampf(float v, float lo, float hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}
PLIANT_HOST_DEVICE inline float lerp(float a, float b, float t) {
    return a + t * (b - a);
}

// Trilinear weights and the base voxel index of grid point g (clamp to edge).
struct Trilinear {
    std::int64_t base;
    float fx, fy, fz;
};
PLIANT_HOST_DEVICE inline Trilinear locate(const RayCastKernel& k, Vec3f g) {
    const float x = clampf(g.x, 0.0f, static_cast<float>(k.n[0] - 1));
    const float y = clampf(g.y, 0.0f, static_cast<float>(k.n[1] - 1));
    const float z = clampf(g.z, 0.0f, static_cast<float>(k.n[2] - 1));
    const int ix = std::min(static_cast<int>(x), k.max_i0[0]);
    const int iy = std::min(static_cast<int>(y), k.max_i0[1]);
    const int iz = std::min(static_cast<int>(z), k.max_i0[2]);
    const std::int64_t sy = k.n[0];
    const std::int64_t sz = sy * k.n[1];
    return {ix + sy * iy + sz * iz, x - static_cast<float>(ix), y - static_cast<float>(iy),
            z - static_cast<float>(iz)};
}

PLIANT_HOST_DEVICE inline float sample_scalar(const RayCastKernel& k, Vec3f g) {
    const Trilinear t = locate(k, g);
    const float* p = k.values + t.base;
    const std::int64_t dx = k.d[0], dy = k.d[1], dz = k.d[2];
    const float c00 = lerp(p[0], p[dx], t.fx);
    const float c10 = lerp(p[dy], p[dy + dx], t.fx);
    const float c01 = lerp(p[dz], p[dz + dx], t.fx);
    const float c11 = lerp(p[dz + dy], p[dz + dy + dx], t.fx);
    return lerp(lerp(c00, c10, t.fy), lerp(c01, c11, t.fy), t.fz);
}

PLIANT_HOST_DEVICE inline Sample sample_rgba(const RayCastKernel& k, Vec3f g) {
    const Trilinear t = locate(k, g);
    const float* p = k.values + 4 * t.base;
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

// Classified sample at g: straight colour and opacity for one full step.
template <bool IS_RGBA>
PLIANT_HOST_DEVICE inline Sample classify(const RayCastKernel& k, Vec3f g) {
    if constexpr (IS_RGBA) {
        const Sample s = sample_rgba(k, g);
        const float a = clampf(s.a, 0.0f, 1.0f);
        if (!(a > 0.0f)) {
            return {0.0f, 0.0f, 0.0f, 0.0f};
        }
        const float a_step = a >= 1.0f ? 1.0f : -std::expm1(k.step_over_unit * std::log1p(-a));
        const float inv = 1.0f / s.a;
        return {s.r * inv, s.g * inv, s.b * inv, a_step};
    } else {
        const int index = static_cast<int>(sample_scalar(k, g) + 0.5f);
        const float* e = k.lut + 4 * index;
        return {e[0], e[1], e[2], e[3]};
    }
}

PLIANT_HOST_DEVICE inline int cell_of(const RayCastKernel& k, float g, int axis) {
    const int c = static_cast<int>((g + 0.5f) * (1.0f / CELL));
    return c < 0 ? 0 : (c >= k.cells[axis] ? k.cells[axis] - 1 : c);
}

PLIANT_HOST_DEVICE inline std::int64_t cell_index(const RayCastKernel& k, int cx, int cy, int cz) {
    return cx + static_cast<std::int64_t>(k.cells[0]) *
                    (cy + static_cast<std::int64_t>(k.cells[1]) * cz);
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

template <bool IS_RGBA>
PLIANT_HOST_DEVICE PixelResult raycast_pixel(const RayCastKernel& k, int i, int j) {
    PixelResult result{k.background, 0};
    Vec3f origin, dir;
    pixel_ray(k, i, j, origin, dir);
    // Step 1: the ray in grid coordinates (t stays world distance) clipped to the box
    // [−0.5, n − 0.5]³.
    const Vec3f go{origin.x * k.inv_spacing.x + k.grid_offset.x,
                   origin.y * k.inv_spacing.y + k.grid_offset.y,
                   origin.z * k.inv_spacing.z + k.grid_offset.z};
    const Vec3f gd{dir.x * k.inv_spacing.x, dir.y * k.inv_spacing.y, dir.z * k.inv_spacing.z};
    const float inf = std::numeric_limits<float>::infinity();
    float t_near = 0.0f;
    float t_far = inf;
    float inv_gd[3];
    for (int a = 0; a < 3; ++a) {
        const float o = go[a];
        const float dv = gd[a];
        const float lo = -0.5f;
        const float hi = static_cast<float>(k.n[a]) - 0.5f;
        if (dv == 0.0f) {
            inv_gd[a] = inf;
            if (o < lo || o > hi) {
                return result;
            }
            continue;
        }
        inv_gd[a] = 1.0f / dv;
        float t0 = (lo - o) * inv_gd[a];
        float t1 = (hi - o) * inv_gd[a];
        if (t0 > t1) {
            std::swap(t0, t1);
        }
        t_near = std::max(t_near, t0);
        t_far = std::min(t_far, t1);
    }
    if (!(t_near < t_far)) {
        return result;
    }
    // Step 2: N segments of the step, samples at their midpoints; the last one shortened.
    const float length = t_far - t_near;
    const auto num_segments =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(length / k.step)));
    const std::int64_t num_full = k.is_mip ? num_segments : num_segments - 1;
    float cr = 0.0f, cg = 0.0f, cb = 0.0f, acc = 0.0f;
    float best = -1.0f;  // MIP: largest value (or α) so far
    Sample best_sample{0.0f, 0.0f, 0.0f, 0.0f};
    std::int64_t samples = 0;
    std::int64_t n = 0;
    // Step 3–5: walk the macro cells; march the samples of occupied ones.
    while (n < num_full) {
        const float t = t_near + (static_cast<float>(n) + 0.5f) * k.step;
        const Vec3f g = go + t * gd;
        const int c[3] = {cell_of(k, g.x, 0), cell_of(k, g.y, 1), cell_of(k, g.z, 2)};
        float t_exit = t_far;
        for (int a = 0; a < 3; ++a) {
            if (gd[a] > 0.0f) {
                t_exit = std::min(
                    t_exit, (static_cast<float>((c[a] + 1) * CELL) - 0.5f - go[a]) * inv_gd[a]);
            } else if (gd[a] < 0.0f) {
                t_exit =
                    std::min(t_exit, (static_cast<float>(c[a] * CELL) - 0.5f - go[a]) * inv_gd[a]);
            }
        }
        const float last = std::ceil((t_exit - t_near) / k.step - 0.5f);
        std::int64_t n_end = last >= static_cast<float>(num_full)
                                 ? num_full
                                 : static_cast<std::int64_t>(std::max(last, 0.0f));
        n_end = std::max(n_end, n + 1);
        const std::int64_t cell = cell_index(k, c[0], c[1], c[2]);
        if (k.is_mip) {
            if (k.skipping && k.cell_max[cell] <= best) {
                n = n_end;
                continue;
            }
            for (; n < n_end; ++n) {
                const Vec3f gs = go + (t_near + (static_cast<float>(n) + 0.5f) * k.step) * gd;
                ++samples;
                if constexpr (IS_RGBA) {
                    const Sample s = sample_rgba(k, gs);
                    if (s.a > best) {
                        best = s.a;
                        best_sample = s;
                    }
                } else {
                    const float v = sample_scalar(k, gs);
                    best = v > best ? v : best;
                }
            }
            continue;
        }
        if (k.skipping && k.occupied[cell] == 0) {
            n = n_end;
            continue;
        }
        for (; n < n_end; ++n) {
            const Vec3f gs = go + (t_near + (static_cast<float>(n) + 0.5f) * k.step) * gd;
            ++samples;
            Sample s = classify<IS_RGBA>(k, gs);
            if (s.a > 0.0f) {
                if (k.shading) {
                    const float f = shade<IS_RGBA>(k, gs, dir);
                    s.r *= f;
                    s.g *= f;
                    s.b *= f;
                }
                const float w = (1.0f - acc) * s.a;
                cr += w * s.r;
                cg += w * s.g;
                cb += w * s.b;
                acc += w;
                if (acc > k.threshold) {
                    break;
                }
            }
        }
        if (acc > k.threshold) {
            break;
        }
    }
    if (k.is_mip) {
        result.samples = samples;
        if (best < 0.0f) {
            return result;
        }
        Sample s{};
        float a = 0.0f;
        if constexpr (IS_RGBA) {
            a = clampf(best_sample.a, 0.0f, 1.0f);
            const float inv = best_sample.a > 0.0f ? 1.0f / best_sample.a : 0.0f;
            s = {best_sample.r * inv, best_sample.g * inv, best_sample.b * inv, a};
        } else {
            const int index = static_cast<int>(best + 0.5f);
            s = {k.lut[4 * index], k.lut[4 * index + 1], k.lut[4 * index + 2], 0.0f};
            a = k.lut_alpha[index];
        }
        result.color = {s.r * a + (1.0f - a) * k.background.r,
                        s.g * a + (1.0f - a) * k.background.g,
                        s.b * a + (1.0f - a) * k.background.b};
        return result;
    }
    // The shortened last segment, of length ℓ: α = 1 − (1 − α_Δs)^(ℓ / Δs).
    if (!(acc > k.threshold)) {
        const float partial = length - static_cast<float>(num_segments - 1) * k.step;
        const float t = t_near + static_cast<float>(num_segments - 1) * k.step + 0.5f * partial;
        const Vec3f g = go + t * gd;
        const std::int64_t cell =
            cell_index(k, cell_of(k, g.x, 0), cell_of(k, g.y, 1), cell_of(k, g.z, 2));
        if (partial > 0.0f && (!k.skipping || k.occupied[cell] != 0)) {
            ++samples;
            Sample s = classify<IS_RGBA>(k, g);
            if (s.a > 0.0f) {
                if (k.shading) {
                    const float f = shade<IS_RGBA>(k, g, dir);
                    s.r *= f;
                    s.g *= f;
                    s.b *= f;
                }
                const float ratio = partial / k.step;
                const float a = s.a >= 1.0f ? 1.0f : -std::expm1(ratio * std::log1p(-s.a));
                const float w = (1.0f - acc) * a;
                cr += w * s.r;
                cg += w * s.g;
                cb += w * s.b;
                acc += w;
            }
        }
    }
    const float rest = 1.0f - acc;
    result.color = {cr + rest * k.background.r, cg + rest * k.background.g,
                    cb + rest * k.background.b};
    result.samples = samples;
    return result;
}

}  // namespace detail

namespace {

double smallest(const Vec3d& s) {
    return std::min({s.x, s.y, s.z});
}

void check_options(const RayCastOptions& o) {
    if (!std::isfinite(o.step) || o.step < 0.0) {
        throw InvalidInput(
            fmt::format("raycast: options.step ({}) must be finite and >= 0 (0: default)", o.step));
    }
    if (!std::isfinite(o.opacity_unit) || o.opacity_unit < 0.0) {
        throw InvalidInput(fmt::format(
            "raycast: options.opacity_unit ({}) must be finite and >= 0 (0: smallest spacing)",
            o.opacity_unit));
    }
    if (!(o.early_termination > 0.0 && o.early_termination <= 1.0)) {
        throw InvalidInput(fmt::format("raycast: options.early_termination ({}) must be in (0, 1]",
                                       o.early_termination));
    }
    const Color& b = o.background;
    for (const float v : {b.r, b.g, b.b}) {
        if (!(v >= 0.0f && v <= 1.0f)) {
            throw InvalidInput(fmt::format(
                "raycast: options.background ({}, {}, {}) must have components in [0, 1]", b.r, b.g,
                b.b));
        }
    }
}

template <volume::VoxelType T>
void to_lookup_coordinates(const volume::Volume& v, double lo, double scale,
                           std::vector<float>& out) {
    const auto values = v.values<T>();
    out.resize(values.size());
    parallel_for(static_cast<std::int64_t>(values.size()), [&](std::int64_t i) {
        const double x = static_cast<double>(values[static_cast<std::size_t>(i)]);
        const double s = (x - lo) * scale;
        out[static_cast<std::size_t>(i)] =
            std::isfinite(s) ? static_cast<float>(std::clamp(s, 0.0, double{detail::LUT_SIZE - 1}))
                             : 0.0f;
    });
}

}  // namespace

double default_step(const volume::Volume& volume, const RayCastOptions& options) {
    return options.step > 0.0 ? options.step : 0.5 * smallest(volume.spacing());
}

RayCaster::RayCaster(const volume::Volume& vol, const volume::TransferFunction* tf,
                     const RayCastOptions& options)
    : m_options(options) {
    const Stopwatch watch;
    check_options(options);
    if (vol.empty()) {
        throw InvalidInput("raycast: the volume is empty (no voxels)");
    }
    using volume::VoxelType;
    m_is_rgba = volume::channels(vol.type()) == 4;
    if (!m_is_rgba && tf == nullptr) {
        throw InvalidInput(
            fmt::format("raycast: a scalar volume ({}) needs a transfer function (got none)",
                        volume::name(vol.type())));
    }
    m_dims = vol.dims();
    m_spacing = vol.spacing();
    m_origin = vol.origin();
    m_step = default_step(vol, options);
    m_opacity_unit = options.opacity_unit > 0.0 ? options.opacity_unit : smallest(m_spacing);
    const std::int64_t num_voxels = vol.num_voxels();

    // Step 1: voxels as floats (lookup coordinates, or opacity-weighted colour and α) and the
    // lookup table.
    if (m_is_rgba) {
        m_values.resize(static_cast<std::size_t>(4 * num_voxels));
        const bool is_u8 = vol.type() == VoxelType::rgba8;
        const std::uint8_t* u8 = is_u8 ? vol.values<VoxelType::rgba8>().data() : nullptr;
        const float* f32 = is_u8 ? nullptr : vol.values<VoxelType::rgba32f>().data();
        parallel_for(num_voxels, [&](std::int64_t v) {
            float c[4];
            for (int ch = 0; ch < 4; ++ch) {
                const auto idx = static_cast<std::size_t>(4 * v + ch);
                const float x = is_u8 ? static_cast<float>(u8[idx]) / 255.0f : f32[idx];
                c[ch] = std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 0.0f;
            }
            const auto o = static_cast<std::size_t>(4 * v);
            m_values[o] = c[0] * c[3];
            m_values[o + 1] = c[1] * c[3];
            m_values[o + 2] = c[2] * c[3];
            m_values[o + 3] = c[3];
        });
    } else {
        tf->validate();
        const double tf_unit = tf->opacity_unit > 0.0 ? tf->opacity_unit : m_opacity_unit;
        m_opacity_unit = tf_unit;
        std::array<double, 2> range = volume::value_range(vol);
        if (!(range[1] > range[0])) {
            range[1] = range[0] + 1.0;
        }
        const double scale = (detail::LUT_SIZE - 1) / (range[1] - range[0]);
        switch (vol.type()) {
            case VoxelType::u8:
                to_lookup_coordinates<VoxelType::u8>(vol, range[0], scale, m_values);
                break;
            case VoxelType::i16:
                to_lookup_coordinates<VoxelType::i16>(vol, range[0], scale, m_values);
                break;
            case VoxelType::u16:
                to_lookup_coordinates<VoxelType::u16>(vol, range[0], scale, m_values);
                break;
            default:
                to_lookup_coordinates<VoxelType::f32>(vol, range[0], scale, m_values);
                break;
        }
        m_lut.resize(4 * detail::LUT_SIZE);
        m_lut_alpha.resize(detail::LUT_SIZE);
        for (int e = 0; e < detail::LUT_SIZE; ++e) {
            const std::array<float, 4> c = tf->evaluate(range[0] + e / scale);
            m_lut[4 * e] = c[0];
            m_lut[4 * e + 1] = c[1];
            m_lut[4 * e + 2] = c[2];
            m_lut[4 * e + 3] = static_cast<float>(volume::corrected_opacity(c[3], m_step, tf_unit));
            m_lut_alpha[e] = c[3];
        }
    }

    // Step 2: macro cells, min/max over each cell's footprint (the cell grown by BORDER voxels).
    for (int a = 0; a < 3; ++a) {
        m_cells[a] = static_cast<int>((m_dims[a] + detail::CELL - 1) / detail::CELL);
    }
    const std::int64_t total_cells = num_cells();
    m_occupied.assign(static_cast<std::size_t>(total_cells), 0);
    m_cell_max.assign(static_cast<std::size_t>(total_cells), 0.0f);
    std::vector<int> nonzero_prefix(detail::LUT_SIZE + 1, 0);
    for (int e = 0; e < detail::LUT_SIZE && !m_is_rgba; ++e) {
        nonzero_prefix[e + 1] = nonzero_prefix[e] + (m_lut[4 * e + 3] > 0.0f ? 1 : 0);
    }
    const int channel_stride = m_is_rgba ? 4 : 1;
    const int channel = m_is_rgba ? 3 : 0;
    parallel_for(
        total_cells,
        [&](std::int64_t cell) {
            const std::int64_t cx = cell % m_cells[0];
            const std::int64_t cy = (cell / m_cells[0]) % m_cells[1];
            const std::int64_t cz = cell / (static_cast<std::int64_t>(m_cells[0]) * m_cells[1]);
            const std::int64_t c[3] = {cx, cy, cz};
            std::int64_t lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::max<std::int64_t>(0, c[a] * detail::CELL - detail::BORDER);
                hi[a] = std::min<std::int64_t>(m_dims[a] - 1,
                                               (c[a] + 1) * detail::CELL - 1 + detail::BORDER);
            }
            float vmin = std::numeric_limits<float>::infinity();
            float vmax = -vmin;
            for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                    const std::int64_t row = m_dims[0] * (y + m_dims[1] * z);
                    for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                        const float v = m_values[static_cast<std::size_t>(
                            (row + x) * channel_stride + channel)];
                        vmin = std::min(vmin, v);
                        vmax = std::max(vmax, v);
                    }
                }
            }
            bool occupied = false;
            if (m_is_rgba) {
                occupied = vmax > 0.0f;
            } else {
                const int i0 = static_cast<int>(vmin + 0.5f);
                const int i1 = static_cast<int>(vmax + 0.5f);
                occupied = nonzero_prefix[i1 + 1] - nonzero_prefix[i0] > 0;
            }
            m_occupied[static_cast<std::size_t>(cell)] = occupied ? 1 : 0;
            m_cell_max[static_cast<std::size_t>(cell)] = vmax;
        },
        1);
    m_prepare_ms = watch.elapsed_ms();
}

std::int64_t RayCaster::num_cells() const {
    return static_cast<std::int64_t>(m_cells[0]) * m_cells[1] * m_cells[2];
}

std::int64_t RayCaster::num_occupied_cells() const {
    std::int64_t count = 0;
    for (const std::uint8_t o : m_occupied) {
        count += o;
    }
    return count;
}

RayCastStats RayCaster::render(const Camera& camera, Image& image) const {
    const Stopwatch watch;
    detail::RayCastKernel k;
    k.width = camera.width();
    k.height = camera.height();
    k.is_perspective = camera.projection() == Projection::perspective;
    // Positions are taken relative to the volume's origin (in double, then float), so volumes
    // far from the world origin keep float precision: grid g = (p − origin) / spacing − 0.5.
    k.eye = vec3_cast<float>(camera.eye() - m_origin);
    k.forward = vec3_cast<float>(camera.forward());
    k.right = vec3_cast<float>(camera.right());
    k.up = vec3_cast<float>(camera.up());
    k.inv_focal = static_cast<float>(1.0 / camera.focal_pixels());
    const Vec3d inv{1.0 / m_spacing.x, 1.0 / m_spacing.y, 1.0 / m_spacing.z};
    k.inv_spacing = vec3_cast<float>(inv);
    for (int a = 0; a < 3; ++a) {
        k.n[a] = static_cast<int>(m_dims[a]);
        k.max_i0[a] = std::max(0, k.n[a] - 2);
        k.cells[a] = m_cells[a];
    }
    k.d[0] = m_dims[0] > 1 ? 1 : 0;
    k.d[1] = m_dims[1] > 1 ? m_dims[0] : 0;
    k.d[2] = m_dims[2] > 1 ? m_dims[0] * m_dims[1] : 0;
    k.values = m_values.data();
    k.lut = m_lut.data();
    k.lut_alpha = m_lut_alpha.data();
    k.occupied = m_occupied.data();
    k.cell_max = m_cell_max.data();
    k.step = static_cast<float>(m_step);
    k.step_over_unit = static_cast<float>(m_step / m_opacity_unit);
    k.threshold = static_cast<float>(m_options.early_termination);
    k.is_mip = m_options.mode == RayCastMode::mip;
    k.shading = m_options.shading && !k.is_mip;
    k.skipping = m_options.empty_space_skipping;
    k.background = m_options.background;
    k.grid_offset = {-0.5f, -0.5f, -0.5f};

    image = Image(k.width, k.height);
    const int tiles_x = (k.width + detail::TILE - 1) / detail::TILE;
    const int tiles_y = (k.height + detail::TILE - 1) / detail::TILE;
    const std::int64_t num_tiles = static_cast<std::int64_t>(tiles_x) * tiles_y;
    std::vector<std::int64_t> tile_samples(static_cast<std::size_t>(num_tiles), 0);
    const bool is_rgba = m_is_rgba;
    parallel_for(
        num_tiles,
        [&](std::int64_t tile) {
            const int x0 = static_cast<int>(tile % tiles_x) * detail::TILE;
            const int y0 = static_cast<int>(tile / tiles_x) * detail::TILE;
            const int x1 = std::min(x0 + detail::TILE, k.width);
            const int y1 = std::min(y0 + detail::TILE, k.height);
            std::int64_t samples = 0;
            for (int y = y0; y < y1; ++y) {
                for (int x = x0; x < x1; ++x) {
                    const detail::PixelResult p = is_rgba ? detail::raycast_pixel<true>(k, x, y)
                                                          : detail::raycast_pixel<false>(k, x, y);
                    image.set(x, y, to_rgb8(p.color));
                    samples += p.samples;
                }
            }
            tile_samples[static_cast<std::size_t>(tile)] = samples;
        },
        1);
    RayCastStats stats;
    for (const std::int64_t s : tile_samples) {
        stats.samples += s;
    }
    stats.ms = watch.elapsed_ms();
    return stats;
}

RayCastStats raycast(const volume::Volume& volume, const volume::TransferFunction* tf,
                     const Camera& camera, const RayCastOptions& options, Image& image) {
    const Stopwatch watch;
    const RayCaster caster(volume, tf, options);
    RayCastStats stats = caster.render(camera, image);
    stats.ms = watch.elapsed_ms();
    return stats;
}

ViewAxis parse_view_axis(const char* text) {
    const std::string s = text == nullptr ? std::string() : std::string(text);
    if (s == "+x" || s == "x")
        return ViewAxis::pos_x;
    if (s == "-x")
        return ViewAxis::neg_x;
    if (s == "+y" || s == "y")
        return ViewAxis::pos_y;
    if (s == "-y")
        return ViewAxis::neg_y;
    if (s == "+z" || s == "z")
        return ViewAxis::pos_z;
    if (s == "-z")
        return ViewAxis::neg_z;
    throw InvalidInput(fmt::format("view axis '{}' is not one of +x, -x, +y, -y, +z, -z", s));
}

Camera view_camera(const AABBd& box, ViewAxis axis, int width, int height) {
    if (box.is_empty() || !is_finite(box.lo) || !is_finite(box.hi)) {
        throw InvalidInput(fmt::format(
            "view_camera: box [({}, {}, {}), ({}, {}, {})] must be finite and non-empty", box.lo.x,
            box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z));
    }
    if (width < 1 || width > 32768 || height < 1 || height > 32768) {
        throw InvalidInput(fmt::format(
            "view_camera: size {}x{} must be within [1, 32768] on each side", width, height));
    }
    Vec3d forward, up;
    switch (axis) {
        case ViewAxis::pos_x:
            forward = {1, 0, 0};
            up = {0, 0, 1};
            break;
        case ViewAxis::neg_x:
            forward = {-1, 0, 0};
            up = {0, 0, 1};
            break;
        case ViewAxis::pos_y:
            forward = {0, 1, 0};
            up = {0, 0, 1};
            break;
        case ViewAxis::neg_y:
            forward = {0, -1, 0};
            up = {0, 0, 1};
            break;
        case ViewAxis::pos_z:
            forward = {0, 0, 1};
            up = {0, 1, 0};
            break;
        case ViewAxis::neg_z:
            forward = {0, 0, -1};
            up = {0, 1, 0};
            break;
    }
    const Vec3d right = cross(forward, up);
    const Vec3d e = box.extent();
    const auto along = [&](Vec3d v) {
        return std::fabs(v.x) * e.x + std::fabs(v.y) * e.y + std::fabs(v.z) * e.z;
    };
    const double extent_right = along(right);
    const double extent_up = along(up);
    const double extent_forward = along(forward);
    const double view_height =
        std::max(extent_up, extent_right * static_cast<double>(height) / width);
    const Vec3d center = box.center();
    const double back = 0.5 * extent_forward + std::max(extent_forward, 1e-6 * view_height);
    return Camera::orthographic(center - back * forward, center, up, view_height, width, height);
}

}  // namespace pliant::render
