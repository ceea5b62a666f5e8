#include "pliant/render/mapped_raycast.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/parallel_task.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/render/detail/mapped_raycast_avx2.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "support/deformed_phantom.hpp"
#include "support/images.hpp"

namespace pliant::render {
namespace {

using test::deform;
using test::Deformed;
using test::Drive;
using test::psnr;
using test::rgba_phantom;

struct Renders {
    Image exact, mapped;
    std::int64_t mapped_samples = 0;
};

Renders render_both(const volume::Volume& source, const volume::TransferFunction* tf,
                    const Deformed& d, const RayCastOptions& options, int size) {
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, size, size);
    volume::Volume target =
        volume::Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
    const volume::Resampler resampler(source, d.grid.mesh.tets, d.grid.mesh.positions,
                                      volume::ResampleOptions{.tf = tf});
    resampler.resample(d.positions, target);
    Renders r;
    RayCaster(target, tf, options).render(camera, r.exact);
    volume::InverseMap map;
    map.build(source, target, d.grid.mesh.tets, d.grid.mesh.positions, d.positions,
              {.node_voxels = d.grid.cell_voxels});
    MappedRayCaster mapped(source, tf, target, options);
    mapped.set_map(map);
    r.mapped_samples = mapped.render(camera, r.mapped).samples;
    return r;
}

// The RGBA source itself, rendered by RayCaster from azimuth `azimuth` (degrees), elevation 20°,
// at size × size: render_both()'s camera turned about +z.
Image render_source(const volume::Volume& source, const RayCastOptions& options, double azimuth,
                    int size) {
    Image image;
    RayCaster(source, nullptr, options)
        .render(orbit_camera(source.bounds(), azimuth, 20.0, 0.0, size, size), image);
    return image;
}

const volume::Volume& rgba64() {
    static const volume::Volume v = rgba_phantom(64);
    return v;
}

TEST(MappedRayCast, IdentityGivesTheSourceRender) {
    const volume::Volume& source = rgba64();
    const Deformed d = deform(source, nullptr, Drive::none, 0);
    for (const bool shading : {false, true}) {
        RayCastOptions options;
        options.shading = shading;
        const Renders r = render_both(source, nullptr, d, options, 96);
        const Image direct = render_source(source, options, 30.0, 96);
        const double db = psnr(direct, r.mapped);
        std::cout << "identity, shading " << shading << ": " << db << " dB against the source\n";
        EXPECT_GT(db, 50.0);
        EXPECT_GT(psnr(direct, r.exact), 50.0);
    }
}

// A translation by whole voxels is sampled exactly by both routes (the same image); by half a
// voxel, only the map route gives the analytic image (the source rendered with its origin moved):
// the resample's second interpolation blurs it.
TEST(MappedRayCast, TranslationMatchesTheAnalyticImage) {
    const volume::Volume& source = rgba64();
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 128, 128);
    for (const float shift : {1.0f, 0.5f}) {
        Deformed d = deform(source, nullptr, Drive::none, 0);
        const auto dx = static_cast<float>(shift * source.spacing().x);
        for (Vec3f& p : d.positions) {
            p.x += dx;
        }
        for (const bool shading : {false, true}) {
            RayCastOptions options;
            options.shading = shading;
            const Renders r = render_both(source, nullptr, d, options, 128);
            volume::Volume moved = source;
            moved.set_origin(source.origin() + Vec3d{dx, 0.0, 0.0});
            Image analytic;
            // The target's box: the moved volume's voxels beyond it are transparent.
            RayCaster(moved, nullptr, options).render(camera, analytic);
            const double db_map = psnr(analytic, r.mapped);
            const double db_exact = psnr(analytic, r.exact);
            std::cout << "translation " << shift << " voxel, shading " << shading << ": map "
                      << db_map << " dB, exact resample " << db_exact
                      << " dB against the analytic image\n";
            EXPECT_GT(db_map, shading ? 38.0 : 50.0);
            if (shift == 1.0f) {
                EXPECT_GT(db_exact, shading ? 38.0 : 50.0);
            } else {
                // The exact route interpolates twice; with opacity-weighted resampling its
                // colours stay those of the surface (a straight-colour resample gives 27 / 30 dB).
                EXPECT_GT(db_exact, shading ? 36.0 : 40.0);
                EXPECT_GT(db_map, db_exact + (shading ? 2.0 : 10.0));
            }
        }
    }
}

