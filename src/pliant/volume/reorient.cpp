#include "pliant/volume/reorient.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {

namespace {

constexpr double SNAP_TO_AXIS = 1e-6;    // |off-axis component| below which an axis is a world axis
constexpr double SNAP_TO_SAMPLE = 1e-6;  // voxels: a sample this near a voxel centre takes it
constexpr std::size_t NO_LIMIT = std::numeric_limits<std::size_t>::max();

std::string vec_text(const Vec3d& v) {
    return fmt::format("({}, {}, {})", v.x, v.y, v.z);
}

// The nearest orthonormal matrix (polar decomposition) to the columns `d`, by the iteration
// X ← (X + X^-T) / 2, which converges quadratically from a nearly orthonormal start. X^-T has the
// columns (c1 × c2, c2 × c0, c0 × c1) / det.
Direction orthonormalized(Direction d) {
    for (int iteration = 0; iteration < 20; ++iteration) {
        const double det = dot(d[0], cross(d[1], d[2]));
        const Direction inverse_t{cross(d[1], d[2]) / det, cross(d[2], d[0]) / det,
                                  cross(d[0], d[1]) / det};
        double change = 0.0;
        for (std::size_t a = 0; a < 3; ++a) {
            const Vec3d next = (d[a] + inverse_t[a]) * 0.5;
            change = std::max(change, norm(next - d[a]));
            d[a] = next;
        }
        if (change < 1e-15) {
            break;
        }
    }
    return d;
}

// Copies `source` into a volume whose axis r is the source's axis perm[r], reversed where
// flip[perm[r]]. Voxels are moved as opaque bytes (any type).
Volume permuted(const Volume& source, const std::array<int, 3>& perm,
                const std::array<bool, 3>& flip) {
    const Dims& n = source.dims();
    const Dims out_dims{n[static_cast<std::size_t>(perm[0])], n[static_cast<std::size_t>(perm[1])],
                        n[static_cast<std::size_t>(perm[2])]};
    Volume out = Volume::allocate(out_dims, source.type(), {1, 1, 1}, {0, 0, 0}, NO_LIMIT);
    const std::size_t voxel = bytes_per_voxel(source.type());
    // Source index = base + Σ_r i_r · stride_r, where stride_r is the source stride of axis
    // perm[r], negated (and base moved to the far end) when that axis is flipped.
    const std::array<std::int64_t, 3> source_stride{1, n[0], n[0] * n[1]};
    std::int64_t base = 0;
    std::array<std::int64_t, 3> stride{};
    for (std::size_t r = 0; r < 3; ++r) {
        const auto a = static_cast<std::size_t>(perm[r]);
        stride[r] = flip[a] ? -source_stride[a] : source_stride[a];
        if (flip[a]) {
            base += (n[a] - 1) * source_stride[a];
        }
    }
    const std::byte* in = source.bytes().data();
    std::byte* dst = out.bytes().data();
    parallel_for(
        out_dims[2],
        [&](std::int64_t k) {
            for (std::int64_t j = 0; j < out_dims[1]; ++j) {
                std::int64_t s = base + k * stride[2] + j * stride[1];
                std::int64_t d = out.index(0, j, k);
                for (std::int64_t i = 0; i < out_dims[0]; ++i, s += stride[0], ++d) {
                    std::memcpy(dst + static_cast<std::size_t>(d) * voxel,
                                in + static_cast<std::size_t>(s) * voxel, voxel);
                }
            }
        },
        1);
    return out;
}

// Reverses the voxel order along each flagged axis, in place (no second copy of the data).
void flip_in_place(Volume& volume, const std::array<bool, 3>& flip) {
    const Dims& d = volume.dims();
    const std::size_t bpv = bytes_per_voxel(volume.type());
    std::byte* bytes = volume.bytes().data();
    std::array<std::byte, 16> tmp{};
    for (std::int64_t k = 0; k < d[2]; ++k) {
        for (std::int64_t j = 0; j < d[1]; ++j) {
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const std::int64_t a = volume.index(i, j, k);
                const std::int64_t b =
                    volume.index(flip[0] ? d[0] - 1 - i : i, flip[1] ? d[1] - 1 - j : j,
                                 flip[2] ? d[2] - 1 - k : k);
                if (a < b) {
                    std::byte* pa = bytes + static_cast<std::size_t>(a) * bpv;
                    std::byte* pb = bytes + static_cast<std::size_t>(b) * bpv;
                    std::memcpy(tmp.data(), pa, bpv);
                    std::memcpy(pa, pb, bpv);
                    std::memcpy(pb, tmp.data(), bpv);
                }
            }
        }
    }
}

