#include "pliant/render/raycast.hpp"

#include <fmt/format.h>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/core/host_device.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/render/detail/raycast_avx2.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"
#include "pliant/render/detail/tiles.hpp"

namespace pliant::render {

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
    if (o.clip && (!is_finite(o.clip->point) || !is_finite(o.clip->normal) ||
                   !(norm(o.clip->normal) > 0.0))) {
        const ClipPlane& c = *o.clip;
        throw InvalidInput(fmt::format(
            "raycast: options.clip: point ({}, {}, {}) must be finite and normal ({}, {}, {}) "
            "finite and nonzero",
            c.point.x, c.point.y, c.point.z, c.normal.x, c.normal.y, c.normal.z));
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

// One row of voxels (x = 0 … nx − 1 at (y, z)) as the kernel's floats: lookup coordinates
// (x − lo) · scale clamped to the table, 0 for non-finite values; or for RGBA volumes the
// opacity-weighted colour and α (4 floats per voxel), channels clamped to [0, 1].
class RowConverter {
public:
    RowConverter(const volume::Volume& v, double lo, double scale)
        : m_volume(&v), m_lo(lo), m_scale(scale), m_avx2(has_avx2()) {}

    // alpha: null, or the row's α alone (RGBA volumes).
    void convert(std::int64_t y, std::int64_t z, float* out, float* alpha = nullptr) const {
        using volume::VoxelType;
        const volume::Dims& n = m_volume->dims();
        const std::int64_t first = n[0] * (y + n[1] * z);
        switch (m_volume->type()) {
            case VoxelType::u8:
                scalar_row(m_volume->values<VoxelType::u8>().data() + first, n[0], out);
                break;
            case VoxelType::i16:
                scalar_row(m_volume->values<VoxelType::i16>().data() + first, n[0], out);
                break;
            case VoxelType::u16:
                scalar_row(m_volume->values<VoxelType::u16>().data() + first, n[0], out);
                break;
            case VoxelType::f32:
                scalar_row(m_volume->values<VoxelType::f32>().data() + first, n[0], out);
                break;
            case VoxelType::rgba8:
                rgba_row(m_volume->values<VoxelType::rgba8>().data() + 4 * first, n[0], out, alpha);
                break;
            case VoxelType::rgba32f:
                rgba_row(m_volume->values<VoxelType::rgba32f>().data() + 4 * first, n[0], out,
                         alpha);
                break;
        }
    }

private:
    template <typename T>
    void scalar_row(const T* in, std::int64_t count, float* out) const {
        std::int64_t i =
            m_avx2 ? detail::lookup_coordinates_avx2(in, count, m_lo, m_scale, out) : 0;
        for (; i < count; ++i) {
            out[i] = detail::lookup_coordinate(static_cast<double>(in[i]), m_lo, m_scale);
        }
    }
    template <typename T>
    void rgba_row(const T* in, std::int64_t count, float* out, float* alpha) const {
        std::int64_t v = m_avx2 ? detail::rgba_values_avx2(in, count, out, alpha) : 0;
        for (; v < count; ++v) {
            float c[4];
            for (int ch = 0; ch < 4; ++ch) {
                const float x = std::is_same_v<T, std::uint8_t>
                                    ? static_cast<float>(in[4 * v + ch]) / 255.0f
                                    : static_cast<float>(in[4 * v + ch]);
                c[ch] = std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 0.0f;
            }
            out[4 * v] = c[0] * c[3];
            out[4 * v + 1] = c[1] * c[3];
            out[4 * v + 2] = c[2] * c[3];
            out[4 * v + 3] = c[3];
            if (alpha != nullptr) {
                alpha[v] = c[3];
            }
        }
    }

    const volume::Volume* m_volume;
    double m_lo, m_scale;
    bool m_avx2;
};

// For j = 0, 1, … while whole footprints fit (2j + 2 ≤ nx − 1) and j < num_j, 4 at a time (SSE2,
// the x86-64 baseline; one at a time elsewhere): min and max of row[2j], row[2j + 1], row[2j + 2]
// into mn[j], mx[j]. Returns the number of j done. Exact (min and max do not round; the values are
// finite lookup coordinates).
std::int64_t row_min_max(const float* row, std::int64_t nx, std::int64_t num_j, float* mn,
                         float* mx) {
    std::int64_t j = 0;
#if defined(__SSE2__)
    for (; j + 3 < num_j && 2 * j + 8 <= nx - 1; j += 4) {
        const __m128 v0 = _mm_loadu_ps(row + 2 * j);                          // r0 r1 r2 r3
        const __m128 v1 = _mm_loadu_ps(row + 2 * j + 4);                      // r4 r5 r6 r7
        const __m128 even = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(2, 0, 2, 0));  // r0 r2 r4 r6
        const __m128 odd = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(3, 1, 3, 1));   // r1 r3 r5 r7
        const __m128 t = _mm_move_ss(even, _mm_load_ss(row + 2 * j + 8));     // r8 r2 r4 r6
        const __m128 next = _mm_shuffle_ps(t, t, _MM_SHUFFLE(0, 3, 2, 1));    // r2 r4 r6 r8
        _mm_storeu_ps(mn + j, _mm_min_ps(even, _mm_min_ps(odd, next)));
        _mm_storeu_ps(mx + j, _mm_max_ps(even, _mm_max_ps(odd, next)));
    }
#endif
    for (; j < num_j && 2 * j + 2 <= nx - 1; ++j) {
        const float a = row[2 * j], b = row[2 * j + 1], c = row[2 * j + 2];
        mn[j] = std::min(a, std::min(b, c));
        mx[j] = std::max(a, std::max(b, c));
    }
    return j;
}

}  // namespace