// A rigid rotation about the volume's centre seen by a camera at azimuth 30° is the source seen
// at azimuth 30° − θ (orbit_camera turns about +z): the analytic image. The map route is closer
// to it than the exact route. Shaded, the map route gives 42.4 dB: its normals are the source's
// turned by the map's Jacobian (chain rule); the bar of 40 dB fails a broken chain rule (measured
// with the AVX2 kernel broken on purpose: no Jacobian 28.2 dB, the Jacobian transposed 24.5 dB,
// one source axis's sign flipped 35.7 dB).
TEST(MappedRayCast, RotationIsCloserToTheAnalyticImageThanTheResample) {
    const volume::Volume& source = rgba64();
    const double theta = 30.0;
    Deformed d;
    d.grid = pbd::build_tet_grid(source, {.cell_voxels = 4});
    pbd::SoftBody body(d.grid, {});
    body.add_driver(pbd::RotateDriver{.axis = pbd::Axis::z,
                                      .angle = theta,
                                      .ramp_time = 0.0,
                                      .centre = source.bounds().center()});
    body.step(1.0 / 24.0);
    d.positions.assign(body.positions().begin(), body.positions().end());
    for (const bool shading : {false, true}) {
        RayCastOptions options;
        options.shading = shading;
        const Renders r = render_both(source, nullptr, d, options, 128);
        const Image analytic = render_source(source, options, 30.0 - theta, 128);
        const double db_map = psnr(analytic, r.mapped);
        const double db_exact = psnr(analytic, r.exact);
        std::cout << "rotation " << theta << "°, shading " << shading << ": map " << db_map
                  << " dB, exact resample " << db_exact << " dB against the analytic image\n";
        EXPECT_GT(db_map, db_exact);
        EXPECT_GT(db_map, shading ? 40.0 : 50.0);
    }
}

class MappedDrivers : public ::testing::TestWithParam<std::tuple<Drive, bool>> {};

// The exact pipeline interpolates twice (the resampler at the target's voxel centres, the ray
// caster between them), the map route once (in the source): they differ by the second
// interpolation's blur at sharp edges, 34–37.5 dB at this size (the half-voxel translation above
// isolates it: there the map route is the analytic image and the resample is not). The bar here
// is that difference; tests/render/deformed_quality_test.cpp measures both routes against a
// converged reference.
TEST_P(MappedDrivers, StayNearTheExactResampleRender) {
    const auto [drive, shading] = GetParam();
    const volume::Volume& source = rgba64();
    const Deformed d = deform(source, nullptr, drive, 12);
    RayCastOptions options;
    options.shading = shading;
    const Renders r = render_both(source, nullptr, d, options, 128);
    const double db = psnr(r.exact, r.mapped);
    std::cout << "driver " << static_cast<int>(drive) << ", shading " << shading << ": " << db
              << " dB against the exact resample's render\n";
    EXPECT_GE(db, 33.0);
    EXPECT_GT(r.mapped_samples, 0);
}

INSTANTIATE_TEST_SUITE_P(FourDrivers, MappedDrivers,
                         ::testing::Combine(::testing::Values(Drive::wave, Drive::twist,
                                                              Drive::bubble, Drive::drag),
                                            ::testing::Bool()));

TEST(MappedRayCast, ScalarSourceThroughItsTransferFunction) {
    const volume::Volume source = volume::shepp_logan_3d({48, 48, 48});
    const volume::TransferFunction tf = volume::preset("mri-brain", source);
    const Deformed d = deform(source, &tf, Drive::twist, 12);
    RayCastOptions options;
    options.shading = true;
    const Renders r = render_both(source, &tf, d, options, 96);
    const double db = psnr(r.exact, r.mapped);
    std::cout << "scalar twist, shaded: " << db << " dB\n";
    EXPECT_GE(db, 28.0);
}

