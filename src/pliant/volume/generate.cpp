#include "pliant/volume/generate.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

struct Ellipsoid {
    double a, b, c;     // semi-axes
    double x0, y0, z0;  // centre
    double phi_deg;     // rotation about z
};

// Kak & Slaney (1988), p. 102: geometry shared by both variants.
constexpr Ellipsoid SHEPP_LOGAN[10] = {
    {0.6900, 0.920, 0.900, 0.000, 0.000, 0.000, 0},
    {0.6624, 0.874, 0.880, 0.000, 0.000, 0.000, 0},
    {0.4100, 0.160, 0.210, -0.220, 0.000, -0.250, 108},
    {0.3100, 0.110, 0.220, 0.220, 0.000, -0.250, 72},
    {0.2100, 0.250, 0.500, 0.000, 0.350, -0.250, 0},
    {0.0460, 0.046, 0.046, 0.000, 0.100, -0.250, 0},
    {0.0460, 0.023, 0.020, -0.080, -0.650, -0.250, 0},
    {0.0460, 0.023, 0.020, 0.060, -0.650, -0.250, 90},
    {0.0560, 0.040, 0.100, 0.060, -0.105, 0.625, 90},
    {0.0560, 0.056, 0.100, 0.000, 0.100, 0.625, 0},
};
constexpr double KAK_SLANEY_A[10] = {2.00, -0.98, -0.02, -0.02, 0.02,
                                     0.02, 0.01,  0.01,  0.02,  -0.02};
constexpr double YU_YE_WANG_A[10] = {1.0, -0.8, -0.2, -0.2, 0.2, 0.2, 0.1, 0.1, 0.2, -0.2};

bool inside(const Ellipsoid& e, const Vec3d& p) {
    const double phi = e.phi_deg * std::numbers::pi / 180.0;
    const double dx = p.x - e.x0;
    const double dy = p.y - e.y0;
    const double dz = p.z - e.z0;
    const double xr = std::cos(phi) * dx + std::sin(phi) * dy;
    const double yr = -std::sin(phi) * dx + std::cos(phi) * dy;
    const double q = (xr / e.a) * (xr / e.a) + (yr / e.b) * (yr / e.b) + (dz / e.c) * (dz / e.c);
    return q <= 1.0;
}

// Spacing 2/dims and origin −1: the box [−1, 1]³.
Volume unit_box_volume(const Dims& dims, VoxelType type) {
    for (int axis = 0; axis < 3; ++axis) {
        if (dims[static_cast<std::size_t>(axis)] < 1) {
            throw InvalidInput(
                fmt::format("volume: dims must be >= 1 on every axis, got {} x {} x {}", dims[0],
                            dims[1], dims[2]));
        }
    }
    const Vec3d spacing{2.0 / static_cast<double>(dims[0]), 2.0 / static_cast<double>(dims[1]),
                        2.0 / static_cast<double>(dims[2])};
    return Volume::allocate(dims, type, spacing, {-1.0, -1.0, -1.0});
}

// Writes straight RGBA (components in [0, 1]) to voxel `index` of an rgba8 or rgba32f volume.
void store_rgba(Volume& volume, std::int64_t index, const std::array<float, 4>& rgba) {
    const auto base = static_cast<std::size_t>(index) * 4;
    if (volume.type() == VoxelType::rgba8) {
        const auto v = volume.values<VoxelType::rgba8>();
        for (std::size_t c = 0; c < 4; ++c) {
            v[base + c] = static_cast<std::uint8_t>(std::lround(255.0f * rgba[c]));
        }
    } else {
        const auto v = volume.values<VoxelType::rgba32f>();
        for (std::size_t c = 0; c < 4; ++c) {
            v[base + c] = rgba[c];
        }
    }
}

// Fraction of the voxel's n³ sub-samples inside the sphere (n = 1: its centre).
double sphere_coverage(const Volume& volume, std::int64_t i, std::int64_t j, std::int64_t k,
                       const Vec3d& center, double radius, int n) {
    const Vec3d& h = volume.spacing();
    const Vec3d& o = volume.origin();
    const double r2 = radius * radius;
    int count = 0;
    for (int sk = 0; sk < n; ++sk) {
        const double z = o.z + (static_cast<double>(k) + (sk + 0.5) / n) * h.z - center.z;
        for (int sj = 0; sj < n; ++sj) {
            const double y = o.y + (static_cast<double>(j) + (sj + 0.5) / n) * h.y - center.y;
            for (int si = 0; si < n; ++si) {
                const double x = o.x + (static_cast<double>(i) + (si + 0.5) / n) * h.x - center.x;
                count += x * x + y * y + z * z <= r2 ? 1 : 0;
            }
        }
    }
    return static_cast<double>(count) / static_cast<double>(n * n * n);
}

Volume sphere_volume(const Dims& dims, double radius, const SphereOptions& options,
                     VoxelType type) {
    if (!std::isfinite(radius) || !(radius > 0.0)) {
        throw InvalidInput(
            fmt::format("uniform_sphere: radius must be finite and > 0, got {}", radius));
    }
    if (options.supersample < 1 || options.supersample > 16) {
        throw InvalidInput(fmt::format("uniform_sphere: supersample must be in [1, 16], got {}",
                                       options.supersample));
    }
    if (options.has_center && !is_finite(options.center)) {
        throw InvalidInput(fmt::format("uniform_sphere: center must be finite, got ({}, {}, {})",
                                       options.center.x, options.center.y, options.center.z));
    }
    return Volume::allocate(dims, type, options.spacing, options.origin);
}

