// The two routes of rendering a deformed volume — exact (volume::Resampler into the source's
// grid, then RayCaster) and through the inverse map (render::MappedRayCaster) — against a
// reference neither of them computes: the exact resample into a grid 5 times finer on each axis,
// rendered by RayCaster with the same rays, step and opacity unit. Its second interpolation
// happens between voxels a fifth of the source's apart, so it converges to the deformed
// source sampled once per ray sample (checked: the 3× and 5× grids agree to ≥ 48 dB).
// RGBA (the phantom classified into rgba8) and scalar (the f32 phantom under its mri-brain
// transfer function) sources. Unshaded only: a shaded reference would take its gradients a fifth
// of a voxel apart, another quantity than the routes' one-voxel central differences.
#include <gtest/gtest.h>

#include <cstdint>
#include <iostream>
#include <tuple>

#include "pliant/render/camera.hpp"
#include "pliant/render/mapped_raycast.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "support/deformed_phantom.hpp"
#include "support/images.hpp"

namespace pliant::render {
namespace {

using test::Drive;
using test::psnr;

constexpr int SIZE = 256;

// The deformed source resampled exactly into a grid `factor` times finer over the same box, and
// rendered.
Image exact_render(const volume::Volume& source, const volume::TransferFunction* tf,
                   const test::Deformed& d, int factor, const RayCastOptions& options,
                   const Camera& camera) {
    const auto k = static_cast<double>(factor);
    const Vec3d spacing = source.spacing() / k;
    const Vec3d origin = source.origin() - source.spacing() * 0.5 + spacing * 0.5;
    const volume::Dims n = source.dims();
    volume::Volume target = volume::Volume::allocate({n[0] * factor, n[1] * factor, n[2] * factor},
                                                     source.type(), spacing, origin);
    const volume::Resampler resampler(source, d.grid.mesh.tets, d.grid.mesh.positions, {.tf = tf});
    resampler.resample(d.positions, target);
    Image image;
    RayCaster(target, tf, options).render(camera, image);
    return image;
}

class DeformedQuality : public ::testing::TestWithParam<std::tuple<Drive, bool>> {};

TEST_P(DeformedQuality, MapRouteIsWithin40DbOfTheConvergedResampleAndCloserThanTheExactRoute) {
    const auto [drive, rgba] = GetParam();
    static const volume::Volume rgba_source = test::rgba_phantom(64);
    static const volume::Volume scalar_source = volume::shepp_logan_3d({64, 64, 64});
    static const volume::TransferFunction scalar_tf = volume::preset("mri-brain", scalar_source);
    const volume::Volume& source = rgba ? rgba_source : scalar_source;
    const volume::TransferFunction* tf = rgba ? nullptr : &scalar_tf;
    const test::Deformed d = test::deform(source, tf, drive, 12);
    RayCastOptions options;
    options.step = 0.5 * source.spacing().x;  // the source's defaults, for every grid
    options.opacity_unit = source.spacing().x;
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, SIZE, SIZE);

    const Image reference = exact_render(source, tf, d, 5, options, camera);
    const Image finer = exact_render(source, tf, d, 3, options, camera);
    const Image exact = exact_render(source, tf, d, 1, options, camera);
    volume::InverseMap map;
    map.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions,
              {.node_voxels = d.grid.cell_voxels});
    MappedRayCaster mapped(source, tf, source, options);
    mapped.set_map(map);
    Image through_map;
    mapped.render(camera, through_map);

    const double converged = psnr(reference, finer);
    const double db_map = psnr(reference, through_map);
    const double db_exact = psnr(reference, exact);
    std::cout << (rgba ? "rgba8" : "f32") << ", driver " << static_cast<int>(drive)
              << ": 3x against 5x " << converged << " dB; against the 5x resample: map route "
              << db_map << " dB, exact route " << db_exact << " dB\n";
    EXPECT_GE(converged, 48.0);
    EXPECT_GE(db_map, 40.0);
    EXPECT_GE(db_exact, 33.0);
    EXPECT_GT(db_map, db_exact);
}

INSTANTIATE_TEST_SUITE_P(FourDrivers, DeformedQuality,
                         ::testing::Combine(::testing::Values(Drive::wave, Drive::twist,
                                                              Drive::bubble, Drive::drag),
                                            ::testing::Bool()));

}  // namespace
}  // namespace pliant::render