// Sparse opaque voxels: most visible map cells have empty sub-cells, whose samples jump past
// them; the images must stay those without skipping, from every side, shaded or not, with the
// map changing between renders (the empty cubes of each render's octants). With the adaptive
// step's first level only: its second may sample differently after a jump
// (detail::mapped_march(); AdaptiveStepStaysNearTheFixedStep compares those).
TEST(MappedRayCast, SubCellJumpsChangeNothingOnASparseSource) {
    volume::Volume source = volume::Volume::allocate({32, 32, 32}, volume::VoxelType::rgba8,
                                                     {1.0, 1.0, 1.0}, {0.0, 0.0, 0.0});
    auto* v = reinterpret_cast<std::uint8_t*>(source.bytes().data());
    std::uint32_t seed = 12345;
    for (int i = 0; i < 40; ++i) {
        std::int64_t at[3];
        for (std::int64_t& c : at) {
            seed = seed * 1664525u + 1013904223u;
            c = 6 + static_cast<std::int64_t>((seed >> 8) % 20);
        }
        std::uint8_t* voxel = v + 4 * (at[0] + 32 * (at[1] + 32 * at[2]));
        voxel[0] = 200;
        voxel[1] = static_cast<std::uint8_t>(40 + 5 * i);
        voxel[2] = 90;
        voxel[3] = 255;
    }
    const Deformed twisted = deform(source, nullptr, Drive::twist, 6);
    const Deformed rest = deform(source, nullptr, Drive::none, 0);
    const volume::Volume target =
        volume::Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
    volume::InverseMap maps[2];
    maps[0].build(source, target, twisted.grid.mesh.tets, twisted.grid.mesh.positions,
                  twisted.positions);
    maps[1].build(source, target, rest.grid.mesh.tets, rest.grid.mesh.positions, rest.positions);
    const AABBd box = source.bounds();
    // Views from every side, axis views (rays with zero direction components) and an
    // orthographic one; the maps alternate, so a view whose octants' empty cubes were computed
    // for the other map would show it.
    const Camera cameras[] = {
        orbit_camera(box, 0.0, 35.0, 0.0, 80, 80),
        orbit_camera(box, 75.0, 35.0, 0.0, 80, 80),
        orbit_camera(box, 160.0, -40.0, 0.0, 80, 80),
        orbit_camera(box, 250.0, 35.0, 0.0, 80, 80),
        orbit_camera(box, 0.0, 0.0, 0.0, 80, 80),
        orbit_camera(box, 90.0, 0.0, 0.0, 80, 80),
        Camera::orthographic({16.0, -40.0, 16.0}, {16.0, 16.0, 16.0}, {0.0, 0.0, 1.0}, 40.0, 80,
                             80),
        Camera::orthographic({60.0, -30.0, 50.0}, {16.0, 16.0, 16.0}, {0.0, 0.0, 1.0}, 40.0, 80,
                             80),
    };
    for (const bool shading : {false, true}) {
        RayCastOptions options;
        options.shading = shading;
        MappedRayCaster skipping(source, nullptr, target, options);
        options.empty_space_skipping = false;
        MappedRayCaster every(source, nullptr, target, options);
        skipping.set_thin_levels(1);
        every.set_thin_levels(1);
        int view = 0;
        for (int round = 0; round < 2; ++round) {
            for (const Camera& camera : cameras) {
                const volume::InverseMap& map = maps[(view++ + round) % 2];
                skipping.set_map(map);
                every.set_map(map);
                Image a, b;
                const RayCastStats sa = skipping.render(camera, a);
                const RayCastStats sb = every.render(camera, b);
                EXPECT_EQ(a.pixels, b.pixels) << "view " << view << ", shading " << shading;
                EXPECT_LT(2 * sa.samples, sb.samples) << "view " << view;
                EXPECT_NE(a.pixels, Image(80, 80).pixels) << "view " << view;
            }
        }
    }
}

// detail::visible_samples() must keep every sample whose map cell (locate_map(), the clamp
// included) is visible: random rays (axis-parallel ones among them, origins inside and outside
// the grid, two steps) against random sets of visible cells (blobs inside the grid, blobs at
// its sides, none).
TEST(MappedRayCast, VisibleSamplesKeepEverySampleInAVisibleCell) {
    detail::MappedKernel m;
    const int n = 33;  // target voxels per axis; 4 voxels per map cell: 9 cells
    const int cells = 9;
    m.b = 4.0f;
    m.inv_b = 0.25f;
    for (int a = 0; a < 3; ++a) {
        m.cells[a] = cells;
        m.target.n[a] = n;
        m.target.g_max[a] = static_cast<float>(n - 1);
    }
    std::uint32_t seed = 777;
    const auto uniform = [&seed](float lo, float hi) {
        seed = seed * 1664525u + 1013904223u;
        return lo + (hi - lo) * static_cast<float>(seed >> 8) / static_cast<float>(1 << 24);
    };
    std::vector<std::uint8_t> visible(static_cast<std::size_t>(cells * cells * cells));
    std::int64_t kept = 0, skipped = 0;
    for (int trial = 0; trial < 1500; ++trial) {
        // A ball of cells (centre and radius random; trial % 3 == 1 lets it reach the grid's
        // sides; every 7th trial none).
        detail::VisibleCells v;
        const float lo = trial % 3 == 1 ? -2.0f : 1.0f;
        const float hi = trial % 3 == 1 ? 10.0f : 7.0f;
        const float centre[3] = {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)};
        const float radius = trial % 7 == 0 ? -1.0f : uniform(0.3f, 3.5f);
        for (int z = 0; z < cells; ++z) {
            for (int y = 0; y < cells; ++y) {
                for (int x = 0; x < cells; ++x) {
                    const float dx = static_cast<float>(x) + 0.5f - centre[0];
                    const float dy = static_cast<float>(y) + 0.5f - centre[1];
                    const float dz = static_cast<float>(z) + 0.5f - centre[2];
                    const bool in = dx * dx + dy * dy + dz * dz <= radius * radius;
                    visible[static_cast<std::size_t>(x + cells * (y + cells * z))] = in ? 1 : 0;
                    if (in) {
                        const std::int64_t c[3] = {x, y, z};
                        v.add(c);
                    }
                }
            }
        }
        detail::set_visible_cells(m, v);
        m.target.step = trial % 2 == 0 ? 0.5f : 0.37f;
        m.target.inv_step = 1.0f / m.target.step;
        detail::GridRay r{};
        for (int a = 0; a < 3; ++a) {
            r.go[a] = uniform(-20.0f, 52.0f);
            r.gd[a] = trial % 5 == a ? 0.0f : uniform(-1.0f, 1.0f);
            r.inv_gd[a] = r.gd[a] != 0.0f ? 1.0f / r.gd[a] : 0.0f;
        }
        r.t_near = uniform(0.0f, 10.0f);
        r.t_far = r.t_near + uniform(0.0f, 120.0f);
        const auto num_full = static_cast<std::int64_t>((r.t_far - r.t_near) * m.target.inv_step);
        std::int64_t begin = 0, end = 0;
        detail::visible_samples(m, r, num_full, begin, end);
        ASSERT_LE(0, begin);
        ASSERT_LE(begin, end);
        ASSERT_LE(end, num_full);
        for (std::int64_t s = 0; s < num_full; ++s) {
            const detail::MapCell c =
                detail::locate_map(m, detail::sample_position(m.target, r, s));
            if (visible[static_cast<std::size_t>(c.index)] != 0) {
                ASSERT_TRUE(s >= begin && s < end)
                    << "trial " << trial << ", sample " << s << " of " << num_full << " not in ["
                    << begin << ", " << end << ")";
            }
            (s >= begin && s < end ? kept : skipped) += 1;
        }
    }
    EXPECT_GT(skipped, kept);  // the span does skip samples
}

