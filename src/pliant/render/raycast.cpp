#include "pliant/render/raycast.hpp"

#include <fmt/format.h>

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
#include "pliant/core/timer.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"

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

    // Step 2: macro cells, min/max over each cell's footprint (raycast_kernel.hpp: the samples
    // with lower corner in [CELL·c, CELL·c + CELL − 1] read the voxels [CELL·c, CELL·c + CELL]).
    for (int a = 0; a < 3; ++a) {
        const std::int64_t max_i0 = std::max<std::int64_t>(0, m_dims[a] - 2);
        m_cells[a] = static_cast<int>(max_i0 / detail::CELL + 1);
    }
    const std::int64_t total_cells = num_cells();
    m_occupied.assign(static_cast<std::size_t>(total_cells), 0);
    m_cell_max.assign(static_cast<std::size_t>(total_cells), 0.0f);
    m_sub_occupied.assign(static_cast<std::size_t>(total_cells), 0);
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
            // The cell's footprint (up to 5³ voxels, read once), then its 8 sub-cells (2³
            // trilinear cells each, footprint 3³ voxels; the cell's footprint is their union).
            constexpr int F = detail::CELL + 1;
            float buf[F][F][F];
            std::int64_t count[3];
            for (int a = 0; a < 3; ++a) {
                count[a] = std::min<std::int64_t>(F, m_dims[a] - c[a] * detail::CELL);
            }
            for (std::int64_t z = 0; z < count[2]; ++z) {
                for (std::int64_t y = 0; y < count[1]; ++y) {
                    const std::int64_t row =
                        c[0] * detail::CELL + m_dims[0] * (c[1] * detail::CELL + y +
                                                           m_dims[1] * (c[2] * detail::CELL + z));
                    for (std::int64_t x = 0; x < count[0]; ++x) {
                        buf[z][y][x] = m_values[static_cast<std::size_t>(
                            (row + x) * channel_stride + channel)];
                    }
                }
            }
            float cell_max = -std::numeric_limits<float>::infinity();
            std::uint8_t sub_mask = 0;
            for (int sub = 0; sub < 8; ++sub) {
                std::int64_t lo[3], hi[3];
                for (int a = 0; a < 3; ++a) {
                    lo[a] = detail::SUB_CELL * ((sub >> a) & 1);
                    hi[a] = std::min<std::int64_t>(count[a] - 1, lo[a] + detail::SUB_CELL);
                }
                float vmin = std::numeric_limits<float>::infinity();
                float vmax = -vmin;
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                            vmin = std::min(vmin, buf[z][y][x]);
                            vmax = std::max(vmax, buf[z][y][x]);
                        }
                    }
                }
                if (!(vmin <= vmax)) {
                    continue;  // past the grid: no sample has its corner here
                }
                cell_max = std::max(cell_max, vmax);
                bool occupied = false;
                if (m_is_rgba) {
                    occupied = vmax > 0.0f;
                } else {
                    // Interpolated values lie in [vmin, vmax] up to a rounding of the lerps,
                    // which may move the nearest entry by one: widened by an entry per side.
                    const int i0 = std::max(0, static_cast<int>(vmin + 0.5f) - 1);
                    const int i1 =
                        std::min(detail::LUT_SIZE - 1, static_cast<int>(vmax + 0.5f) + 1);
                    occupied = nonzero_prefix[i1 + 1] - nonzero_prefix[i0] > 0;
                }
                sub_mask = static_cast<std::uint8_t>(sub_mask | (occupied ? 1 << sub : 0));
            }
            const bool occupied = sub_mask != 0;
            const float vmax = cell_max;
            m_sub_occupied[static_cast<std::size_t>(cell)] = sub_mask;
            m_occupied[static_cast<std::size_t>(cell)] = occupied ? 1 : 0;
            m_cell_max[static_cast<std::size_t>(cell)] = vmax;
        },
        64);
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
    k.is_mip = m_options.mode == RayCastMode::mip;
    k.shading = m_options.shading && !k.is_mip;
    k.skipping = m_options.empty_space_skipping;
    k.background = m_options.background;
    k.grid_offset = {-0.5f, -0.5f, -0.5f};
    if (m_options.clip) {
        // In the kernel's frame (world relative to the volume's origin), unit normal.
        const Vec3d n = m_options.clip->normal / norm(m_options.clip->normal);
        k.has_clip = true;
        k.clip_normal = vec3_cast<float>(n);
        k.clip_offset = static_cast<float>(dot(n, m_options.clip->point - m_origin));
    }

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