double default_step(const volume::Volume& volume, const RayCastOptions& options) {
    return options.step > 0.0 ? options.step : 0.5 * smallest(volume.spacing());
}

RayCaster::RayCaster(const volume::Volume& volume, const volume::TransferFunction* tf,
                     const RayCastOptions& options)
    : m_options(options) {
    check_options(options);
    prepare(volume, tf);
}

void RayCaster::prepare(const volume::Volume& vol, const volume::TransferFunction* tf) {
    const Stopwatch watch;
    if (vol.empty()) {
        throw InvalidInput("raycast: the volume is empty (no voxels)");
    }
    const bool is_rgba = volume::channels(vol.type()) == 4;
    if (!is_rgba && tf == nullptr) {
        throw InvalidInput(
            fmt::format("raycast: a scalar volume ({}) needs a transfer function (got none)",
                        volume::name(vol.type())));
    }
    if (!is_rgba) {
        tf->validate();
    }
    m_is_rgba = is_rgba;
    m_dims = vol.dims();
    m_spacing = vol.spacing();
    m_origin = vol.origin();
    m_direction = vol.direction();
    m_step = default_step(vol, m_options);
    m_opacity_unit = m_options.opacity_unit > 0.0 ? m_options.opacity_unit : smallest(m_spacing);

    // Step 1: the lookup table (scalar volumes) over the volume's value range [lo, hi].
    double lo = 0.0, scale = 1.0;
    if (!m_is_rgba) {
        const double tf_unit = tf->opacity_unit > 0.0 ? tf->opacity_unit : m_opacity_unit;
        m_opacity_unit = tf_unit;
        std::array<double, 2> range = volume::value_range(vol);
        if (!(range[1] > range[0])) {
            range[1] = range[0] + 1.0;
        }
        lo = range[0];
        scale = (detail::LUT_SIZE - 1) / (range[1] - range[0]);
        m_lut.resize(4 * static_cast<std::size_t>(detail::LUT_SIZE));
        m_lut_alpha.resize(detail::LUT_SIZE);
        for (std::size_t e = 0; e < static_cast<std::size_t>(detail::LUT_SIZE); ++e) {
            const std::array<float, 4> c = tf->evaluate(range[0] + static_cast<double>(e) / scale);
            m_lut[4 * e] = c[0];
            m_lut[4 * e + 1] = c[1];
            m_lut[4 * e + 2] = c[2];
            m_lut[4 * e + 3] = static_cast<float>(volume::corrected_opacity(c[3], m_step, tf_unit));
            m_lut_alpha[e] = c[3];
        }
    }

    // Step 2, one parallel pass over slabs of a cell layer (4 voxel layers): the voxels as floats
    // (lookup coordinates, or opacity-weighted colour and α) and the macro cells' sub-cell
    // occupancy and largest value (raycast_kernel.hpp: the samples with lower corner in
    // [CELL·c, CELL·c + CELL − 1] read the voxels [CELL·c, CELL·c + CELL]; sub-cell j of an
    // axis reads [2j, 2j + 2], clipped to the grid, and exists when 2j ≤ n − 1).
    const std::int64_t n[3] = {m_dims[0], m_dims[1], m_dims[2]};
    for (int a = 0; a < 3; ++a) {
        const std::int64_t max_i0 = std::max<std::int64_t>(0, n[a] - 2);
        m_cells[a] = static_cast<int>(max_i0 / detail::CELL + 1);
    }
    const int channels = m_is_rgba ? 4 : 1;
    const std::int64_t total_cells = num_cells();
    m_values.resize(static_cast<std::size_t>(channels * vol.num_voxels()));
    // The α channel alone for the gradients of shaded RGBA views (the AVX2 march's pairs).
    const bool alpha_apart =
        m_is_rgba && m_options.shading && m_options.mode == RayCastMode::composite;
    m_alpha.resize(alpha_apart ? static_cast<std::size_t>(vol.num_voxels()) : 0);
    m_occupied.resize(static_cast<std::size_t>(total_cells));
    m_cell_max.resize(static_cast<std::size_t>(total_cells));
    m_sub_occupied.resize(static_cast<std::size_t>(total_cells));
    std::array<int, detail::LUT_SIZE + 1> nonzero_prefix{};
    for (int e = 0; e < detail::LUT_SIZE && !m_is_rgba; ++e) {
        nonzero_prefix[e + 1] = nonzero_prefix[e] + (m_lut[4 * e + 3] > 0.0f ? 1 : 0);
    }
    const RowConverter converter(vol, lo, scale);
    const int num_sub_x = 2 * m_cells[0];
    parallel_for(
        m_cells[2],
        [&](std::int64_t cz) {
            const std::int64_t z0 = detail::CELL * cz;
            // Layers [z0, own_end) are this slab's to write; its footprint reaches z_last.
            const std::int64_t own_end = cz + 1 == m_cells[2] ? n[2] : z0 + detail::CELL;
            const std::int64_t z_last = std::min(n[2] - 1, z0 + detail::CELL);
            const auto row_of = [&](std::int64_t y, std::int64_t z) {
                return m_values.data() + channels * (n[0] * (y + n[1] * z));
            };
            for (std::int64_t z = z0; z < own_end; ++z) {
                for (std::int64_t y = 0; y < n[1]; ++y) {
                    float* alpha =
                        m_alpha.empty() ? nullptr : m_alpha.data() + n[0] * (y + n[1] * z);
                    converter.convert(y, z, row_of(y, z), alpha);
                }
            }
            // Per cell row: min/max of each sub-cell (sz, sy, x sub-cell j), accumulated from
            // the min/max of the rows' x sub-cells.
            std::vector<float> boundary(static_cast<std::size_t>(channels * n[0]));
            std::vector<float> sub_min(static_cast<std::size_t>(4 * num_sub_x));
            std::vector<float> sub_max(static_cast<std::size_t>(4 * num_sub_x));
            std::vector<float> row_min(static_cast<std::size_t>(num_sub_x));
            std::vector<float> row_max(static_cast<std::size_t>(num_sub_x));
            // x sub-cells that exist (2j ≤ nx − 1); the others keep +∞ / −∞ (empty).
            const std::int64_t num_rows_x = std::min<std::int64_t>(num_sub_x, (n[0] - 1) / 2 + 1);
            const int channel = m_is_rgba ? 3 : 0;
            for (std::int64_t cy = 0; cy < m_cells[1]; ++cy) {
                std::fill(sub_min.begin(), sub_min.end(), std::numeric_limits<float>::infinity());
                std::fill(sub_max.begin(), sub_max.end(), -std::numeric_limits<float>::infinity());
                const std::int64_t y0 = detail::CELL * cy;
                const std::int64_t y_last = std::min(n[1] - 1, y0 + detail::CELL);
                for (std::int64_t z = z0; z <= z_last; ++z) {
                    for (std::int64_t y = y0; y <= y_last; ++y) {
                        const float* row = row_of(y, z);
                        if (z >= own_end) {  // the next slab's layer: converted again here
                            converter.convert(y, z, boundary.data());
                            row = boundary.data();
                        }
                        // The min/max of the row's x sub-cells j: voxels [2j, min(2j + 2, nx − 1)].
                        const auto at = [&](std::int64_t x) {
                            return row[channels * x + channel];
                        };
                        std::int64_t j = 0;
                        if (channels == 1) {
                            j = row_min_max(row, n[0], num_rows_x, row_min.data(), row_max.data());
                        }
                        for (; j < num_rows_x; ++j) {
                            const std::int64_t x_last = std::min(n[0] - 1, 2 * j + 2);
                            float lo_v = at(2 * j), hi_v = lo_v;
                            for (std::int64_t x = 2 * j + 1; x <= x_last; ++x) {
                                lo_v = std::min(lo_v, at(x));
                                hi_v = std::max(hi_v, at(x));
                            }
                            row_min[j] = lo_v;
                            row_max[j] = hi_v;
                        }
                        // Into the (sz, sy) sub-cells the row belongs to: layer zl = z − z0 is in
                        // sz = 0 for zl ≤ 2, in sz = 1 for zl ≥ 2 (likewise rows in sy).
                        const std::int64_t zl = z - z0, yl = y - y0;
                        for (std::int64_t sz = 0; sz < 2; ++sz) {
                            for (std::int64_t sy = 0; sy < 2; ++sy) {
                                if (zl < 2 * sz || zl > 2 * sz + 2 || yl < 2 * sy ||
                                    yl > 2 * sy + 2) {
                                    continue;
                                }
                                float* dst_min = sub_min.data() + (2 * sz + sy) * num_sub_x;
                                float* dst_max = sub_max.data() + (2 * sz + sy) * num_sub_x;
                                for (std::int64_t i = 0; i < num_rows_x; ++i) {
                                    dst_min[i] = std::min(dst_min[i], row_min[i]);
                                    dst_max[i] = std::max(dst_max[i], row_max[i]);
                                }
                            }
                        }
                    }
                }
                for (std::int64_t cx = 0; cx < m_cells[0]; ++cx) {
                    float cell_max = -std::numeric_limits<float>::infinity();
                    std::uint8_t sub_mask = 0;
                    for (int sub = 0; sub < 8; ++sub) {
                        const std::int64_t j = 2 * cx + (sub & 1);
                        const std::int64_t plane = 2 * ((sub >> 2) & 1) + ((sub >> 1) & 1);
                        const float vmin = sub_min[static_cast<std::size_t>(plane * num_sub_x + j)];
                        const float vmax = sub_max[static_cast<std::size_t>(plane * num_sub_x + j)];
                        if (!(vmin <= vmax)) {
                            continue;  // past the grid: no sample has its corner here
                        }
                        cell_max = std::max(cell_max, vmax);
                        bool occupied = false;
                        if (m_is_rgba) {
                            occupied = vmax > 0.0f;
                        } else {
                            // Interpolated values lie in [vmin, vmax] up to the rounding of
                            // the lerps (detail::LERP_ROUNDING): the entries nearest to that
                            // widened range.
                            const float widened_lo = std::max(0.0f, vmin - detail::LERP_ROUNDING);
                            const int i0 = static_cast<int>(widened_lo + 0.5f);
                            const int i1 =
                                std::min(detail::LUT_SIZE - 1,
                                         static_cast<int>(vmax + detail::LERP_ROUNDING + 0.5f));
                            occupied = nonzero_prefix[i1 + 1] - nonzero_prefix[i0] > 0;
                        }
                        sub_mask = static_cast<std::uint8_t>(sub_mask | (occupied ? 1 << sub : 0));
                    }
                    const auto cell = static_cast<std::size_t>(
                        cx + m_cells[0] * (cy + static_cast<std::int64_t>(m_cells[1]) * cz));
                    m_sub_occupied[cell] = sub_mask;
                    m_occupied[cell] = sub_mask != 0 ? 1 : 0;
                    m_cell_max[cell] = cell_max;
                }
            }
        },
        1);

    // Step 3: the empty cubes towards each octant, which rays jump over at once.
    m_empty_cube.resize(8 * m_occupied.size());
    parallel_for(
        8,
        [&](std::int64_t octant) {
            const std::size_t count = m_occupied.size();
            detail::empty_cubes(m_occupied, m_cells.data(), static_cast<int>(octant),
                                std::span<std::uint8_t>(m_empty_cube)
                                    .subspan(static_cast<std::size_t>(octant) * count, count));
        },
        1);
    m_prepare_ms = watch.elapsed_ms();
}