TEST(MappedRayCast, SkippingChangesNothingAndThreadsChangeNothing) {
    const volume::Volume& source = rgba64();
    const Deformed d = deform(source, nullptr, Drive::twist, 12);
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 96, 96);
    const volume::Volume target =
        volume::Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
    volume::InverseMap map;
    map.build(source, target, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
    for (const bool shading : {false, true}) {
        RayCastOptions options;
        options.shading = shading;
        MappedRayCaster skipping(source, nullptr, target, options);
        skipping.set_map(map);
        options.empty_space_skipping = false;
        MappedRayCaster every(source, nullptr, target, options);
        every.set_map(map);
        EXPECT_LT(skipping.num_visible_cells(), skipping.num_cells());
        // Threads, at the default levels of the adaptive step.
        Image a, c;
        set_num_threads(1);
        const RayCastStats sa = skipping.render(camera, a);
        set_num_threads(2);
        const RayCastStats sc = skipping.render(camera, c);
        EXPECT_EQ(a.pixels, c.pixels) << "1 and 2 threads differ";
        EXPECT_EQ(sa.samples, sc.samples);
        // Skipping, with the adaptive step's first level only (SubCellJumpsChangeNothing...).
        skipping.set_thin_levels(1);
        every.set_thin_levels(1);
        Image skipped, unskipped;
        const RayCastStats sd = skipping.render(camera, skipped);
        const RayCastStats se = every.render(camera, unskipped);
        set_num_threads(0);
        EXPECT_EQ(skipped.pixels, unskipped.pixels) << "skipping changed the image";
        EXPECT_LT(sd.samples, se.samples);
    }
}

// A scalar source whose transfer function has opacity only strictly between two of its values
// (the voxels themselves transparent, a sample visible only where interpolation crosses an
// edge between them): the cells' bits (their value ranges) keep every such sample — skipping
// changes no pixel — and skip some of the volume.
TEST(MappedRayCast, ScalarSkippingKeepsSamplesBetweenVoxelValues) {
    const volume::Volume source = volume::shepp_logan_3d({40, 36, 32});
    std::vector<float> values(source.values<volume::VoxelType::f32>().begin(),
                              source.values<volume::VoxelType::f32>().end());
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    ASSERT_GE(values.size(), 3U);
    const double v1 = values[values.size() - 2], v2 = values.back();
    const double mid = 0.5 * (v1 + v2), half = 0.1 * (v2 - v1);
    volume::TransferFunction tf;
    tf.name = "band";
    tf.color = {{v1, {1.0f, 0.8f, 0.6f}}};
    tf.opacity = {{mid - half, 0.0f}, {mid, 0.9f}, {mid + half, 0.0f}};
    tf.validate();
    const Deformed d = deform(source, nullptr, Drive::twist, 12);  // the whole box's grid
    volume::InverseMap map;
    map.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 80, 80);
    RayCastOptions options;
    MappedRayCaster skipping(source, &tf, source, options);
    options.empty_space_skipping = false;
    MappedRayCaster every(source, &tf, source, options);
    skipping.set_map(map);
    every.set_map(map);
    Image a, b;
    const RayCastStats sa = skipping.render(camera, a);
    const RayCastStats sb = every.render(camera, b);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_LT(sa.samples, sb.samples);
    EXPECT_LT(skipping.num_visible_cells(), skipping.num_cells());
    std::int64_t lit = 0;
    for (const std::uint8_t v : a.pixels) {
        lit += v > 0 ? 1 : 0;
    }
    EXPECT_GT(lit, 0);
}