// Trilinear resampling of one voxel type: T is the channel type, C the channels.
template <typename T, int C>
void resample_into(const Volume& source, Volume& out, double outside) {
    const Dims& n = source.dims();
    const Dims& m = out.dims();
    const std::span<const T> in(reinterpret_cast<const T*>(source.bytes().data()),
                                source.bytes().size() / sizeof(T));
    const std::span<T> dst(reinterpret_cast<T*>(out.bytes().data()),
                           out.bytes().size() / sizeof(T));
    const Direction& d = source.direction();
    const Vec3d s = source.spacing();
    const Vec3d o = source.origin();
    const auto to_channel = [](double v) -> T {
        if constexpr (std::is_floating_point_v<T>) {
            return static_cast<T>(v);
        } else {
            const double r = std::nearbyint(v);
            const auto lo = static_cast<double>(std::numeric_limits<T>::lowest());
            const auto hi = static_cast<double>(std::numeric_limits<T>::max());
            return static_cast<T>(std::clamp(r, lo, hi));
        }
    };
    const T outside_value = to_channel(outside);
    // Continuous source index (voxel centre i at u = i) of a world point, per axis.
    const auto grid_coordinate = [&](const Vec3d& p, std::size_t a) {
        double u = dot(d[a], p - o) / s[static_cast<int>(a)] - 0.5;
        const double nearest = std::nearbyint(u);
        if (std::abs(u - nearest) <= SNAP_TO_SAMPLE) {
            u = nearest;
        }
        return u;
    };
    parallel_for(
        m[2],
        [&](std::int64_t k) {
            for (std::int64_t j = 0; j < m[1]; ++j) {
                for (std::int64_t i = 0; i < m[0]; ++i) {
                    const Vec3d p = out.voxel_center(i, j, k);
                    std::array<std::int64_t, 3> i0{};
                    std::array<std::int64_t, 3> i1{};
                    std::array<double, 3> f{};
                    bool inside = true;
                    for (std::size_t a = 0; a < 3; ++a) {
                        const double u = grid_coordinate(p, a);
                        const auto last = static_cast<double>(n[a] - 1);
                        if (!(u >= -0.5 - SNAP_TO_SAMPLE && u <= last + 0.5 + SNAP_TO_SAMPLE)) {
                            inside = false;
                            break;
                        }
                        const double c = std::clamp(u, 0.0, last);
                        const auto lo = std::min(static_cast<std::int64_t>(std::floor(c)),
                                                 std::max<std::int64_t>(n[a] - 2, 0));
                        i0[a] = lo;
                        i1[a] = std::min(lo + 1, n[a] - 1);
                        f[a] = c - static_cast<double>(lo);
                    }
                    const std::int64_t out_index = out.index(i, j, k) * C;
                    if (!inside) {
                        for (int c = 0; c < C; ++c) {
                            dst[static_cast<std::size_t>(out_index + c)] = outside_value;
                        }
                        continue;
                    }
                    std::array<double, C> sum{};
                    for (int corner = 0; corner < 8; ++corner) {
                        const bool bx = (corner & 1) != 0;
                        const bool by = (corner & 2) != 0;
                        const bool bz = (corner & 4) != 0;
                        const double w = (bx ? f[0] : 1.0 - f[0]) * (by ? f[1] : 1.0 - f[1]) *
                                         (bz ? f[2] : 1.0 - f[2]);
                        if (w == 0.0) {
                            continue;
                        }
                        const std::int64_t at = source.index(bx ? i1[0] : i0[0], by ? i1[1] : i0[1],
                                                             bz ? i1[2] : i0[2]) *
                                                C;
                        for (int c = 0; c < C; ++c) {
                            sum[static_cast<std::size_t>(c)] +=
                                w * static_cast<double>(in[static_cast<std::size_t>(at + c)]);
                        }
                    }
                    for (int c = 0; c < C; ++c) {
                        dst[static_cast<std::size_t>(out_index + c)] =
                            to_channel(sum[static_cast<std::size_t>(c)]);
                    }
                }
            }
        },
        1);
}

}  // namespace