void RayCaster::update(const volume::Volume& volume, const volume::TransferFunction* tf) {
    prepare(volume, tf);
}

void RayCaster::set_clip(const std::optional<ClipPlane>& clip) {
    RayCastOptions options = m_options;
    options.clip = clip;
    check_options(options);
    m_options.clip = clip;
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

Vec3d RayCaster::grid_from_world(const Vec3d& v) const {
    if (m_direction == volume::IDENTITY_DIRECTION) {
        return v;
    }
    // D is orthogonal: its inverse is its transpose, whose rows are D's columns.
    return {dot(m_direction[0], v), dot(m_direction[1], v), dot(m_direction[2], v)};
}

void RayCaster::fill_kernel(detail::RayCastKernel& k) const {
    const Vec3d inv{1.0 / m_spacing.x, 1.0 / m_spacing.y, 1.0 / m_spacing.z};
    k.inv_spacing = vec3_cast<float>(inv);
    for (int a = 0; a < 3; ++a) {
        k.n[a] = static_cast<int>(m_dims[a]);
        k.g_max[a] = static_cast<float>(k.n[a] - 1);
        k.max_i0[a] = std::max(0, k.n[a] - 2);
        k.cells[a] = m_cells[a];
    }
    k.d[0] = m_dims[0] > 1 ? 1 : 0;
    k.d[1] = m_dims[1] > 1 ? m_dims[0] : 0;
    k.d[2] = m_dims[2] > 1 ? m_dims[0] * m_dims[1] : 0;
    k.stride[0] = 1;
    k.stride[1] = m_dims[0];
    k.stride[2] = m_dims[0] * m_dims[1];
    k.values = m_values.data();
    k.alpha = m_alpha.empty() ? nullptr : m_alpha.data();
    k.lut = m_lut.data();
    k.lut_alpha = m_lut_alpha.data();
    k.sub_occupied = m_sub_occupied.data();
    for (int octant = 0; octant < 8; ++octant) {
        k.empty_cube[octant] =
            m_empty_cube.data() + static_cast<std::size_t>(octant) * m_occupied.size();
    }
    k.cell_max = m_cell_max.data();
    k.step = static_cast<float>(m_step);
    k.inv_step = 1.0f / k.step;
    k.step_over_unit = static_cast<float>(m_step / m_opacity_unit);
    k.threshold = static_cast<float>(m_options.early_termination);
    k.is_rgba = m_is_rgba;
    k.is_mip = m_options.mode == RayCastMode::mip;
    k.shading = m_options.shading && !k.is_mip;
    k.skipping = m_options.empty_space_skipping;
    k.background = m_options.background;
    k.grid_offset = {-0.5f, -0.5f, -0.5f};
    if (m_options.clip) {
        // In the kernel's frame (relative to the volume's origin, in the grid's axes), unit
        // normal; the offset dot(n, point − origin) is the same in either frame.
        const Vec3d n = m_options.clip->normal / norm(m_options.clip->normal);
        k.has_clip = true;
        k.clip_normal = vec3_cast<float>(grid_from_world(n));
        k.clip_offset = static_cast<float>(dot(n, m_options.clip->point - m_origin));
    }
}

RayCastStats RayCaster::render_rays(std::span<const Ray> rays, std::span<float> rgb) const {
    if (rgb.size() != 3 * rays.size()) {
        throw InvalidInput(
            fmt::format("render::RayCaster::render_rays: rgb.size() ({}) != 3 x "
                        "rays.size() ({})",
                        rgb.size(), rays.size()));
    }
    const Stopwatch watch;
    detail::RayCastKernel k;
    k.is_perspective = true;
    fill_kernel(k);
    constexpr std::int64_t CHUNK = 256;
    const auto n = static_cast<std::int64_t>(rays.size());
    const std::int64_t num_chunks = (n + CHUNK - 1) / CHUNK;
    std::vector<std::int64_t> chunk_samples(static_cast<std::size_t>(num_chunks), 0);
    const bool is_rgba = m_is_rgba;
    parallel_for(
        num_chunks,
        [&](std::int64_t chunk) {
            std::int64_t samples = 0;
            for (std::int64_t i = chunk * CHUNK; i < std::min(n, (chunk + 1) * CHUNK); ++i) {
                const Ray& ray = rays[static_cast<std::size_t>(i)];
                // Relative to the volume's origin, in the grid's frame, as render() does with
                // the eye.
                const Vec3f origin = vec3_cast<float>(grid_from_world(ray.origin - m_origin));
                const Vec3f dir = vec3_cast<float>(grid_from_world(ray.direction));
                const detail::PixelResult p = is_rgba ? detail::raycast_ray<true>(k, origin, dir)
                                                      : detail::raycast_ray<false>(k, origin, dir);
                rgb[static_cast<std::size_t>(3 * i)] = p.color.r;
                rgb[static_cast<std::size_t>(3 * i + 1)] = p.color.g;
                rgb[static_cast<std::size_t>(3 * i + 2)] = p.color.b;
                samples += p.samples;
            }
            chunk_samples[static_cast<std::size_t>(chunk)] = samples;
        },
        1);
    RayCastStats stats;
    for (const std::int64_t c : chunk_samples) {
        stats.samples += c;
    }
    stats.ms = watch.elapsed_ms();
    return stats;
}

RayCastStats RayCaster::render(const Camera& camera, Image& image) const {
    const Stopwatch watch;
    detail::RayCastKernel k;
    k.width = camera.width();
    k.height = camera.height();
    k.is_perspective = camera.projection() == Projection::perspective;
    // Positions are taken relative to the volume's origin (in double, then float), so volumes
    // far from the world origin keep float precision, and into the grid's frame (the camera
    // turned by Dᵀ about the origin, an exact rigid motion in double): grid
    // g = Dᵀ (p − origin) / spacing − 0.5.
    k.eye = vec3_cast<float>(grid_from_world(camera.eye() - m_origin));
    k.forward = vec3_cast<float>(grid_from_world(camera.forward()));
    k.right = vec3_cast<float>(grid_from_world(camera.right()));
    k.up = vec3_cast<float>(grid_from_world(camera.up()));
    k.inv_focal = static_cast<float>(1.0 / camera.focal_pixels());
    fill_kernel(k);
    // An orthographic axis view: the cubes of its octants merged once per frame (O(cells), a
    // fraction of a millisecond at 64³ cells) instead of 2 or 4 lookups per jump.
    std::vector<std::uint8_t> axis_cube;
    if (!k.is_perspective && m_options.empty_space_skipping) {
        const Vec3f gd{k.forward.x * k.inv_spacing.x, k.forward.y * k.inv_spacing.y,
                       k.forward.z * k.inv_spacing.z};
        const int octant = (gd.x < 0.0f ? 1 : 0) | (gd.y < 0.0f ? 2 : 0) | (gd.z < 0.0f ? 4 : 0);
        const int zero = (gd.x == 0.0f ? 1 : 0) | (gd.y == 0.0f ? 2 : 0) | (gd.z == 0.0f ? 4 : 0);
        if (zero != 0) {
            const std::size_t count = m_occupied.size();
            axis_cube.assign(k.empty_cube[octant], k.empty_cube[octant] + count);
            for (int flip = 1; flip < 8; ++flip) {
                if ((flip & ~zero) == 0) {
                    const std::uint8_t* other = k.empty_cube[octant ^ flip];
                    for (std::size_t c = 0; c < count; ++c) {
                        axis_cube[c] = std::max(axis_cube[c], other[c]);
                    }
                }
            }
            k.axis_cube = axis_cube.data();
        }
    }
    image = Image(k.width, k.height);
    const bool is_rgba = m_is_rgba;
    // The AVX2 march gives the scalar kernel's bits (detail/raycast_avx2.hpp): for speed only.
    // Every kind of ray takes it (composite and MIP, scalar and RGBA, shaded, clipped).
    const bool use_avx2 = detail::composite_avx2_fits(k);
    RayCastStats stats;
    stats.samples = detail::render_tiles(k.width, k.height, [&](int x0, int y0, int x1, int y1) {
        std::int64_t samples = 0;
        if (use_avx2) {
            Color colors[detail::TILE * detail::TILE];
            samples = k.is_mip ? detail::mip_tile_avx2(k, x0, y0, x1, y1, colors)
                               : detail::composite_tile_avx2(k, x0, y0, x1, y1, colors);
            for (int y = y0; y < y1; ++y) {
                for (int x = x0; x < x1; ++x) {
                    image.set(x, y, to_rgb8(colors[(y - y0) * (x1 - x0) + (x - x0)]));
                }
            }
        } else {
            for (int y = y0; y < y1; ++y) {
                for (int x = x0; x < x1; ++x) {
                    const detail::PixelResult p = is_rgba ? detail::raycast_pixel<true>(k, x, y)
                                                          : detail::raycast_pixel<false>(k, x, y);
                    image.set(x, y, to_rgb8(p.color));
                    samples += p.samples;
                }
            }
        }
        return samples;
    });
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
    if (s == "+x" || s == "x") {
        return ViewAxis::pos_x;
    }
    if (s == "-x") {
        return ViewAxis::neg_x;
    }
    if (s == "+y" || s == "y") {
        return ViewAxis::pos_y;
    }
    if (s == "-y") {
        return ViewAxis::neg_y;
    }
    if (s == "+z" || s == "z") {
        return ViewAxis::pos_z;
    }
    if (s == "-z") {
        return ViewAxis::neg_z;
    }
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