// The AVX2 march (8 rays per vector) is the scalar kernel's bits: images and sample counts, for
// every kind the mapped caster renders: RGBA and scalar sources (through a transfer function),
// shaded or not, at the default step (Δs/u = 1/2) and another, clipped, without skipping,
// without early termination, and along an axis (rays with zero direction components jump by
// the cubes of several octants).
void expect_avx2_matches_scalar(const volume::Volume& source, const volume::TransferFunction* tf) {
    const Deformed d = deform(source, tf, Drive::twist, 12);
    volume::InverseMap map;
    map.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
    const AABBd box = source.bounds();
    const Vec3d centre = 0.5 * (box.lo + box.hi);
    const Camera orbit = orbit_camera(box, 30.0, 20.0, 0.0, 96, 96);
    const Camera axis =
        Camera::orthographic(centre + Vec3d{0.0, 0.0, 2.0 * (box.hi.z - box.lo.z)}, centre,
                             {0.0, 1.0, 0.0}, 1.2 * (box.hi.y - box.lo.y), 64, 64);
    struct Case {
        const char* name;
        double step = 0.0;
        bool shading = false;
        bool clip = false;
        bool skipping = true;
        double termination = 0.99;
        const Camera* camera = nullptr;
    };
    const double other_step = 0.7 * source.spacing().x;
    const Case cases[] = {
        {"unshaded", 0.0, false, false, true, 0.99, &orbit},
        {"shaded", 0.0, true, false, true, 0.99, &orbit},
        {"unshaded, other step", other_step, false, false, true, 0.99, &orbit},
        {"shaded, other step", other_step, true, false, true, 0.99, &orbit},
        {"clipped", 0.0, true, true, true, 0.99, &orbit},
        {"no skipping", 0.0, true, false, false, 0.99, &orbit},
        {"no early termination", 0.0, false, false, true, 1.0, &orbit},
        {"axis view", 0.0, true, false, true, 0.99, &axis},
    };
    for (const Case& c : cases) {
        RayCastOptions options;
        options.shading = c.shading;
        options.step = c.step;
        options.empty_space_skipping = c.skipping;
        options.early_termination = c.termination;
        if (c.clip) {
            options.clip = ClipPlane{centre, {1.0, 0.5, -0.25}};
        }
        MappedRayCaster caster(source, tf, source, options);
        caster.set_map(map);
        Image simd, scalar;
        const RayCastStats a = caster.render(*c.camera, simd);
        allow_avx2(false);
        const RayCastStats b = caster.render(*c.camera, scalar);
        allow_avx2(true);
        EXPECT_EQ(simd.pixels, scalar.pixels) << c.name;
        EXPECT_EQ(a.samples, b.samples) << c.name;
        EXPECT_GT(a.samples, 0) << c.name;
        std::int64_t lit = 0;  // pixels the source makes visible at all
        for (const std::uint8_t v : simd.pixels) {
            lit += v > 0 ? 1 : 0;
        }
        EXPECT_GT(lit, 0) << c.name;
    }
}

TEST(MappedRayCast, Avx2MarchMatchesTheScalarKernelOnRgba) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    expect_avx2_matches_scalar(rgba64(), nullptr);
}

TEST(MappedRayCast, Avx2MarchMatchesTheScalarKernelOnScalars) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    const volume::Volume source = volume::shepp_logan_3d({48, 40, 44});
    const volume::TransferFunction tf = volume::preset("mri-brain", source);
    expect_avx2_matches_scalar(source, &tf);
}