double max_axis_cosine(const GridPlacement& placement) {
    double largest = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double na = norm(placement.steps[a]);
        if (!std::isfinite(na) || na == 0.0) {
            return std::numeric_limits<double>::quiet_NaN();
        }
        for (std::size_t b = a + 1; b < 3; ++b) {
            const double nb = norm(placement.steps[b]);
            if (!std::isfinite(nb) || nb == 0.0) {
                return std::numeric_limits<double>::quiet_NaN();
            }
            largest = std::max(largest,
                               std::abs(dot(placement.steps[a], placement.steps[b])) / (na * nb));
        }
    }
    return largest;
}

Volume place_nearest_axes(Volume volume, const GridPlacement& placement) {
    if (!is_finite(placement.centre0)) {
        throw InvalidInput(
            fmt::format("place_nearest_axes: the first voxel's centre must be "
                        "finite, got {}",
                        vec_text(placement.centre0)));
    }
    for (std::size_t a = 0; a < 3; ++a) {
        const Vec3d& step = placement.steps[a];
        if (!is_finite(step) || squared_norm(step) == 0.0) {
            throw InvalidInput(fmt::format(
                "place_nearest_axes: the step along grid axis {} must be finite and non-zero, got "
                "{}",
                a, vec_text(step)));
        }
    }
    const double cosine = max_axis_cosine(placement);
    if (!(cosine <= MAX_AXIS_COSINE)) {
        throw InvalidInput(fmt::format(
            "place_nearest_axes: the grid is sheared: its axes {} {} {} are not orthogonal "
            "(largest |cosine| {:.3g}, expected at most {})",
            vec_text(placement.steps[0]), vec_text(placement.steps[1]),
            vec_text(placement.steps[2]), cosine, MAX_AXIS_COSINE));
    }

    // The signed permutation nearest to the normalized steps: repeatedly the largest remaining
    // |component| (ties: lowest world axis, then lowest grid axis) pairs a world axis r with a
    // grid axis a.
    Direction unit{};
    for (std::size_t a = 0; a < 3; ++a) {
        unit[a] = placement.steps[a] / norm(placement.steps[a]);
    }
    std::array<int, 3> perm{-1, -1, -1};  // new axis r is old axis perm[r]
    std::array<bool, 3> used{false, false, false};
    for (int round = 0; round < 3; ++round) {
        double best = -1.0;
        int best_r = -1;
        int best_a = -1;
        for (int r = 0; r < 3; ++r) {
            if (perm[static_cast<std::size_t>(r)] >= 0) {
                continue;
            }
            for (int a = 0; a < 3; ++a) {
                if (used[static_cast<std::size_t>(a)]) {
                    continue;
                }
                const double v = std::abs(unit[static_cast<std::size_t>(a)][r]);
                if (v > best) {
                    best = v;
                    best_r = r;
                    best_a = a;
                }
            }
        }
        perm[static_cast<std::size_t>(best_r)] = best_a;
        used[static_cast<std::size_t>(best_a)] = true;
    }
    std::array<bool, 3> flip{};
    for (std::size_t r = 0; r < 3; ++r) {
        const auto a = static_cast<std::size_t>(perm[r]);
        flip[a] = unit[a][static_cast<int>(r)] < 0.0;
    }

    // Voxel (0, 0, 0) after re-indexing is the old voxel at the far end of every flipped axis.
    const Dims old_dims = volume.dims();
    Vec3d centre0 = placement.centre0;
    for (std::size_t a = 0; a < 3; ++a) {
        if (flip[a]) {
            centre0 += placement.steps[a] * static_cast<double>(old_dims[a] - 1);
        }
    }
    std::array<Vec3d, 3> steps{};
    Direction direction{};
    for (std::size_t r = 0; r < 3; ++r) {
        const auto a = static_cast<std::size_t>(perm[r]);
        steps[r] = flip[a] ? -placement.steps[a] : placement.steps[a];
        direction[r] = flip[a] ? -unit[a] : unit[a];
    }
    const bool is_identity_perm = perm == std::array<int, 3>{0, 1, 2};
    const bool any_flip = flip[0] || flip[1] || flip[2];
    if (!is_identity_perm) {
        volume = permuted(volume, perm, flip);
    } else if (any_flip) {
        flip_in_place(volume, flip);
    }

    bool axis_aligned = true;
    for (std::size_t r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            if (c != static_cast<int>(r) && std::abs(direction[r][c]) > SNAP_TO_AXIS) {
                axis_aligned = false;
            }
        }
    }
    if (axis_aligned) {
        // Exactly what the axis-aligned readers always computed: spacing from the diagonal,
        // origin = first centre − spacing / 2 per axis.
        const Vec3d spacing{std::abs(steps[0].x), std::abs(steps[1].y), std::abs(steps[2].z)};
        volume.set_spacing(spacing);
        volume.set_origin({centre0.x - 0.5 * spacing.x, centre0.y - 0.5 * spacing.y,
                           centre0.z - 0.5 * spacing.z});
        volume.set_direction(IDENTITY_DIRECTION);
        return volume;
    }
    Vec3d spacing{};
    for (std::size_t r = 0; r < 3; ++r) {
        const double stated = placement.lengths[static_cast<std::size_t>(perm[r])];
        spacing[static_cast<int>(r)] =
            stated > 0.0 && std::isfinite(stated) ? stated : norm(steps[r]);
    }
    direction = orthonormalized(direction);
    volume.set_spacing(spacing);
    volume.set_origin(centre0 - direction[0] * (0.5 * spacing.x) -
                      direction[1] * (0.5 * spacing.y) - direction[2] * (0.5 * spacing.z));
    volume.set_direction(direction);
    return volume;
}