Vec3d sphere_center(const Volume& volume, const SphereOptions& options) {
    if (options.has_center) {
        return options.center;
    }
    const AABBd box = volume.bounds();
    return (box.lo + box.hi) * 0.5;
}

// Arrow from the origin along `axis` (0, 1, 2): shaft radius 0.05 over [0.25, 0.6], cone over
// [0.6, 0.9] with base radius 0.13.
bool in_arrow(const Vec3d& p, int axis) {
    const double t = p[axis];
    const double u = p[(axis + 1) % 3];
    const double v = p[(axis + 2) % 3];
    const double r = std::sqrt(u * u + v * v);
    if (t >= 0.25 && t <= 0.6) {
        return r <= 0.05;
    }
    if (t > 0.6 && t <= 0.9) {
        return r <= 0.13 * (0.9 - t) / 0.3;
    }
    return false;
}

}  // namespace

namespace {

// Calls fill(i, j, k) for every voxel, in parallel over slices k (each voxel written by one
// call: the same result for any number of threads).
template <typename Fill>
void for_each_voxel(const Dims& dims, Fill&& fill) {
    parallel_for(
        dims[2],
        [&](std::int64_t k) {
            for (std::int64_t j = 0; j < dims[1]; ++j) {
                for (std::int64_t i = 0; i < dims[0]; ++i) {
                    fill(i, j, k);
                }
            }
        },
        1);
}

}  // namespace

float shepp_logan_value(const Vec3d& p, SheppLoganVariant variant) {
    const double* amplitude =
        variant == SheppLoganVariant::kak_slaney ? KAK_SLANEY_A : YU_YE_WANG_A;
    double sum = 0.0;
    for (std::size_t n = 0; n < 10; ++n) {
        if (inside(SHEPP_LOGAN[n], p)) {
            sum += amplitude[n];
        }
    }
    return static_cast<float>(sum);
}

Volume shepp_logan_3d(const Dims& dims, SheppLoganVariant variant) {
    Volume volume = unit_box_volume(dims, VoxelType::f32);
    const auto out = volume.values<VoxelType::f32>();
    for_each_voxel(dims, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        out[static_cast<std::size_t>(volume.index(i, j, k))] =
            shepp_logan_value(volume.voxel_center(i, j, k), variant);
    });
    return volume;
}

Volume uniform_sphere(const Dims& dims, double radius, float value, const SphereOptions& options) {
    if (!std::isfinite(value)) {
        throw InvalidInput(fmt::format("uniform_sphere: value must be finite, got {}", value));
    }
    Volume volume = sphere_volume(dims, radius, options, VoxelType::f32);
    const Vec3d center = sphere_center(volume, options);
    const auto out = volume.values<VoxelType::f32>();
    for_each_voxel(dims, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const double f = sphere_coverage(volume, i, j, k, center, radius, options.supersample);
        out[static_cast<std::size_t>(volume.index(i, j, k))] =
            static_cast<float>(f * static_cast<double>(value));
    });
    return volume;
}

Volume uniform_sphere(const Dims& dims, double radius, const std::array<float, 4>& rgba,
                      const SphereOptions& options) {
    for (std::size_t c = 0; c < 4; ++c) {
        if (!(rgba[c] >= 0.0f && rgba[c] <= 1.0f)) {
            throw InvalidInput(
                fmt::format("uniform_sphere: rgba[{}] must be in [0, 1], got {}", c, rgba[c]));
        }
    }
    Volume volume = sphere_volume(dims, radius, options, VoxelType::rgba32f);
    const Vec3d center = sphere_center(volume, options);
    for_each_voxel(dims, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const double f = sphere_coverage(volume, i, j, k, center, radius, options.supersample);
        if (f > 0.0) {
            store_rgba(
                volume, volume.index(i, j, k),
                {rgba[0], rgba[1], rgba[2], static_cast<float>(f * static_cast<double>(rgba[3]))});
        }
    });
    return volume;
}

Volume rgba_test_object(const Dims& dims, VoxelType type) {
    if (type != VoxelType::rgba8 && type != VoxelType::rgba32f) {
        throw InvalidInput(
            fmt::format("rgba_test_object: type must be rgba8 or rgba32f, got {}", name(type)));
    }
    Volume volume = unit_box_volume(dims, type);
    for_each_voxel(dims, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const Vec3d p = volume.voxel_center(i, j, k);
        std::array<float, 4> rgba{0.0f, 0.0f, 0.0f, 0.0f};
        if (p.x * p.x + p.y * p.y + p.z * p.z <= 0.25 * 0.25) {
            rgba = {0.5f, 0.5f, 0.5f, 0.1f};
        }
        if (in_arrow(p, 0)) {
            rgba = {1.0f, 0.0f, 0.0f, 0.6f};
        }
        if (in_arrow(p, 1)) {
            rgba = {0.0f, 1.0f, 0.0f, 0.6f};
        }
        if (in_arrow(p, 2)) {
            rgba = {0.0f, 0.0f, 1.0f, 0.6f};
        }
        if (std::abs(p.x + 0.6) <= 0.1 && std::abs(p.y + 0.6) <= 0.1 &&
            std::abs(p.z + 0.6) <= 0.1) {
            rgba = {1.0f, 1.0f, 0.0f, 0.6f};
        }
        store_rgba(volume, volume.index(i, j, k), rgba);
    });
    return volume;
}

}  // namespace pliant::volume