// The same source as rgba8 (read in its bytes, premultiplied in units of 1/255²) and as rgba32f
// holding c / 255 (the float copy's route) renders the same pixels up to rounding (a byte in a
// thousand one level apart at most), with the same sample counts,
// through a twist, on the AVX2 march and the scalar kernel, shaded or not (with the bytes
// packed beside the gradient): the phantom, and noise whose channels take every byte value.
TEST(MappedRayCast, Rgba8SourceGivesTheFloatSourceImage) {
    volume::Volume noise = volume::Volume::allocate({40, 36, 32}, volume::VoxelType::rgba8,
                                                    rgba64().spacing(), rgba64().origin());
    {
        std::uint32_t state = 12345;
        for (std::uint8_t& b : noise.values<volume::VoxelType::rgba8>()) {
            state = state * 1664525u + 1013904223u;
            b = static_cast<std::uint8_t>(state >> 24);
        }
    }
    for (const volume::Volume* bytes : {&rgba64(), static_cast<const volume::Volume*>(&noise)}) {
        volume::Volume floats = volume::Volume::allocate(bytes->dims(), volume::VoxelType::rgba32f,
                                                         bytes->spacing(), bytes->origin());
        const auto in = bytes->values<volume::VoxelType::rgba8>();
        const auto out = floats.values<volume::VoxelType::rgba32f>();
        for (std::size_t i = 0; i < in.size(); ++i) {
            out[i] = static_cast<float>(in[i]) / 255.0f;
        }
        const Deformed d = deform(*bytes, nullptr, Drive::twist, 12);
        volume::InverseMap map;
        map.build(*bytes, *bytes, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
        const Camera camera = orbit_camera(bytes->bounds(), 30.0, 20.0, 0.0, 80, 80);
        for (const bool shading : {false, true}) {
            for (const bool avx2 : {true, false}) {
                RayCastOptions options;
                options.shading = shading;
                MappedRayCaster from_bytes(*bytes, nullptr, *bytes, options);
                MappedRayCaster from_floats(floats, nullptr, floats, options);
                from_bytes.set_thin_alpha(0.0);  // a float source has no adaptive step
                from_bytes.set_map(map);
                from_floats.set_map(map);
                Image a, b;
                allow_avx2(avx2);
                const RayCastStats sa = from_bytes.render(camera, a);
                const RayCastStats sb = from_floats.render(camera, b);
                allow_avx2(true);
                // The two routes round differently (integer corners against c / 255 floats):
                // a pixel may land one level apart, rarely.
                ASSERT_EQ(a.pixels.size(), b.pixels.size());
                std::size_t differing = 0;
                for (std::size_t i = 0; i < a.pixels.size(); ++i) {
                    const int diff = std::abs(int{a.pixels[i]} - int{b.pixels[i]});
                    EXPECT_LE(diff, 1)
                        << "pixel byte " << i << ", shading " << shading << ", avx2 " << avx2;
                    differing += diff != 0 ? 1 : 0;
                }
                EXPECT_LE(differing, a.pixels.size() / 1000)
                    << "shading " << shading << ", avx2 " << avx2;
                EXPECT_EQ(sa.samples, sb.samples);
                EXPECT_GT(sa.samples, 0);
            }
        }
    }
}

// A radiance field's reconstruction in small: rgba8 haze (α 6–40 of 255, smooth) in a ball of
// radius 0.45 box widths, a denser shell (α 110–150) at radius 0.2–0.26 and a small opaque
// core, coloured along x and z; empty outside the ball.
volume::Volume haze(std::int64_t n) {
    volume::Volume v =
        volume::Volume::allocate({n, n, n}, volume::VoxelType::rgba8, {1.0, 1.0, 1.0}, {});
    const auto bytes = v.values<volume::VoxelType::rgba8>();
    for (std::int64_t z = 0; z < n; ++z) {
        for (std::int64_t y = 0; y < n; ++y) {
            for (std::int64_t x = 0; x < n; ++x) {
                const double p[3] = {(x + 0.5) / n - 0.5, (y + 0.5) / n - 0.5, (z + 0.5) / n - 0.5};
                const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                double a = 0.0;
                if (r < 0.08) {
                    a = 255.0;
                } else if (r > 0.2 && r < 0.26) {
                    a = 130.0 + 20.0 * std::sin(25.0 * p[0]);
                } else if (r < 0.45) {
                    a = 23.0 + 17.0 * std::sin(9.0 * p[0] + 5.0 * p[1]) * std::cos(7.0 * p[2]);
                }
                std::uint8_t* out = &bytes[static_cast<std::size_t>(4 * (x + n * (y + n * z)))];
                out[0] = static_cast<std::uint8_t>(std::lround(127.0 + 120.0 * p[0] / 0.5));
                out[1] = 180;
                out[2] = static_cast<std::uint8_t>(std::lround(127.0 + 120.0 * p[2] / 0.5));
                out[3] = static_cast<std::uint8_t>(std::lround(a));
            }
        }
    }
    return v;
}

// The adaptive step (thin voxels sampled once per 2^l steps, l ≤ thin_levels) against the
// fixed step: the image within 40 dB, fewer samples, on the haze above (most of its samples
// thin; the second level, shaded, fewer again) and on the phantom, shaded and not, through a
// twist; the AVX2 march is the scalar kernel's bits (discarded runs, jumps onto the coarsest
// runs); skipping changes nothing with the first level and stays at PSNR ≥ 65 dB with the second.
// A coarse sample given the fine step's opacity (half the haze's) fails the PSNR bar (29 dB).
TEST(MappedRayCast, AdaptiveStepStaysNearTheFixedStep) {
    const volume::Volume cloud = haze(48);
    for (const volume::Volume* source : {&cloud, &rgba64()}) {
        const Deformed d = deform(*source, nullptr, Drive::twist, 12);
        volume::InverseMap map;
        map.build(*source, *source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
        const Camera camera = orbit_camera(source->bounds(), 30.0, 20.0, 0.0, 96, 96);
        for (const bool shading : {false, true}) {
            RayCastOptions options;
            options.shading = shading;
            MappedRayCaster caster(*source, nullptr, *source, options);
            caster.set_map(map);
            options.empty_space_skipping = false;
            MappedRayCaster every(*source, nullptr, *source, options);
            every.set_map(map);
            EXPECT_DOUBLE_EQ(caster.thin_alpha(), detail::THIN_ALPHA_BYTES / 255.0);
            EXPECT_EQ(caster.thin_levels(), RayCastOptions{}.thin_levels);
            caster.set_thin_alpha(0.0);
            Image fixed;
            const RayCastStats c = caster.render(camera, fixed);
            caster.set_thin_alpha(detail::THIN_ALPHA_BYTES / 255.0);
            std::int64_t coarser = c.samples;
            for (int levels = 1; levels <= detail::MAX_THIN_LEVELS; ++levels) {
                const std::string where = fmt::format("shading {}, {} levels", shading, levels);
                caster.set_thin_levels(levels);
                every.set_thin_levels(levels);
                Image adaptive, scalar, unskipped;
                const RayCastStats a = caster.render(camera, adaptive);
                allow_avx2(false);
                const RayCastStats b = caster.render(camera, scalar);
                allow_avx2(true);
                every.render(camera, unskipped);
                EXPECT_EQ(adaptive.pixels, scalar.pixels) << where;
                EXPECT_EQ(a.samples, b.samples) << where;
                const double db = psnr(fixed, adaptive);
                const double db_skip = psnr(unskipped, adaptive);
                std::cout << (source == &cloud ? "haze" : "phantom") << ", " << where << ": " << db
                          << " dB against the fixed step, samples " << a.samples << " against "
                          << c.samples << "; " << db_skip << " dB against no skipping\n";
                EXPECT_GT(db, 40.0) << where;
                if (levels == 1) {
                    EXPECT_EQ(adaptive.pixels, unskipped.pixels)
                        << where << ": skipping changed it";
                    EXPECT_LT(a.samples, c.samples) << where;
                } else {
                    EXPECT_GT(db_skip, 65.0) << where;
                }
                if (source == &cloud) {
                    EXPECT_LT(a.samples, 3 * c.samples / 4) << "the haze is mostly thin";
                    if (levels == 2 && shading) {
                        EXPECT_LT(a.samples, coarser) << "the second level takes longer runs";
                    }
                }
                if (levels == 2 && !shading) {
                    EXPECT_EQ(a.samples, coarser) << "no second level without packed records";
                }
                coarser = a.samples;
            }
        }
    }
    MappedRayCaster caster(cloud, nullptr, cloud);
    EXPECT_THROW(caster.set_thin_alpha(-0.1), InvalidInput);
    EXPECT_THROW(caster.set_thin_alpha(1.5), InvalidInput);
    EXPECT_THROW(caster.set_thin_levels(-1), InvalidInput);
    EXPECT_THROW(caster.set_thin_levels(detail::MAX_THIN_LEVELS + 1), InvalidInput);
    RayCastOptions three_levels;
    three_levels.thin_levels = 3;
    EXPECT_THROW(MappedRayCaster(cloud, nullptr, cloud, three_levels), InvalidInput);
}

TEST(MappedRayCast, EarlyTerminationStillWorks) {
    const volume::Volume& source = rgba64();
    const Deformed d = deform(source, nullptr, Drive::wave, 6);
    RayCastOptions options;
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 64, 64);
    const volume::Volume target =
        volume::Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
    volume::InverseMap map;
    map.build(source, target, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
    MappedRayCaster early(source, nullptr, target, options);
    early.set_map(map);
    options.early_termination = 1.0;
    MappedRayCaster never(source, nullptr, target, options);
    never.set_map(map);
    Image a, b;
    const std::int64_t with = early.render(camera, a).samples;
    const std::int64_t without = never.render(camera, b).samples;
    EXPECT_LT(with, without);
    EXPECT_GT(psnr(a, b), 40.0);
}

// A map's state computed on another thread (compute_map() on a BackgroundTask, while the caster
// renders the previous map on this one) and installed gives set_map()'s image and sample counts,
// RGBA and scalar, shaded or not; the empty cubes asked for are computed with it, and the
// installation hands back the state it replaced.
TEST(MappedRayCast, StateComputedOnAnotherThreadGivesSetMapsImage) {
    const volume::Volume scalar = volume::shepp_logan_3d({48, 40, 44});
    const volume::TransferFunction tf = volume::preset("mri-brain", scalar);
    struct Source {
        const volume::Volume* volume;
        const volume::TransferFunction* tf;
    };
    for (const Source& src : {Source{&rgba64(), nullptr}, Source{&scalar, &tf}}) {
        const volume::Volume& source = *src.volume;
        const Deformed d = deform(source, src.tf, Drive::twist, 12);
        volume::InverseMap first, second;  // at rest, twisted
        first.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.grid.mesh.positions);
        second.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
        const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 64, 64);
        for (const bool shading : {false, true}) {
            RayCastOptions options;
            options.shading = shading;
            MappedRayCaster reference(source, src.tf, source, options);
            reference.set_map(second);
            Image expected;
            const RayCastStats want = reference.render(camera, expected);

            MappedRayCaster caster(source, src.tf, source, options);
            caster.set_map(first);
            MapOccupancy next;
            EXPECT_FALSE(next.has_map());
            const int octants = caster.octants_of(camera);
            EXPECT_NE(octants, 0);
            BackgroundTask task(1);
            task.start([&] { caster.compute_map(second, next, octants); });
            Image during;
            caster.render(camera, during);  // the first map, beside the computation
            task.wait();
            ASSERT_TRUE(caster.is_own(next));
            EXPECT_EQ(next.map(), &second);
            EXPECT_EQ(next.octants() & octants, octants);
            EXPECT_EQ(next.num_visible_cells(), reference.num_visible_cells());
            caster.install_map(next);
            EXPECT_EQ(next.map(), &first);  // the state it replaced
            Image got;
            const RayCastStats have = caster.render(camera, got);
            EXPECT_EQ(got.pixels, expected.pixels) << "shading " << shading;
            EXPECT_EQ(have.samples, want.samples) << "shading " << shading;
            EXPECT_NE(got.pixels, during.pixels);  // the maps differ
        }
    }
}

