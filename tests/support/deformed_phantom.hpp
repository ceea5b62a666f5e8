// A deformed RGBA phantom for the tests of rendering deformed volumes (render/mapped_raycast and
// the exact route through volume::Resampler): the 3D Shepp–Logan phantom classified by mri-brain
// into rgba8, as the radiance field exports, and a soft body over its visible voxels driven for a
// number of frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::test {

// The phantom classified by mri-brain into rgba8 (channels round(255 · c)), n³.
inline volume::Volume rgba_phantom(std::int64_t n) {
    const volume::Volume scalar = volume::shepp_logan_3d({n, n, n});
    const volume::Volume rgba = volume::apply(scalar, volume::preset("mri-brain", scalar));
    volume::Volume out = volume::Volume::allocate(rgba.dims(), volume::VoxelType::rgba8,
                                                  rgba.spacing(), rgba.origin());
    const auto* in = reinterpret_cast<const float*>(rgba.bytes().data());
    auto* dst = reinterpret_cast<std::uint8_t*>(out.bytes().data());
    for (std::int64_t i = 0; i < 4 * rgba.num_voxels(); ++i) {
        dst[i] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(in[i], 0.0f, 1.0f)));
    }
    return out;
}

enum class Drive { none, wave, twist, bubble, drag };

// A body over the volume's visible voxels (cells of 4 voxels, as pliant deform builds it) and
// its positions after `frames` frames at 24 fps, stiffness 0.8: wave amplitude 0.05, twist 90°,
// the default bubbles, or the vertex nearest the box's top corner dragged 0.15 box widths along
// −x with a radius of a quarter box width.
struct Deformed {
    pbd::TetGrid grid;
    std::vector<Vec3f> positions;
};

inline Deformed deform(const volume::Volume& source, const volume::TransferFunction* tf,
                       Drive drive, int frames) {
    Deformed d;
    d.grid = pbd::build_tet_grid(source, {.cell_voxels = 4, .tf = tf});
    pbd::SoftBody body(d.grid, {.stiffness = 0.8});
    switch (drive) {
        case Drive::none:
            break;
        case Drive::wave:
            body.add_driver(pbd::WaveDriver{.amplitude = 0.05});
            break;
        case Drive::twist:
            body.add_driver(pbd::TwistDriver{.angle = 90.0});
            break;
        case Drive::bubble:
            body.add_driver(pbd::BubbleDriver{});
            break;
        case Drive::drag: {
            const AABBd box = source.bounds();
            const std::span<const Vec3f> rest = body.positions();
            std::int32_t best = 0;
            double best_d = 1e300;
            for (std::size_t v = 0; v < rest.size(); ++v) {
                const double dd = squared_norm(vec3_cast<double>(rest[v]) - box.hi);
                if (dd < best_d) {
                    best_d = dd;
                    best = static_cast<std::int32_t>(v);
                }
            }
            const Vec3f target = rest[static_cast<std::size_t>(best)] -
                                 Vec3f{0.15f * static_cast<float>(box.extent().x), 0.0f, 0.0f};
            body.set_drag(best, target, 0.25f * static_cast<float>(box.extent().x));
            break;
        }
    }
    for (int f = 0; f < frames && drive != Drive::none; ++f) {
        body.step(1.0 / 24.0);
    }
    d.positions.assign(body.positions().begin(), body.positions().end());
    return d;
}

}  // namespace pliant::test
