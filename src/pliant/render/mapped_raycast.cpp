#include "pliant/render/mapped_raycast.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <span>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/render/detail/mapped_raycast_avx2.hpp"
#include "pliant/render/detail/mapped_raycast_kernel.hpp"
#include "pliant/render/detail/tiles.hpp"

namespace pliant::render {

namespace {

constexpr int BRICK = 4;        // occupancy bricks (64 bits), voxels per edge
constexpr int BRICK_SHIFT = 2;  // log2(BRICK)
// Source grid units the box of a map cell's node values is widened by: far above the rounding
// of the float trilinear interpolation of coordinates below a few thousand.
constexpr float HULL_MARGIN = 1.0f / 32.0f;

// The bits of a brick (bit x + 4 y + 16 z) whose coordinate along axis a lies in [lo, hi] ⊂ [0, 3].
constexpr std::uint64_t brick_mask(int a, int lo, int hi) {
    std::uint64_t mask = 0;
    for (int bit = 0; bit < 64; ++bit) {
        const int c = (bit >> (2 * a)) & 3;
        if (c >= lo && c <= hi) {
            mask |= std::uint64_t{1} << bit;
        }
    }
    return mask;
}

// brick_mask(a, lo, hi) at [a][lo][hi].
constexpr std::array<std::array<std::array<std::uint64_t, 4>, 4>, 3> BRICK_MASKS = [] {
    std::array<std::array<std::array<std::uint64_t, 4>, 4>, 3> t{};
    for (int a = 0; a < 3; ++a) {
        for (int lo = 0; lo < 4; ++lo) {
            for (int hi = lo; hi < 4; ++hi) {
                t[static_cast<std::size_t>(a)][static_cast<std::size_t>(lo)]
                 [static_cast<std::size_t>(hi)] = brick_mask(a, lo, hi);
            }
        }
    }
    return t;
}();

// The bits of the bricks at brick coordinate b along axis a of the voxel range [v0, v1].
inline std::uint64_t range_mask(int a, std::int64_t b, std::int64_t v0, std::int64_t v1) {
    const auto lo = static_cast<std::size_t>((b << BRICK_SHIFT) >= v0 ? 0 : v0 & 3);
    const auto hi = static_cast<std::size_t>(((b + 1) << BRICK_SHIFT) <= v1 ? 3 : v1 & 3);
    return BRICK_MASKS[static_cast<std::size_t>(a)][lo][hi];
}

// Dilates brick bits (bricks[a] bricks of 4³ voxels per axis, x fastest) by one voxel toward
// −x, −y and −z: voxel (x, y, z) of the result is set when a voxel of {x, x + 1} × {y, y + 1} ×
// {z, z + 1} is set in the input (bits past the volume's end are 0 in the input). Separable:
// x and y in place per brick layer (a brick reads its successor before the successor is
// written), then z per brick row.
void dilate_bricks(std::vector<std::uint64_t>& bits, const std::array<std::int64_t, 3>& bricks) {
    const std::uint64_t x0 = brick_mask(0, 0, 0), x3 = brick_mask(0, 3, 3);
    const std::uint64_t y0 = brick_mask(1, 0, 0), y3 = brick_mask(1, 3, 3);
    const std::uint64_t z0 = brick_mask(2, 0, 0);
    const std::int64_t bx = bricks[0], by = bricks[1], bz = bricks[2];
    std::uint64_t* w = bits.data();
    parallel_for(
        bz,
        [&](std::int64_t z) {
            for (std::int64_t y = 0; y < by; ++y) {
                std::uint64_t* row = w + bx * (y + by * z);
                for (std::int64_t x = 0; x < bx; ++x) {
                    const std::uint64_t next = x + 1 < bx ? row[x + 1] : 0;
                    row[x] |= ((row[x] >> 1) & ~x3) | ((next & x0) << 3);
                }
            }
            for (std::int64_t y = 0; y < by; ++y) {
                std::uint64_t* row = w + bx * (y + by * z);
                const std::uint64_t* next = y + 1 < by ? row + bx : nullptr;
                for (std::int64_t x = 0; x < bx; ++x) {
                    const std::uint64_t n = next != nullptr ? next[x] : 0;
                    row[x] |= ((row[x] >> 4) & ~y3) | ((n & y0) << 12);
                }
            }
        },
        1);
    parallel_for(
        by,
        [&](std::int64_t y) {
            for (std::int64_t z = 0; z < bz; ++z) {
                std::uint64_t* row = w + bx * (y + by * z);
                const std::uint64_t* next = z + 1 < bz ? row + bx * by : nullptr;
                for (std::int64_t x = 0; x < bx; ++x) {
                    const std::uint64_t n = next != nullptr ? next[x] : 0;
                    row[x] |= (row[x] >> 16) | ((n & z0) << 48);
                }
            }
        },
        1);
}

// The octants (detail::octant_of(), and the flips of detail::zero_axes_of()) that the rays of
// kernel k may have. A ray's grid direction has the signs of v = forward + cx·right + cy·up
// (perspective; forward itself for orthographic: every ray), v affine in the pixel's (cx, cy):
// over the image its smallest and largest values per axis are at the 4 corner pixels. An axis
// whose corners all lie beyond 1e-5 of the terms' magnitude (far above the float rounding of v)
// on one side gives its rays that sign; otherwise both (a ray there may have either sign, or 0).
int ray_octants(const detail::RayCastKernel& k) {
    const double cx[2] = {(0.5 - 0.5 * k.width) * k.inv_focal,
                          (k.width - 0.5 - 0.5 * k.width) * k.inv_focal};
    const double cy[2] = {(0.5 * k.height - 0.5) * k.inv_focal,
                          (0.5 * k.height - (k.height - 0.5)) * k.inv_focal};
    int signs[3] = {0, 0, 0};  // bit 0: a ray may go along +a (or not move), bit 1: along −a
    for (int a = 0; a < 3; ++a) {
        const double f = k.forward[a], r = k.right[a], u = k.up[a];
        double lo = f, hi = f, scale = std::abs(f);
        if (k.is_perspective) {
            lo = std::numeric_limits<double>::infinity();
            hi = -lo;
            for (const double x : cx) {
                for (const double y : cy) {
                    const double v = f + x * r + y * u;
                    lo = std::min(lo, v);
                    hi = std::max(hi, v);
                }
            }
            scale += std::max(std::abs(cx[0]), std::abs(cx[1])) * std::abs(r) +
                     std::max(std::abs(cy[0]), std::abs(cy[1])) * std::abs(u);
        }
        const double margin = 1e-5 * scale;
        signs[a] = lo > margin ? 1 : hi < -margin ? 2 : 3;
    }
    int octants = 0;
    for (int octant = 0; octant < 8; ++octant) {
        bool possible = true;
        for (int a = 0; a < 3; ++a) {
            possible = possible && (signs[a] >> (octant >> a & 1) & 1) != 0;
        }
        octants |= possible ? 1 << octant : 0;
    }
    return octants;
}

double smallest(const Vec3d& s) {
    return std::min({s.x, s.y, s.z});
}

// The camera's fields of a kernel (image size, projection, eye relative to `origin`, frame).
void set_camera(const Camera& camera, const Vec3d& origin, detail::RayCastKernel& k) {
    k.width = camera.width();
    k.height = camera.height();
    k.is_perspective = camera.projection() == Projection::perspective;
    k.eye = vec3_cast<float>(camera.eye() - origin);
    k.forward = vec3_cast<float>(camera.forward());
    k.right = vec3_cast<float>(camera.right());
    k.up = vec3_cast<float>(camera.up());
    k.inv_focal = static_cast<float>(1.0 / camera.focal_pixels());
}

// Per voxel i of an rgba8 volume of dims n (4 bytes per voxel, x fastest) the largest α byte of
// its 3³ neighbourhood (the voxels within one step along each axis, clipped to the grid), into
// out[i · out_stride]: a maximum along x, then y, then z, each pass in parallel over z (every
// value written by one task: the same bytes for any number of threads).
void neighbourhood_alpha(const std::uint8_t* rgba8, const std::int64_t n[3], std::uint8_t* out,
                         std::int64_t out_stride) {
    const std::int64_t row = n[0], layer = n[0] * n[1];
    std::vector<std::uint8_t> along_x(static_cast<std::size_t>(layer * n[2]));
    std::vector<std::uint8_t> along_y(along_x.size());
    // dst[i · stride] = max(below[i], here[i], above[i]) for i < count.
    const auto widest = [](const std::uint8_t* below, const std::uint8_t* here,
                           const std::uint8_t* above, std::uint8_t* dst, std::int64_t stride,
                           std::int64_t count) {
        for (std::int64_t i = 0; i < count; ++i) {
            dst[i * stride] = std::max({below[i], here[i], above[i]});
        }
    };
    parallel_for(
        n[2],
        [&](std::int64_t z) {
            for (std::int64_t y = 0; y < n[1]; ++y) {
                const std::uint8_t* a = rgba8 + 4 * (layer * z + row * y) + 3;
                std::uint8_t* dst = &along_x[static_cast<std::size_t>(layer * z + row * y)];
                for (std::int64_t x = 0; x < n[0]; ++x) {
                    dst[x] = std::max({a[4 * std::max<std::int64_t>(x - 1, 0)], a[4 * x],
                                       a[4 * std::min(x + 1, n[0] - 1)]});
                }
            }
        },
        1);
    parallel_for(
        n[2],
        [&](std::int64_t z) {
            const std::uint8_t* in = &along_x[static_cast<std::size_t>(layer * z)];
            for (std::int64_t y = 0; y < n[1]; ++y) {
                widest(in + row * std::max<std::int64_t>(y - 1, 0), in + row * y,
                       in + row * std::min(y + 1, n[1] - 1),
                       &along_y[static_cast<std::size_t>(layer * z + row * y)], 1, row);
            }
        },
        1);
    parallel_for(
        n[2],
        [&](std::int64_t z) {
            const std::uint8_t* in = along_y.data();
            widest(in + layer * std::max<std::int64_t>(z - 1, 0), in + layer * z,
                   in + layer * std::min(z + 1, n[2] - 1), out + out_stride * layer * z, out_stride,
                   layer);
        },
        1);
}

// The last MappedRayCaster id handed out (ids start at 1; 0 tags no caster).
std::atomic<std::uint64_t> last_caster_id{0};

}  // namespace

MappedRayCaster::MappedRayCaster(const volume::Volume& source, const volume::TransferFunction* tf,
                                 const volume::Volume& target, const RayCastOptions& options)
    : m_id(++last_caster_id), m_options(options) {
    const Stopwatch watch;
    if (target.empty()) {
        throw InvalidInput("raycast through a map: the target frame is empty (no voxels)");
    }
    if (options.mode != RayCastMode::composite) {
        throw InvalidInput(
            "raycast through a map: only composite rendering is supported (got mip); resample "
            "the volume instead");
    }
    set_thin_levels(options.thin_levels);
    // The source prepared with the target's step and opacity unit (those of a RayCaster of the
    // resampled target).
    RayCastOptions source_options = options;
    source_options.step = default_step(target, options);
    source_options.opacity_unit =
        options.opacity_unit > 0.0 ? options.opacity_unit : smallest(target.spacing());
    // The gradients are taken here (m_gradient), not by the source's march: no α copy.
    source_options.clip.reset();
    source_options.shading = false;
    // An rgba8 source is read in its bytes (detail::MappedKernel::rgba8, a copy: 4 bytes per
    // voxel instead of the float copy's 16): its RayCaster, for the options' fields alone, is
    // that of one voxel with the source's spacing (render() sets the grid's fields).
    if (source.type() == volume::VoxelType::rgba8 && !source.empty()) {
        const std::span<const std::uint8_t> bytes = source.values<volume::VoxelType::rgba8>();
        m_rgba8.assign(bytes.begin(), bytes.end());
        const volume::Volume proxy = volume::Volume::allocate({1, 1, 1}, volume::VoxelType::rgba8,
                                                              source.spacing(), source.origin());
        m_source = std::make_unique<RayCaster>(proxy, tf, source_options);
    } else {
        m_source = std::make_unique<RayCaster>(source, tf, source_options);
    }
    m_step = m_source->step();
    m_source_dims = source.dims();
    m_target_dims = target.dims();
    m_target_spacing = target.spacing();
    m_target_origin = target.origin();

    const std::int64_t n[3] = {m_source_dims[0], m_source_dims[1], m_source_dims[2]};
    const float* values = m_source->m_values.data();
    for (int a = 0; a < 3; ++a) {
        m_bricks[static_cast<std::size_t>(a)] = (n[a] + BRICK - 1) / BRICK;
    }
    m_brick_bits.assign(static_cast<std::size_t>(m_bricks[0] * m_bricks[1] * m_bricks[2]), 0);
    if (!m_source->m_is_rgba) {
        // Lookup entries with opacity, prefix counts.
        std::vector<int> nonzero_prefix(static_cast<std::size_t>(detail::LUT_SIZE) + 1, 0);
        for (std::size_t e = 0; e < static_cast<std::size_t>(detail::LUT_SIZE); ++e) {
            nonzero_prefix[e + 1] = nonzero_prefix[e] + (m_source->m_lut[4 * e + 3] > 0.0f ? 1 : 0);
        }
        // Per source cell (first corner v, the voxels {v, v + 1}³ clamped to the grid), bit v of
        // the bricks: the lookup entries of the cell's value range, widened by
        // detail::LERP_ROUNDING, have opacity (RayCaster's test of its cells: a sample
        // interpolated in the cell lies in that range). The bits of the RGBA bricks after
        // dilate_bricks(), for the lookup's opacity. Parallel over brick layers, each written
        // by one task.
        parallel_for(
            m_bricks[2],
            [&](std::int64_t bz) {
                // Per x the min and max over the 4 rows (y, y + 1) × (z, z + 1), clamped.
                std::vector<float> row_min(static_cast<std::size_t>(n[0]));
                std::vector<float> row_max(static_cast<std::size_t>(n[0]));
                for (std::int64_t z = bz * BRICK; z < std::min(n[2], (bz + 1) * BRICK); ++z) {
                    const std::int64_t z1 = std::min(z + 1, n[2] - 1);
                    for (std::int64_t y = 0; y < n[1]; ++y) {
                        const std::int64_t y1 = std::min(y + 1, n[1] - 1);
                        const float* r0 = values + n[0] * (y + n[1] * z);
                        const float* r1 = values + n[0] * (y1 + n[1] * z);
                        const float* r2 = values + n[0] * (y + n[1] * z1);
                        const float* r3 = values + n[0] * (y1 + n[1] * z1);
                        for (std::int64_t x = 0; x < n[0]; ++x) {
                            const auto i = static_cast<std::size_t>(x);
                            row_min[i] = std::min(std::min(r0[x], r1[x]), std::min(r2[x], r3[x]));
                            row_max[i] = std::max(std::max(r0[x], r1[x]), std::max(r2[x], r3[x]));
                        }
                        std::uint64_t* out =
                            m_brick_bits.data() + m_bricks[0] * ((y >> 2) + m_bricks[1] * bz);
                        const int shift = static_cast<int>(4 * (y & 3) + 16 * (z & 3));
                        for (std::int64_t x = 0; x < n[0]; ++x) {
                            const auto i0 = static_cast<std::size_t>(x);
                            const auto i1 = static_cast<std::size_t>(std::min(x + 1, n[0] - 1));
                            const float lo = std::min(row_min[i0], row_min[i1]);
                            const float hi = std::max(row_max[i0], row_max[i1]);
                            const int e0 =
                                static_cast<int>(std::max(0.0f, lo - detail::LERP_ROUNDING) + 0.5f);
                            const int e1 =
                                std::min(detail::LUT_SIZE - 1,
                                         static_cast<int>(hi + detail::LERP_ROUNDING + 0.5f));
                            if (e0 <= e1 && nonzero_prefix[static_cast<std::size_t>(e1) + 1] -
                                                    nonzero_prefix[static_cast<std::size_t>(e0)] >
                                                0) {
                                out[x >> 2] |= std::uint64_t{1}
                                               << (shift + static_cast<int>(x & 3));
                            }
                        }
                    }
                }
            },
            1);
    }
    if (m_source->m_is_rgba) {
        // Bricks of 4³ voxels, bit (x & 3) + 4 (y & 3) + 16 (z & 3) set for a voxel with α > 0
        // (bits past the volume's end stay 0), then dilated (dilate_bricks()). Parallel over
        // brick layers, each written by one task.
        parallel_for(
            m_bricks[2],
            [&](std::int64_t bz) {
                for (std::int64_t z = bz * BRICK; z < std::min(n[2], (bz + 1) * BRICK); ++z) {
                    for (std::int64_t y = 0; y < n[1]; ++y) {
                        const std::int64_t first = 4 * n[0] * (y + n[1] * z) + 3;
                        const float* row = m_rgba8.empty() ? values + first : nullptr;
                        const std::uint8_t* bytes = m_rgba8.empty() ? nullptr : &m_rgba8[first];
                        std::uint64_t* out =
                            m_brick_bits.data() + m_bricks[0] * ((y >> 2) + m_bricks[1] * bz);
                        const int shift = static_cast<int>(4 * (y & 3) + 16 * (z & 3));
                        for (std::int64_t x = 0; x < n[0]; ++x) {
                            if (row != nullptr ? row[4 * x] > 0.0f : bytes[4 * x] > 0) {
                                out[x >> 2] |= std::uint64_t{1}
                                               << (shift + static_cast<int>(x & 3));
                            }
                        }
                    }
                }
            },
            1);
        dilate_bricks(m_brick_bits, m_bricks);
    }
    if (options.shading) {
        build_gradient();
    }
    m_prepare_ms = watch.elapsed_ms();
}

MappedRayCaster::~MappedRayCaster() = default;

void MappedRayCaster::build_gradient() {
    const std::int64_t n[3] = {m_source_dims[0], m_source_dims[1], m_source_dims[2]};
    const std::int64_t channels = m_source->m_is_rgba ? 4 : 1;
    // The shaded values lie in [0, 1] (α) or [0, LUT_SIZE − 1] (lookup coordinates), so |D| is
    // at most that range: it maps to 32767.
    const float scale = 32767.0f / (m_source->m_is_rgba ? 1.0f : float{detail::LUT_SIZE - 1});
    const float* values = m_rgba8.empty() ? m_source->m_values.data() + (channels - 1) : nullptr;
    // An rgba8 source: the packed records (detail::PACKED_VOXEL_BYTES: the bytes, the gradient,
    // 0, the neighbourhood's α byte, 0), which replace m_rgba8; else m_gradient, 4 values per
    // voxel.
    const bool packed = !m_rgba8.empty();
    constexpr std::int64_t VALUES = detail::PACKED_VOXEL_BYTES / 2;  // GradientValues per record
    detail::GradientValue* gradient = nullptr;
    std::int64_t stride = 4;  // GradientValues per voxel
    if (packed) {
        m_packed.resize(static_cast<std::size_t>(VALUES * n[0] * n[1] * n[2]));
        gradient = m_packed.data() + 2;
        stride = VALUES;
    } else {
        m_gradient.resize(static_cast<std::size_t>(4 * n[0] * n[1] * n[2]));
        gradient = m_gradient.data();
    }
    const auto quantize = [scale](float d) {
        return static_cast<detail::GradientValue>(
            std::clamp(std::nearbyint(d * scale), -32767.0f, 32767.0f));
    };
    parallel_for(
        n[2],
        [&](std::int64_t z) {
            const std::int64_t z0 = std::max<std::int64_t>(z - 1, 0);
            const std::int64_t z1 = std::min(z + 1, n[2] - 1);
            // rgba8: the α rows as the float copy holds them (detail::unit8()), 1 float per
            // voxel; else the float copy's rows, `channels` floats per voxel.
            std::vector<float> alpha_rows(m_rgba8.empty() ? 0 : static_cast<std::size_t>(5 * n[0]));
            const std::int64_t step = m_rgba8.empty() ? channels : 1;
            for (std::int64_t y = 0; y < n[1]; ++y) {
                const std::int64_t y0 = std::max<std::int64_t>(y - 1, 0);
                const std::int64_t y1 = std::min(y + 1, n[1] - 1);
                // The shaded value of voxel x of the k-th row (ry, rz) is row[step · x].
                const auto row = [&](int k, std::int64_t ry, std::int64_t rz) -> const float* {
                    if (m_rgba8.empty()) {
                        return values + channels * n[0] * (ry + n[1] * rz);
                    }
                    const std::uint8_t* in = &m_rgba8[4 * n[0] * (ry + n[1] * rz) + 3];
                    float* out = alpha_rows.data() + k * n[0];
                    for (std::int64_t x = 0; x < n[0]; ++x) {
                        out[x] = detail::unit8(in[4 * x]);
                    }
                    return out;
                };
                const float* here = row(0, y, z);
                const float* below_y = row(1, y0, z);
                const float* above_y = row(2, y1, z);
                const float* below_z = row(3, y, z0);
                const float* above_z = row(4, y, z1);
                const std::int64_t first = n[0] * (y + n[1] * z);
                detail::GradientValue* out = gradient + stride * first;
                for (std::int64_t x = 0; x < n[0]; ++x) {
                    const std::int64_t x0 = step * std::max<std::int64_t>(x - 1, 0);
                    const std::int64_t x1 = step * std::min(x + 1, n[0] - 1);
                    const std::int64_t at = step * x;
                    out[stride * x] = quantize(here[x1] - here[x0]);
                    out[stride * x + 1] = quantize(above_y[at] - below_y[at]);
                    out[stride * x + 2] = quantize(above_z[at] - below_z[at]);
                    out[stride * x + 3] = 0;
                }
                if (packed) {
                    detail::GradientValue* record = m_packed.data() + VALUES * first;
                    for (std::int64_t x = 0; x < n[0]; ++x) {
                        std::memcpy(record + VALUES * x, &m_rgba8[4 * (first + x)], 4);
                        record[VALUES * x + 6] = 0;
                        record[VALUES * x + 7] = 0;
                    }
                }
            }
        },
        1);
    if (packed) {
        neighbourhood_alpha(
            m_rgba8.data(), n,
            reinterpret_cast<std::uint8_t*>(m_packed.data()) + detail::PACKED_WIDE_ALPHA,
            detail::PACKED_VOXEL_BYTES);
        m_rgba8 = {};
    }
}

void MappedRayCaster::set_clip(const std::optional<ClipPlane>& clip) {
    m_source->set_clip(clip);  // validates
    m_source->set_clip(std::nullopt);
    m_options.clip = clip;
}

void MappedRayCaster::set_thin_alpha(double thin_alpha) {
    if (!(thin_alpha >= 0.0 && thin_alpha <= 1.0)) {
        throw InvalidInput(
            fmt::format("raycast through a map: thin_alpha must be in [0, 1], got {}", thin_alpha));
    }
    m_thin_alpha = thin_alpha;
}

void MappedRayCaster::set_thin_levels(int levels) {
    if (levels < 0 || levels > detail::MAX_THIN_LEVELS) {
        throw InvalidInput(
            fmt::format("raycast through a map: thin_levels must be in [0, {}], got {}",
                        detail::MAX_THIN_LEVELS, levels));
    }
    m_thin_levels = levels;
}

std::int64_t MapOccupancy::num_visible_cells() const {
    std::int64_t count = 0;
    for (const std::uint8_t v : m_visible) {
        count += v;
    }
    return count;
}

void MapOccupancy::clear() {
    m_map = nullptr;
    m_octants_ready = 0;
}

bool MappedRayCaster::corner_range(const float lo[3], const float hi[3], std::int64_t v0[3],
                                   std::int64_t v1[3]) const {
    for (int a = 0; a < 3; ++a) {
        const std::int64_t n = m_source_dims[static_cast<std::size_t>(a)];
        const auto last = static_cast<float>(n - 1);
        const float l = lo[a] - HULL_MARGIN;
        const float h = hi[a] + HULL_MARGIN;
        if (h < -0.5f || l > last + 0.5f) {
            return false;  // every sample outside the source: transparent
        }
        const std::int64_t max_i0 = std::max<std::int64_t>(0, n - 2);
        v0[a] = std::min(static_cast<std::int64_t>(std::clamp(l, 0.0f, last)), max_i0);
        v1[a] = std::min(static_cast<std::int64_t>(std::clamp(h, 0.0f, last)), max_i0);
    }
    return true;
}

bool MappedRayCaster::bricks_visible(const std::int64_t v0[3], const std::int64_t v1[3]) const {
    // The dilated bricks (dilate_bricks(): bit v covers voxels v and v + 1 per axis) at
    // [v0, v1]: exact per voxel; on an axis of one voxel v1 = v0, whose bit covers that voxel
    // alone. A point (the cell's centre) reads one bit.
    std::int64_t b0[3], b1[3];
    for (int a = 0; a < 3; ++a) {
        b0[a] = v0[a] >> BRICK_SHIFT;
        b1[a] = v1[a] >> BRICK_SHIFT;
    }
    if (b0[0] == b1[0] && b0[1] == b1[1] && b0[2] == b1[2]) {  // one brick (most points)
        std::uint64_t mask = m_brick_bits[static_cast<std::size_t>(
            b0[0] + m_bricks[0] * (b0[1] + m_bricks[1] * b0[2]))];
        for (int a = 0; a < 3; ++a) {
            mask &= BRICK_MASKS[static_cast<std::size_t>(a)][static_cast<std::size_t>(v0[a] & 3)]
                               [static_cast<std::size_t>(v1[a] & 3)];
        }
        return mask != 0;
    }
    for (std::int64_t bz = b0[2]; bz <= b1[2]; ++bz) {
        const std::uint64_t mz = range_mask(2, bz, v0[2], v1[2]);
        for (std::int64_t by = b0[1]; by <= b1[1]; ++by) {
            const std::uint64_t myz = mz & range_mask(1, by, v0[1], v1[1]);
            const std::uint64_t* row = m_brick_bits.data() + m_bricks[0] * (by + m_bricks[1] * bz);
            for (std::int64_t bx = b0[0]; bx <= b1[0]; ++bx) {
                if ((row[bx] & myz & range_mask(0, bx, v0[0], v1[0])) != 0) {
                    return true;
                }
            }
        }
    }
    return false;
}

bool MappedRayCaster::hull_visible(const float lo[3], const float hi[3]) const {
    std::int64_t v0[3] = {}, v1[3] = {};
    return corner_range(lo, hi, v0, v1) && bricks_visible(v0, v1);
}

std::uint8_t MappedRayCaster::sub_cells_visible(const float* g, std::int64_t base,
                                                const std::int64_t off[8], const float lo[3],
                                                const float hi[3]) const {
    // Every half-cell has the cell's centre (the mean of its nodes) as a corner, so its box
    // holds the centre's: when the voxels the centre reads have opacity, all 8 are visible
    // (inside the body, most cells). Else, when the cell's box has none, none is.
    float centre[3];
    for (int ch = 0; ch < 3; ++ch) {
        const float* v = g + 3 * base + ch;
        centre[ch] = 0.5f * (0.5f * (0.5f * (v[3 * off[0]] + v[3 * off[1]]) +
                                     0.5f * (v[3 * off[2]] + v[3 * off[3]])) +
                             0.5f * (0.5f * (v[3 * off[4]] + v[3 * off[5]]) +
                                     0.5f * (v[3 * off[6]] + v[3 * off[7]])));
    }
    if (hull_visible(centre, centre)) {
        return 0xFF;
    }
    if (!hull_visible(lo, hi)) {
        return 0;
    }
    // The map at the 3³ lattice of half-cell fractions: per channel, the node values (lattice
    // points 0 and 2 per axis) and their midpoints, along x, then y, then z.
    float lattice[27][3];
    for (int c = 0; c < 8; ++c) {
        const float* v = g + 3 * (base + off[c]);
        const int at = 2 * (c & 1) + 6 * ((c >> 1) & 1) + 18 * (c >> 2);
        for (int ch = 0; ch < 3; ++ch) {
            lattice[at][ch] = v[ch];
        }
    }
    for (int ch = 0; ch < 3; ++ch) {
        for (const int row : {0, 6, 18, 24}) {  // x midpoints of the rows y, z ∈ {0, 2}
            lattice[row + 1][ch] = 0.5f * (lattice[row][ch] + lattice[row + 2][ch]);
        }
        for (const int z : {0, 18}) {  // y midpoints of the layers z ∈ {0, 2}
            for (int x = 0; x < 3; ++x) {
                lattice[z + 3 + x][ch] = 0.5f * (lattice[z + x][ch] + lattice[z + 6 + x][ch]);
            }
        }
        for (int xy = 0; xy < 9; ++xy) {  // z midpoints
            lattice[9 + xy][ch] = 0.5f * (lattice[xy][ch] + lattice[18 + xy][ch]);
        }
    }
    std::uint8_t bits = 0;
    for (int sub = 0; sub < 8; ++sub) {
        const int first = (sub & 1) + 3 * ((sub >> 1) & 1) + 9 * (sub >> 2);
        float sub_lo[3] = {lattice[first][0], lattice[first][1], lattice[first][2]};
        float sub_hi[3] = {sub_lo[0], sub_lo[1], sub_lo[2]};
        for (int c = 1; c < 8; ++c) {
            const float* v = lattice[first + (c & 1) + 3 * ((c >> 1) & 1) + 9 * (c >> 2)];
            for (int a = 0; a < 3; ++a) {
                sub_lo[a] = std::min(sub_lo[a], v[a]);
                sub_hi[a] = std::max(sub_hi[a], v[a]);
            }
        }
        if (hull_visible(sub_lo, sub_hi)) {
            bits = static_cast<std::uint8_t>(bits | (1 << sub));
        }
    }
    return bits;
}

void MappedRayCaster::compute_map(const volume::InverseMap& map, MapOccupancy& state,
                                  int octants) const {
    const Stopwatch watch;
    const std::array<std::int64_t, 3>& nodes = map.nodes();
    const int b = map.node_voxels();
    if (nodes[0] == 0) {
        throw InvalidInput("raycast through a map: the map was not built");
    }
    for (int a = 0; a < 3; ++a) {
        const std::int64_t expected = (m_target_dims[static_cast<std::size_t>(a)] - 1) / b + 2;
        if (nodes[static_cast<std::size_t>(a)] != expected) {
            throw InvalidInput(fmt::format(
                "raycast through a map: the map has {} nodes along axis {}, expected {} for the "
                "target's {} voxels at {} voxels per node",
                nodes[static_cast<std::size_t>(a)], a, expected,
                m_target_dims[static_cast<std::size_t>(a)], b));
        }
    }
    state.m_map = nullptr;  // until it is complete (an exception leaves it without a map)
    std::array<int, 3>& cells = state.m_cells;
    for (int a = 0; a < 3; ++a) {
        cells[static_cast<std::size_t>(a)] =
            static_cast<int>(nodes[static_cast<std::size_t>(a)] - 1);
    }
    const std::int64_t cx_n = cells[0], cy_n = cells[1], cz_n = cells[2];
    const auto total = static_cast<std::size_t>(cx_n * cy_n * cz_n);
    state.m_occupancy.resize(total);
    state.m_sub_occupied.resize(total);
    state.m_visible.resize(total);
    const float* g = map.node_coordinates().data();
    const std::int64_t nx = nodes[0], nxy = nodes[0] * nodes[1];
    const std::int64_t off[8] = {0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1};
    const std::int32_t* extents = map.node_row_extents().data();
    // Per layer of cells the extents of its visible cells (detail::VisibleCells), then their
    // union.
    std::vector<detail::VisibleCells> layer_cells(static_cast<std::size_t>(cz_n));
    parallel_for(
        cz_n,
        [&](std::int64_t cz) {
            detail::VisibleCells& layer = layer_cells[static_cast<std::size_t>(cz)];
            for (std::int64_t cy = 0; cy < cy_n; ++cy) {
                // Cells with both x nodes inside the 4 node rows' extents (the others have an
                // empty node): [x0, x1).
                std::int64_t x0 = 0;
                std::int64_t x1 = cx_n;
                for (const std::int64_t row :
                     {cy + nodes[1] * cz, cy + 1 + nodes[1] * cz, cy + nodes[1] * (cz + 1),
                      cy + 1 + nodes[1] * (cz + 1)}) {
                    x0 = std::max<std::int64_t>(x0, extents[2 * row]);
                    x1 = std::min<std::int64_t>(x1, extents[2 * row + 1] - 1);
                }
                const auto row_cell = static_cast<std::size_t>(cx_n * (cy + cy_n * cz));
                if (x0 >= x1) {
                    x0 = x1 = 0;
                }
                std::fill_n(state.m_occupancy.begin() + static_cast<std::ptrdiff_t>(row_cell), cx_n,
                            0);
                std::fill_n(state.m_sub_occupied.begin() + static_cast<std::ptrdiff_t>(row_cell),
                            cx_n, 0);
                std::fill_n(state.m_visible.begin() + static_cast<std::ptrdiff_t>(row_cell), cx_n,
                            0);
                for (std::int64_t cx = x0; cx < x1; ++cx) {
                    const auto cell = static_cast<std::size_t>(cx + cx_n * (cy + cy_n * cz));
                    const std::int64_t base = cx + nx * cy + nxy * cz;
                    // Most cells away from the body have an empty node: passed over at the
                    // first one.
                    bool valid = true;
                    for (const std::int64_t o : off) {
                        if (std::isnan(g[3 * (base + o)])) {
                            valid = false;
                            break;
                        }
                    }
                    if (!valid) {
                        state.m_occupancy[cell] = 0;
                        state.m_sub_occupied[cell] = 0;
                        state.m_visible[cell] = 0;
                        continue;
                    }
                    float lo[3] = {g[3 * base], g[3 * base + 1], g[3 * base + 2]};
                    float hi[3] = {lo[0], lo[1], lo[2]};
                    for (int c = 1; c < 8; ++c) {
                        const float* v = g + 3 * (base + off[c]);
                        for (int a = 0; a < 3; ++a) {
                            lo[a] = std::min(lo[a], v[a]);
                            hi[a] = std::max(hi[a], v[a]);
                        }
                    }
                    std::uint8_t bits = detail::MAP_CELL_VALID;
                    const std::uint8_t sub = sub_cells_visible(g, base, off, lo, hi);
                    if (sub != 0) {
                        bits = static_cast<std::uint8_t>(bits | detail::MAP_CELL_VISIBLE);
                    }
                    state.m_occupancy[cell] = bits;
                    state.m_sub_occupied[cell] = sub;
                    state.m_visible[cell] = sub != 0 ? 1 : 0;
                    if (sub != 0) {
                        const std::int64_t at[3] = {cx, cy, cz};
                        layer.add(at);
                    }
                }
            }
        },
        1);
    state.m_visible_cells = detail::VisibleCells();
    for (const detail::VisibleCells& layer : layer_cells) {
        state.m_visible_cells.merge(layer);
    }
    // The nodes padded to 4 floats (the AVX2 march loads a node pair as 8 floats).
    state.m_nodes4.resize(static_cast<std::size_t>(4 * nxy * nodes[2]));
    parallel_for(
        nodes[2],
        [&](std::int64_t z) {
            for (std::int64_t q = nxy * z; q < nxy * (z + 1); ++q) {
                const float* in = g + 3 * q;
                float* out = state.m_nodes4.data() + 4 * q;
                out[0] = in[0];
                out[1] = in[1];
                out[2] = in[2];
                out[3] = 0.0f;
            }
        },
        1);
    state.m_empty_cube.resize(8 * total);
    state.m_octants_ready = 0;
    state.m_caster = m_id;
    state.m_map = &map;
    compute_cubes(state, octants);
    state.m_ms = watch.elapsed_ms();
}

void MappedRayCaster::install_map(MapOccupancy& state) {
    if (!state.has_map()) {
        throw InvalidInput("raycast through a map: the state to install has no map");
    }
    if (state.m_caster != m_id) {
        throw InvalidInput(
            "raycast through a map: the state to install was computed by another caster");
    }
    std::swap(m_state, state);
}

void MappedRayCaster::set_map(const volume::InverseMap& map) {
    compute_map(map, m_state);
}

int MappedRayCaster::octants_of(const Camera& camera) const {
    detail::RayCastKernel k;
    set_camera(camera, m_target_origin, k);
    return ray_octants(k);
}

void MappedRayCaster::compute_cubes(const MapOccupancy& state, int octants) {
    int todo[8];
    int count = 0;
    for (int octant = 0; octant < 8; ++octant) {
        if ((octants >> octant & 1) != 0 && (state.m_octants_ready >> octant & 1) == 0) {
            todo[count++] = octant;
        }
    }
    if (count == 0) {
        return;
    }
    const std::size_t total = state.m_occupancy.size();
    parallel_for(
        count,
        [&](std::int64_t i) {
            const int octant = todo[i];
            detail::empty_cubes(state.m_visible, state.m_cells.data(), octant,
                                std::span<std::uint8_t>(state.m_empty_cube)
                                    .subspan(static_cast<std::size_t>(octant) * total, total));
        },
        1);
    state.m_octants_ready |= octants;
}

RayCastStats MappedRayCaster::render(const Camera& camera, Image& image) const {
    const MapOccupancy& state = m_state;
    if (state.m_map == nullptr) {
        throw InvalidInput("raycast through a map: set_map() was not called");
    }
    const Stopwatch watch;
    detail::MappedKernel m;
    m_source->fill_kernel(m.source);
    detail::RayCastKernel& k = m.target;
    k = m.source;  // options (step, opacity correction, threshold, background, skipping)
    set_camera(camera, m_target_origin, k);
    const Vec3d inv{1.0 / m_target_spacing.x, 1.0 / m_target_spacing.y, 1.0 / m_target_spacing.z};
    k.inv_spacing = vec3_cast<float>(inv);
    for (int a = 0; a < 3; ++a) {
        k.n[a] = static_cast<int>(m_target_dims[static_cast<std::size_t>(a)]);
        k.g_max[a] = static_cast<float>(k.n[a] - 1);
        k.max_i0[a] = std::max(0, k.n[a] - 2);
        m.source_hi[a] = static_cast<float>(m_source_dims[static_cast<std::size_t>(a)]) - 0.5f;
        m.cells[a] = state.m_cells[static_cast<std::size_t>(a)];
    }
    k.shading = m_options.shading;
    k.skipping = m_options.empty_space_skipping;
    k.has_clip = false;
    if (m_options.clip) {
        const Vec3d nrm = m_options.clip->normal / norm(m_options.clip->normal);
        k.has_clip = true;
        k.clip_normal = vec3_cast<float>(nrm);
        k.clip_offset = static_cast<float>(dot(nrm, m_options.clip->point - m_target_origin));
    }
    m.nodes = state.m_map->node_coordinates().data();
    m.nodes4 = state.m_nodes4.data();
    m.node_stride[0] = 1;
    m.node_stride[1] = state.m_map->nodes()[0];
    m.node_stride[2] = state.m_map->nodes()[0] * state.m_map->nodes()[1];
    m.b = static_cast<float>(state.m_map->node_voxels());
    m.inv_b = 1.0f / m.b;
    m.occupancy = state.m_occupancy.data();
    m.sub_occupied = state.m_sub_occupied.data();
    m.half_b = 0.5f * m.b;
    m.gradient = m_gradient.empty() ? nullptr : m_gradient.data();
    if (!m_rgba8.empty() || !m_packed.empty()) {
        // The source's grid (its RayCaster holds one voxel, for the options' fields).
        detail::RayCastKernel& s = m.source;
        const std::int64_t n[3] = {m_source_dims[0], m_source_dims[1], m_source_dims[2]};
        for (int a = 0; a < 3; ++a) {
            s.n[a] = static_cast<int>(n[a]);
            s.g_max[a] = static_cast<float>(s.n[a] - 1);
            s.max_i0[a] = std::max(0, s.n[a] - 2);
        }
        s.d[0] = n[0] > 1 ? 1 : 0;
        s.d[1] = n[1] > 1 ? n[0] : 0;
        s.d[2] = n[2] > 1 ? n[0] * n[1] : 0;
        s.stride[0] = 1;
        s.stride[1] = n[0];
        s.stride[2] = n[0] * n[1];
        s.values = nullptr;
        s.alpha = nullptr;
        if (m_packed.empty()) {
            m.rgba8 = m_rgba8.data();
        } else {
            // The packed records (detail::PACKED_VOXEL_BYTES): the bytes, then the gradient.
            const auto* record = reinterpret_cast<const std::uint8_t*>(m_packed.data());
            m.rgba8 = record;
            m.rgba8_stride = detail::PACKED_VOXEL_BYTES;
            m.gradient = m_packed.data() + 2;
            m.gradient_stride = detail::PACKED_VOXEL_BYTES / sizeof(detail::GradientValue);
        }
        // The adaptive step's thresholds on the α bytes: thin_alpha, halved per level.
        const auto thin_bytes = static_cast<float>(m_thin_alpha * 255.0);
        // The second level needs the packed records' neighbourhood byte (a shaded source).
        m.thin_levels =
            thin_bytes > 0.0f ? (m_packed.empty() ? std::min(m_thin_levels, 1) : m_thin_levels) : 0;
        for (int l = 0; l < m.thin_levels; ++l) {
            m.thin_limit[l] = std::ldexp(thin_bytes, -l);
        }
    }
    detail::set_visible_cells(m, state.m_visible_cells);
    for (int octant = 0; octant < 8; ++octant) {
        m.empty_cube[octant] =
            state.m_empty_cube.data() + static_cast<std::size_t>(octant) * state.m_occupancy.size();
    }

    if (k.skipping) {
        const std::lock_guard<std::mutex> lock(m_cubes_mutex);
        compute_cubes(state, ray_octants(k));
    }
    image = Image(k.width, k.height);
    const bool is_rgba = m_source->m_is_rgba;
    // The AVX2 march gives the scalar kernel's bits (detail/mapped_raycast_avx2.hpp).
    const bool use_avx2 = detail::mapped_avx2_fits(m);
    RayCastStats stats;
    stats.samples = detail::render_tiles(k.width, k.height, [&](int x0, int y0, int x1, int y1) {
        std::int64_t samples = 0;
        if (use_avx2) {
            Color colors[detail::TILE * detail::TILE];
            samples = detail::mapped_tile_avx2(m, x0, y0, x1, y1, colors);
            for (int y = y0; y < y1; ++y) {
                for (int x = x0; x < x1; ++x) {
                    image.set(x, y, to_rgb8(colors[(y - y0) * (x1 - x0) + (x - x0)]));
                }
            }
            return samples;
        }
        for (int y = y0; y < y1; ++y) {
            for (int x = x0; x < x1; ++x) {
                const detail::PixelResult p = is_rgba ? detail::mapped_pixel<true>(m, x, y)
                                                      : detail::mapped_pixel<false>(m, x, y);
                image.set(x, y, to_rgb8(p.color));
                samples += p.samples;
            }
        }
        return samples;
    });
    stats.ms = watch.elapsed_ms();
    return stats;
}

}  // namespace pliant::render