// A state is its caster's own: another caster (e.g. one rebuilt for a new transfer function)
// refuses it, as it refuses a state without a map; a refused map leaves the state as it was.
TEST(MappedRayCast, RefusesAnotherCastersState) {
    const volume::Volume& source = rgba64();
    const Deformed d = deform(source, nullptr, Drive::twist, 6);
    volume::InverseMap map;
    map.build(source, source, d.grid.mesh.tets, d.grid.mesh.positions, d.positions);
    MappedRayCaster old_caster(source, nullptr, source);
    MappedRayCaster new_caster(source, nullptr, source);
    MapOccupancy state;
    EXPECT_THROW(new_caster.install_map(state), InvalidInput);  // no map
    old_caster.compute_map(map, state);
    EXPECT_TRUE(old_caster.is_own(state));
    EXPECT_FALSE(new_caster.is_own(state));
    EXPECT_THROW(new_caster.install_map(state), InvalidInput);
    Image image;
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 8, 8);
    EXPECT_THROW(new_caster.render(camera, image), InvalidInput);  // nothing installed
    EXPECT_TRUE(state.has_map());                                  // left as it was
    state.clear();
    EXPECT_FALSE(old_caster.is_own(state));
    EXPECT_THROW(old_caster.install_map(state), InvalidInput);
    old_caster.compute_map(map, state);
    volume::InverseMap unbuilt;
    EXPECT_THROW(old_caster.compute_map(unbuilt, state), InvalidInput);
    old_caster.install_map(state);
    EXPECT_NO_THROW(old_caster.render(camera, image));
}