Volume resample_to_axis_aligned(const Volume& source, const AxisAlignedOptions& options) {
    if (source.empty()) {
        throw InvalidInput("resample_to_axis_aligned: the source volume is empty");
    }
    const Vec3d& requested = options.spacing;
    const bool default_spacing = requested.x == 0.0 && requested.y == 0.0 && requested.z == 0.0;
    if (!default_spacing && (!is_finite(requested) || !(requested.x > 0.0) ||
                             !(requested.y > 0.0) || !(requested.z > 0.0))) {
        throw InvalidInput(fmt::format(
            "resample_to_axis_aligned: spacing must be 0 (the smallest source spacing) or "
            "finite and > 0 on every axis, got {}",
            vec_text(requested)));
    }
    if (!std::isfinite(options.outside)) {
        throw InvalidInput(fmt::format(
            "resample_to_axis_aligned: the outside value must be finite, got {}", options.outside));
    }
    if (source.is_axis_aligned() && default_spacing) {
        return source;
    }
    const Vec3d& ss = source.spacing();
    const double smallest = std::min({ss.x, ss.y, ss.z});
    const Vec3d spacing = default_spacing ? Vec3d{smallest, smallest, smallest} : requested;

    const AABBd box = source.world_bounds();
    Dims dims{};
    Vec3d origin{};
    for (int a = 0; a < 3; ++a) {
        const double extent = box.hi[a] - box.lo[a];
        // A box that is a whole number of voxels (up to rounding) is not grown by one.
        const double count = std::max(1.0, std::ceil(extent / spacing[a] - 1e-9));
        if (!(count < 2147483647.0)) {
            throw InvalidInput(fmt::format(
                "resample_to_axis_aligned: {} voxels along axis {} (extent {} / spacing {}), "
                "expected at most 2^31 - 1",
                count, a, extent, spacing[a]));
        }
        dims[static_cast<std::size_t>(a)] = static_cast<std::int64_t>(count);
        origin[a] = box.lo[a] - 0.5 * (count * spacing[a] - extent);
    }
    Volume out = Volume::allocate(dims, source.type(), spacing, origin, options.max_bytes);
    switch (source.type()) {
        case VoxelType::u8:
            resample_into<std::uint8_t, 1>(source, out, options.outside);
            break;
        case VoxelType::i16:
            resample_into<std::int16_t, 1>(source, out, options.outside);
            break;
        case VoxelType::u16:
            resample_into<std::uint16_t, 1>(source, out, options.outside);
            break;
        case VoxelType::f32:
            resample_into<float, 1>(source, out, options.outside);
            break;
        case VoxelType::rgba8:
            resample_into<std::uint8_t, 4>(source, out, options.outside);
            break;
        case VoxelType::rgba32f:
            resample_into<float, 4>(source, out, options.outside);
            break;
    }
    return out;
}

}  // namespace pliant::volume