TEST(MappedRayCast, RefusesMipAnUnbuiltMapAndAForeignMap) {
    const volume::Volume& source = rgba64();
    RayCastOptions mip;
    mip.mode = RayCastMode::mip;
    EXPECT_THROW(MappedRayCaster(source, nullptr, source, mip), InvalidInput);
    MappedRayCaster caster(source, nullptr, source);
    Image image;
    const Camera camera = orbit_camera(source.bounds(), 30.0, 20.0, 0.0, 8, 8);
    EXPECT_THROW(caster.render(camera, image), InvalidInput);
    volume::InverseMap unbuilt;
    EXPECT_THROW(caster.set_map(unbuilt), InvalidInput);
    const volume::Volume small = rgba_phantom(16);
    const pbd::TetGrid g = pbd::build_tet_grid(small, {.cell_voxels = 4});
    volume::InverseMap foreign;
    foreign.build(small, small, g.mesh.tets, g.mesh.positions, g.mesh.positions);
    EXPECT_THROW(caster.set_map(foreign), InvalidInput);
    const volume::Volume scalar = volume::shepp_logan_3d({8, 8, 8});
    EXPECT_THROW(MappedRayCaster(scalar, nullptr, scalar), InvalidInput);  // no tf
}

}  // namespace
}  // namespace pliant::render
