#include "pliant/volume/resample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/geometry/exact_predicates.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/detail/resample_avx2.hpp"
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::volume {
namespace {

pbd::TetGrid full_grid(const Volume& v, int cell_voxels) {
    return pbd::build_tet_grid(v, {.cell_voxels = cell_voxels, .full_box = true});
}

Volume like(const Volume& v, VoxelType type) {
    return Volume::allocate(v.dims(), type, v.spacing(), v.origin());
}

std::vector<Vec3f> transformed(const std::vector<Vec3f>& rest, const Vec3d& center,
                               const double m[3][3], const Vec3d& shift = {0, 0, 0}) {
    std::vector<Vec3f> out(rest.size());
    for (std::size_t v = 0; v < rest.size(); ++v) {
        const Vec3d d = vec3_cast<double>(rest[v]) - center;
        const Vec3d p{m[0][0] * d.x + m[0][1] * d.y + m[0][2] * d.z,
                      m[1][0] * d.x + m[1][1] * d.y + m[1][2] * d.z,
                      m[2][0] * d.x + m[2][1] * d.y + m[2][2] * d.z};
        out[v] = vec3_cast<float>(p + center + shift);
    }
    return out;
}

Vec3d box_center(const Volume& v) {
    const AABBd b = v.bounds();
    return (b.lo + b.hi) * 0.5;
}

// Counts, per voxel of `grid`, the tets that claim its centre, by testing every voxel of every
// tet's box with the per-voxel form of the tie rule (the brute force the row spans must equal).
std::vector<int> brute_force_coverage(const pbd::TetGrid& g, const std::vector<Vec3f>& deformed,
                                      const Volume& grid, const Volume& source) {
    const detail::GridFrame tf = detail::frame_of(grid);
    const detail::GridFrame sf = detail::frame_of(source);
    std::vector<int> counts(static_cast<std::size_t>(grid.num_voxels()), 0);
    for (const geometry::Tet& tet : g.mesh.tets) {
        Vec3f p[4];
        Vec3f r[4];
        for (int v = 0; v < 4; ++v) {
            p[v] = deformed[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
            r[v] = g.mesh.positions[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
        }
        detail::TetRaster t{};
        if (!detail::setup_tet(p, tet.data(), r, tf, sf, t)) {
            continue;
        }
        for (std::int64_t k = t.lo[2]; k <= t.hi[2]; ++k) {
            for (std::int64_t j = t.lo[1]; j <= t.hi[1]; ++j) {
                for (std::int64_t i = t.lo[0]; i <= t.hi[0]; ++i) {
                    if (detail::inside(t, i, j, k)) {
                        ++counts[static_cast<std::size_t>(grid.index(i, j, k))];
                    }
                }
            }
        }
    }
    return counts;
}

// Per voxel of `grid`: the number of closed tets holding its centre (exact orient3d).
std::vector<int> closed_tet_counts(const std::vector<geometry::Tet>& tets,
                                   const std::vector<Vec3f>& positions, const Volume& grid) {
    std::vector<int> counts(static_cast<std::size_t>(grid.num_voxels()), 0);
    for (const geometry::Tet& t : tets) {
        Vec3d p[4];
        for (int v = 0; v < 4; ++v) {
            p[v] = vec3_cast<double>(
                positions[static_cast<std::size_t>(t[static_cast<std::size_t>(v)])]);
        }
        // Every voxel of the tet's box, grown by one voxel.
        std::int64_t lo[3];
        std::int64_t hi[3];
        for (int a = 0; a < 3; ++a) {
            const double mn = std::min(std::min(p[0][a], p[1][a]), std::min(p[2][a], p[3][a]));
            const double mx = std::max(std::max(p[0][a], p[1][a]), std::max(p[2][a], p[3][a]));
            const std::int64_t n = grid.dims()[static_cast<std::size_t>(a)];
            lo[a] = std::clamp<std::int64_t>(
                static_cast<std::int64_t>(std::floor((mn - grid.origin()[a]) / grid.spacing()[a])) -
                    1,
                0, n - 1);
            hi[a] = std::clamp<std::int64_t>(
                static_cast<std::int64_t>(std::floor((mx - grid.origin()[a]) / grid.spacing()[a])) +
                    1,
                0, n - 1);
        }
        for (std::int64_t k = lo[2]; k <= hi[2]; ++k) {
            for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
                for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
                    const Vec3d x = grid.voxel_center(i, j, k);
                    if (geometry::orient3d(x, p[1], p[2], p[3]) >= 0 &&
                        geometry::orient3d(p[0], x, p[2], p[3]) >= 0 &&
                        geometry::orient3d(p[0], p[1], x, p[3]) >= 0 &&
                        geometry::orient3d(p[0], p[1], p[2], x) >= 0) {
                        ++counts[static_cast<std::size_t>(grid.index(i, j, k))];
                    }
                }
            }
        }
    }
    return counts;
}

Volume filled(const Dims& dims, float value, const Vec3d& spacing, const Vec3d& origin) {
    Volume v = Volume::allocate(dims, VoxelType::f32, spacing, origin);
    for (float& x : v.values<VoxelType::f32>()) {
        x = value;
    }
    return v;
}

double psnr(std::span<const float> a, std::span<const float> b, std::span<const std::uint8_t> mask,
            double peak) {
    double sum = 0.0;
    std::int64_t n = 0;
    for (std::size_t v = 0; v < a.size(); ++v) {
        if (mask[v]) {
            const double d = static_cast<double>(a[v]) - static_cast<double>(b[v]);
            sum += d * d;
            ++n;
        }
    }
    const double mse = sum / static_cast<double>(std::max<std::int64_t>(n, 1));
    return mse == 0.0 ? std::numeric_limits<double>::infinity()
                      : 10.0 * std::log10(peak * peak / mse);
}

constexpr double IDENTITY[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

TEST(Resample, IdentityReproducesTheSourceAndWritesEveryVoxelOnce) {
    const Volume source = shepp_logan_3d({40, 36, 32});
    for (const int b : {1, 3, 4}) {
        const pbd::TetGrid g = full_grid(source, b);
        const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
        Volume target = like(source, VoxelType::f32);
        const ResampleStats stats = resampler.resample(g.mesh.positions, target);
        EXPECT_EQ(stats.num_tets, static_cast<std::int64_t>(g.mesh.tets.size()));
        EXPECT_EQ(stats.num_degenerate, 0);
        EXPECT_EQ(stats.num_inverted, 0);
        EXPECT_GT(stats.num_tets_skipped, 0);  // the corners of the box hold no phantom
        const auto want = source.values<VoxelType::f32>();
        const auto got = target.values<VoxelType::f32>();
        for (std::size_t v = 0; v < want.size(); ++v) {
            ASSERT_NEAR(got[v], want[v], 1e-6f) << "B = " << b << ", voxel " << v;
        }
        // Every voxel centre lies strictly inside the box: the kept tets claim each centre of
        // their region once, the skipped tets none.
        std::vector<std::uint8_t> counts(static_cast<std::size_t>(source.num_voxels()));
        resampler.count_coverage(g.mesh.positions, source, counts);
        std::int64_t covered = 0;
        for (const std::uint8_t c : counts) {
            ASSERT_LE(c, 1);
            covered += c;
        }
        EXPECT_EQ(covered, stats.num_voxels_written);
    }
}

TEST(Resample, RgbaIdentityIsExactAndConvertsToFloat) {
    const Volume source = rgba_test_object({24, 24, 24}, VoxelType::rgba8);
    const pbd::TetGrid g = pbd::build_tet_grid(source, {.cell_voxels = 4});
    ASSERT_GT(g.mesh.tets.size(), 0u);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    Volume same = like(source, VoxelType::rgba8);
    resampler.resample(g.mesh.positions, same);
    EXPECT_EQ(std::memcmp(same.bytes().data(), source.bytes().data(), source.size_bytes()), 0);
    Volume as_float = like(source, VoxelType::rgba32f);
    resampler.resample(g.mesh.positions, as_float);
    const auto src = source.values<VoxelType::rgba8>();
    const auto got = as_float.values<VoxelType::rgba32f>();
    for (std::size_t c = 0; c < src.size(); ++c) {
        ASSERT_NEAR(got[c], static_cast<float>(src[c]) / 255.0f, 1e-6f);
    }
}

TEST(Resample, CentresExactlyOnFacesEdgesAndVerticesAreWrittenExactlyOnce) {
    // Target centres on the source's voxel corners: with spacings and origin powers of two, every
    // lattice vertex, lattice edge and face diagonal of the grid passes exactly through target
    // voxel centres, and the plane values are exact.
    const Vec3d spacing{0.5, 1.0, 2.0};
    const Vec3d origin{-4.0, 2.0, -8.0};
    const Volume source = filled({13, 11, 9}, 1.0f, spacing, origin);
    const Volume grid = Volume::allocate(
        {14, 12, 10}, VoxelType::u8, spacing,
        {origin.x - 0.5 * spacing.x, origin.y - 0.5 * spacing.y, origin.z - 0.5 * spacing.z});
    for (const int b : {1, 2, 4}) {
        const pbd::TetGrid g = full_grid(source, b);
        const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
        ASSERT_EQ(resampler.kept_tets().size(), g.mesh.tets.size());
        for (const double shift : {0.0, 3.0}) {  // identity, and 3 whole voxels along +y
            const std::vector<Vec3f> deformed =
                transformed(g.mesh.positions, {0, 0, 0}, IDENTITY, {0.0, shift * spacing.y, 0.0});
            std::vector<std::uint8_t> counts(static_cast<std::size_t>(grid.num_voxels()));
            resampler.count_coverage(deformed, grid, counts);
            const std::vector<int> brute = brute_force_coverage(g, deformed, grid, source);
            const AABBd box{{origin.x, origin.y + shift * spacing.y, origin.z},
                            {origin.x + 13 * spacing.x, origin.y + (11 + shift) * spacing.y,
                             origin.z + 9 * spacing.z}};
            std::int64_t on_faces = 0;
            for (std::int64_t k = 0; k < 10; ++k) {
                for (std::int64_t j = 0; j < 12; ++j) {
                    for (std::int64_t i = 0; i < 14; ++i) {
                        const std::size_t v = static_cast<std::size_t>(grid.index(i, j, k));
                        ASSERT_EQ(counts[v], brute[v]) << i << " " << j << " " << k;
                        const Vec3d x = grid.voxel_center(i, j, k);
                        const bool strictly_inside = x.x > box.lo.x && x.x < box.hi.x &&
                                                     x.y > box.lo.y && x.y < box.hi.y &&
                                                     x.z > box.lo.z && x.z < box.hi.z;
                        if (strictly_inside) {
                            ASSERT_EQ(counts[v], 1) << "B " << b << " voxel " << i << " " << j
                                                    << " " << k << " shift " << shift;
                        } else {
                            ASSERT_LE(counts[v], 1);
                        }
                    }
                }
            }
            // The test exercises ties: many centres lie on the boundary of two or more closed
            // tets (exact orientation predicates), and each of them is still written once.
            const std::vector<int> closed = closed_tet_counts(g.mesh.tets, deformed, grid);
            for (std::size_t v = 0; v < closed.size(); ++v) {
                on_faces += closed[v] >= 2 ? 1 : 0;
                ASSERT_TRUE(closed[v] >= 1 || counts[v] == 0) << v;
            }
            EXPECT_GT(on_faces, 0);
        }
    }
}

TEST(Resample, RowSpansEqualTheBruteForceOnRandomDeformations) {
    const Volume source = filled({20, 18, 16}, 1.0f, {1.0, 1.0, 1.0}, {0, 0, 0});
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-1.5f, 1.5f);  // folds: some tets invert
    std::vector<Vec3f> deformed = g.mesh.positions;
    for (Vec3f& p : deformed) {
        p += Vec3f{jitter(rng), jitter(rng), jitter(rng)};
    }
    std::vector<std::uint8_t> counts(static_cast<std::size_t>(source.num_voxels()));
    resampler.count_coverage(deformed, source, counts);
    const std::vector<int> brute = brute_force_coverage(g, deformed, source, source);
    for (std::size_t v = 0; v < counts.size(); ++v) {
        ASSERT_EQ(counts[v], brute[v]) << v;
    }
    Volume target = like(source, VoxelType::f32);
    const ResampleStats stats = resampler.resample(deformed, target);
    EXPECT_GT(stats.num_inverted, 0);
}

TEST(Resample, RigidRotationReproducesTheRotatedVolume) {
    const Volume source = shepp_logan_3d({64, 64, 64});
    const pbd::TetGrid g = full_grid(source, 4);
    const double angle = 30.0 * std::numbers::pi / 180.0;
    const double co = std::cos(angle);
    const double si = std::sin(angle);
    const double rot[3][3] = {{co, -si, 0}, {si, co, 0}, {0, 0, 1}};
    const Vec3d c = box_center(source);
    const std::vector<Vec3f> deformed = transformed(g.mesh.positions, c, rot);
    Volume target = like(source, VoxelType::f32);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    resampler.resample(deformed, target);

    // Reference: the source sampled trilinearly at R⁻¹(x − c) + c, on the voxels the rotated
    // mesh covers (its union is the rotated box; elsewhere the output is 0).
    std::vector<std::uint8_t> covered(static_cast<std::size_t>(source.num_voxels()));
    resampler.count_coverage(deformed, source, covered);
    std::vector<float> reference(covered.size(), 0.0f);
    const auto values = source.values<VoxelType::f32>();
    const auto got = target.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < 64; ++k) {
        for (std::int64_t j = 0; j < 64; ++j) {
            for (std::int64_t i = 0; i < 64; ++i) {
                const std::size_t v = static_cast<std::size_t>(source.index(i, j, k));
                const Vec3d d = source.voxel_center(i, j, k) - c;
                const Vec3d x{co * d.x + si * d.y + c.x, -si * d.x + co * d.y + c.y, d.z + c.z};
                const Vec3d gcoord{(x.x - source.origin().x) / source.spacing().x - 0.5,
                                   (x.y - source.origin().y) / source.spacing().y - 0.5,
                                   (x.z - source.origin().z) / source.spacing().z - 0.5};
                detail::sample_trilinear<float, 1>(values.data(), source.dims().data(), gcoord.x,
                                                   gcoord.y, gcoord.z, &reference[v]);
                if (!covered[v]) {
                    ASSERT_EQ(got[v], 0.0f);
                }
            }
        }
    }
    const double db = psnr(got, reference, covered, 2.0);
    EXPECT_GE(db, 35.0);
    RecordProperty("psnr_vs_trilinear_reference_db", std::to_string(db));
    std::cout << "rotation 30 deg: PSNR vs trilinear reference " << db << " dB\n";
}

TEST(Resample, RigidRotationOfASmoothFieldMatchesTheAnalyticRotation) {
    // f(x) = sin(3x)·cos(2y)·cos(z) + 1 over [−1, 1]³, 64³ voxels: the resampled rotation should
    // be f(R⁻¹x) up to trilinear interpolation error (O(h²)).
    constexpr std::int64_t N = 64;
    Volume source = Volume::allocate({N, N, N}, VoxelType::f32, {2.0 / N, 2.0 / N, 2.0 / N},
                                     {-1.0, -1.0, -1.0});
    auto field = [](const Vec3d& p) {
        return static_cast<float>(std::sin(3 * p.x) * std::cos(2 * p.y) * std::cos(p.z) + 1.0);
    };
    auto values = source.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < N; ++k) {
        for (std::int64_t j = 0; j < N; ++j) {
            for (std::int64_t i = 0; i < N; ++i) {
                values[static_cast<std::size_t>(source.index(i, j, k))] =
                    field(source.voxel_center(i, j, k));
            }
        }
    }
    const pbd::TetGrid g = full_grid(source, 4);
    const double angle = 30.0 * std::numbers::pi / 180.0;
    const double co = std::cos(angle);
    const double si = std::sin(angle);
    const double rot[3][3] = {{co, -si, 0}, {si, co, 0}, {0, 0, 1}};
    const std::vector<Vec3f> deformed = transformed(g.mesh.positions, {0, 0, 0}, rot);
    Volume target = like(source, VoxelType::f32);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    resampler.resample(deformed, target);
    // Compare where the rotated point is at least one voxel inside the box (no clamping).
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(source.num_voxels()), 0);
    std::vector<float> analytic(mask.size(), 0.0f);
    for (std::int64_t k = 0; k < N; ++k) {
        for (std::int64_t j = 0; j < N; ++j) {
            for (std::int64_t i = 0; i < N; ++i) {
                const std::size_t v = static_cast<std::size_t>(source.index(i, j, k));
                const Vec3d x = source.voxel_center(i, j, k);
                const Vec3d p{co * x.x + si * x.y, -si * x.x + co * x.y, x.z};
                analytic[v] = field(p);
                const double lim = 1.0 - 2.0 / N;
                mask[v] = std::abs(p.x) < lim && std::abs(p.y) < lim && std::abs(p.z) < lim;
            }
        }
    }
    const double db = psnr(target.values<VoxelType::f32>(), analytic, mask, 2.0);
    std::cout << "rotation 30 deg, smooth field: PSNR vs analytic " << db << " dB\n";
    EXPECT_GE(db, 35.0);
}

TEST(Resample, WholeVoxelTranslationShiftsTheVolume) {
    const Volume source = rgba_test_object({32, 32, 32}, VoxelType::rgba8);
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    const Vec3d s = source.spacing();
    const std::vector<Vec3f> deformed =
        transformed(g.mesh.positions, {0, 0, 0}, IDENTITY, {2 * s.x, -1 * s.y, 3 * s.z});
    Volume target = like(source, VoxelType::rgba8);
    resampler.resample(deformed, target);
    const auto src = source.values<VoxelType::rgba8>();
    const auto got = target.values<VoxelType::rgba8>();
    for (std::int64_t k = 0; k < 32; ++k) {
        for (std::int64_t j = 0; j < 32; ++j) {
            for (std::int64_t i = 0; i < 32; ++i) {
                const std::int64_t si = i - 2;
                const std::int64_t sj = j + 1;
                const std::int64_t sk = k - 3;
                const bool inside = si >= 0 && sj < 32 && sk >= 0;
                for (int c = 0; c < 4; ++c) {
                    const std::uint8_t want =
                        inside ? src[static_cast<std::size_t>(4 * source.index(si, sj, sk) + c)]
                               : 0;
                    ASSERT_EQ(got[static_cast<std::size_t>(4 * target.index(i, j, k) + c)], want)
                        << i << " " << j << " " << k << " channel " << c;
                }
            }
        }
    }
}

TEST(Resample, OneAndManyThreadsAreBitwiseIdenticalEvenWithFolds) {
    const Volume source = rgba_test_object({48, 40, 36}, VoxelType::rgba32f);
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> jitter(-0.1f, 0.1f);  // ±2.4 voxels: folds
    const double rot[3][3] = {{0.8, -0.6, 0}, {0.6, 0.8, 0}, {0, 0, 1}};
    std::vector<Vec3f> deformed = transformed(g.mesh.positions, box_center(source), rot);
    for (Vec3f& p : deformed) {
        p += Vec3f{jitter(rng), jitter(rng), jitter(rng)};
    }
    const int saved = num_threads();
    set_num_threads(1);
    Volume one = like(source, VoxelType::rgba32f);
    const ResampleStats s1 = resampler.resample(deformed, one);
    for (const int threads : {2, 4}) {
        set_num_threads(threads);
        Volume many = like(source, VoxelType::rgba32f);
        const ResampleStats sn = resampler.resample(deformed, many);
        EXPECT_EQ(std::memcmp(one.bytes().data(), many.bytes().data(), one.size_bytes()), 0)
            << threads << " threads";
        EXPECT_EQ(s1.num_voxels_written, sn.num_voxels_written);
        EXPECT_EQ(s1.num_inverted, sn.num_inverted);
    }
    set_num_threads(saved);
    EXPECT_GT(s1.num_inverted, 0);
}

TEST(Resample, Avx2AndScalarKernelsAreBitwiseIdentical) {
    if (!pliant::has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    // f32 → f32 takes the AVX2 sampler; tets up to 8 voxels wide the AVX2 rows.
    const Volume source = shepp_logan_3d({48, 44, 40});
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    const Vec3d c = box_center(source);
    const AABBd box = source.bounds();
    const double a = 30.0 * std::numbers::pi / 180.0;
    const double rot[3][3] = {
        {std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}};
    const double stretch[3][3] = {{2.5, 0, 0}, {0, 0.7, 0}, {0, 0, 1.2}};  // tets > 8 wide
    std::vector<std::vector<Vec3f>> deformations = {
        g.mesh.positions,                           // ties on faces, edges, vertices
        transformed(g.mesh.positions, c, rot),      // faces parallel to the rows
        transformed(g.mesh.positions, c, stretch),  // wide tets: both kernels in one run
        transformed(g.mesh.positions, c, rot, (box.hi - box.lo) * 0.15)};  // partly outside
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> jitter(-2.0f, 2.0f);  // folds, inverted tets
    deformations.push_back(transformed(g.mesh.positions, c, rot));
    for (Vec3f& p : deformations.back()) {
        p += Vec3f{jitter(rng), jitter(rng), jitter(rng)};
    }
    for (std::size_t d = 0; d < deformations.size(); ++d) {
        Volume fast = like(source, VoxelType::f32);
        Volume plain = like(source, VoxelType::f32);
        std::vector<std::uint8_t> fast_counts(static_cast<std::size_t>(source.num_voxels()));
        std::vector<std::uint8_t> plain_counts(fast_counts.size());
        const ResampleStats s_fast = resampler.resample(deformations[d], fast);
        resampler.count_coverage(deformations[d], source, fast_counts);
        pliant::allow_avx2(false);
        const ResampleStats s_plain = resampler.resample(deformations[d], plain);
        resampler.count_coverage(deformations[d], source, plain_counts);
        pliant::allow_avx2(true);
        EXPECT_GT(s_fast.num_voxels_written, 0) << d;
        EXPECT_EQ(s_fast.num_voxels_written, s_plain.num_voxels_written) << d;
        EXPECT_EQ(s_fast.num_inverted, s_plain.num_inverted) << d;
        EXPECT_EQ(std::memcmp(fast.bytes().data(), plain.bytes().data(), fast.size_bytes()), 0)
            << "deformation " << d;
        EXPECT_EQ(fast_counts, plain_counts) << "deformation " << d;
    }
}

TEST(Resample, Avx2Rgba8SamplerEqualsTheScalarSamplerBitwise) {
    if (!pliant::has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    // rgba8 → rgba8 and rgba8 → rgba32f take the AVX2 rgba8 sampler: random bytes in every
    // channel (every rounding case), odd dims, interior and boundary batches, folds.
    Volume source =
        Volume::allocate({37, 41, 29}, VoxelType::rgba8, {0.5, 0.75, 1.0}, {-3.0, 2.0, 1.0});
    std::mt19937 bytes_rng(5);
    std::uniform_int_distribution<int> byte(0, 255);
    for (std::byte& b : source.bytes()) {
        b = static_cast<std::byte>(byte(bytes_rng));
    }
    const pbd::TetGrid g = full_grid(source, 3);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    const Vec3d c = box_center(source);
    const AABBd box = source.bounds();
    const double a = 25.0 * std::numbers::pi / 180.0;
    const double rot[3][3] = {
        {std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}};
    std::vector<std::vector<Vec3f>> deformations = {
        g.mesh.positions, transformed(g.mesh.positions, c, rot),
        transformed(g.mesh.positions, c, rot, (box.hi - box.lo) * 0.2)};  // partly outside
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> jitter(-0.8f, 0.8f);
    deformations.push_back(transformed(g.mesh.positions, c, rot));
    for (Vec3f& p : deformations.back()) {
        p += Vec3f{jitter(rng), jitter(rng), jitter(rng)};
    }
    for (const VoxelType type : {VoxelType::rgba8, VoxelType::rgba32f}) {
        for (std::size_t d = 0; d < deformations.size(); ++d) {
            Volume fast = like(source, type);
            Volume plain = like(source, type);
            const ResampleStats s_fast = resampler.resample(deformations[d], fast);
            pliant::allow_avx2(false);
            const ResampleStats s_plain = resampler.resample(deformations[d], plain);
            pliant::allow_avx2(true);
            EXPECT_GT(s_fast.num_voxels_written, 1000) << d;
            EXPECT_EQ(s_fast.num_voxels_written, s_plain.num_voxels_written) << d;
            EXPECT_EQ(std::memcmp(fast.bytes().data(), plain.bytes().data(), fast.size_bytes()), 0)
                << "deformation " << d << ", target " << static_cast<int>(type);
        }
    }
}

TEST(Resample, Avx2SetupOfFourTetsEqualsTheScalarSetup) {
    if (!pliant::has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    const Volume target =
        Volume::allocate({40, 36, 32}, VoxelType::f32, {0.5, 0.25, 1.0}, {-3.0, 1.0, 2.0});
    const Volume source =
        Volume::allocate({20, 24, 28}, VoxelType::f32, {1.0, 0.5, 0.75}, {-2.0, 0.5, 1.5});
    const detail::GridFrame tf = detail::frame_of(target);
    const detail::GridFrame sf = detail::frame_of(source);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> coord(-4.0f, 30.0f);
    std::uniform_int_distribution<int> kind(0, 5);
    int num_ok = 0;
    int num_degenerate = 0;
    int num_flat_layers = 0;
    std::uniform_int_distribution<int> slot(0, 7);
    for (int round = 0; round < 2000; ++round) {
        // Lane l uses vertices 8l … 8l + 7 (random, possibly repeated, in random order).
        std::vector<Vec3f> deformed(32);
        std::vector<Vec3f> rest_positions(32);
        for (std::size_t v = 0; v < deformed.size(); ++v) {
            deformed[v] = {coord(rng), coord(rng), coord(rng)};
            rest_positions[v] = {coord(rng), coord(rng), coord(rng)};
        }
        Vec3f p[4][4];
        Vec3f r[4][4];
        std::int32_t ids[4][4];
        detail::RestInfo rest[4];
        for (int l = 0; l < 4; ++l) {
            const int k = kind(rng);
            std::array<std::int32_t, 8> order{0, 1, 2, 3, 4, 5, 6, 7};
            std::shuffle(order.begin(), order.end(), rng);
            for (int v = 0; v < 4; ++v) {
                ids[l][v] = 8 * l + order[static_cast<std::size_t>(v)];
            }
            if (k == 4) {  // a repeated vertex index (degenerate)
                ids[l][3] = ids[l][slot(rng) % 3];
            }
            auto at = [&](int v) -> Vec3f& {
                return deformed[static_cast<std::size_t>(ids[l][v])];
            };
            if (k == 0) {  // a face in a layer plane (a = b = 0), through layer centres
                const float z = static_cast<float>(target.origin().z) + std::round(at(0).z) + 0.5f;
                at(0).z = z;
                at(1).z = z;
                at(2).z = z;
            } else if (k == 1) {  // a face parallel to the rows (a = 0)
                at(1).x = at(0).x;
                at(2).x = at(0).x;
            } else if (k == 2) {  // degenerate: coplanar, or two vertices equal
                at(3) = at((round & 1) == 0 ? 2 : 0);
            } else if (k == 3) {  // vertices on the lattice of the target's voxel corners
                for (int v = 0; v < 4; ++v) {
                    at(v) = {std::round(at(v).x), std::round(at(v).y), std::round(at(v).z)};
                }
            }
        }
        for (int l = 0; l < 4; ++l) {
            for (int v = 0; v < 4; ++v) {
                p[l][v] = deformed[static_cast<std::size_t>(ids[l][v])];
                r[l][v] = rest_positions[static_cast<std::size_t>(ids[l][v])];
            }
            rest[l] = detail::rest_info(r[l], sf);
        }
        detail::TetRaster fast[4]{};
        const int ok = detail::setup_tets_avx2(deformed.data(), rest_positions.data(), ids, rest,
                                               tf, sf, fast);
        for (int l = 0; l < 4; ++l) {
            detail::TetRaster plain{};
            const bool is_ok = detail::setup_tet(p[l], ids[l], r[l], rest[l], tf, sf, plain);
            ASSERT_EQ(((ok >> l) & 1) != 0, is_ok) << "round " << round << " lane " << l;
            for (int a = 0; a < 3; ++a) {
                ASSERT_EQ(fast[l].lo[a], plain.lo[a]);
                ASSERT_EQ(fast[l].hi[a], plain.hi[a]);
            }
            if (!is_ok) {
                ++num_degenerate;
                continue;
            }
            ++num_ok;
            num_flat_layers += plain.k_hi - plain.k_lo != plain.hi[2] - plain.lo[2] ? 1 : 0;
            ASSERT_EQ(std::memcmp(&fast[l], &plain, sizeof(plain)), 0)
                << "round " << round << " lane " << l;
        }
    }
    EXPECT_GT(num_ok, 5000);
    EXPECT_GT(num_degenerate, 100);
    EXPECT_GT(num_flat_layers, 10);
}

TEST(Resample, EmptySourceGivesZerosAndSkipsEveryTet) {
    const Volume source = Volume::allocate({16, 16, 16}, VoxelType::f32);
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    EXPECT_TRUE(resampler.kept_tets().empty());
    Volume target = filled({16, 16, 16}, 7.0f, {1, 1, 1}, {0, 0, 0});
    const ResampleStats stats = resampler.resample(g.mesh.positions, target);
    EXPECT_EQ(stats.num_tets_skipped, stats.num_tets);
    EXPECT_EQ(stats.num_voxels_written, 0);
    for (const float x : target.values<VoxelType::f32>()) {
        ASSERT_EQ(x, 0.0f);
    }
}

TEST(Resample, SkippingChangesNothing) {
    // A small sphere: most tets are skipped; resampling every tet (a visibility that keeps all,
    // through a transfer function opaque everywhere) gives the same volume.
    const Volume source = uniform_sphere({32, 32, 32}, 5.0, 1.0f, {.supersample = 2});
    const pbd::TetGrid g = full_grid(source, 4);
    const double rot[3][3] = {{0.6, -0.8, 0}, {0.8, 0.6, 0}, {0, 0, 1}};
    const std::vector<Vec3f> deformed = transformed(g.mesh.positions, box_center(source), rot);
    TransferFunction opaque{.name = "opaque",
                            .color = {{.value = 0.0, .rgb = {1, 1, 1}}},
                            .opacity = {{.value = 0.0, .alpha = 1.0f}}};
    const Resampler skipping(source, g.mesh.tets, g.mesh.positions);
    const Resampler all(source, g.mesh.tets, g.mesh.positions, {.tf = &opaque});
    EXPECT_EQ(all.kept_tets().size(), g.mesh.tets.size());
    EXPECT_LT(skipping.kept_tets().size(), g.mesh.tets.size() / 2);
    Volume a = like(source, VoxelType::f32);
    Volume b = like(source, VoxelType::f32);
    skipping.resample(deformed, a);
    all.resample(deformed, b);
    EXPECT_EQ(std::memcmp(a.bytes().data(), b.bytes().data(), a.size_bytes()), 0);
}

TEST(Resample, MirroredMeshIsInvertedAndRasterizedUnlessSkipped) {
    const Volume source = shepp_logan_3d({24, 24, 24});
    const pbd::TetGrid g = full_grid(source, 4);
    const double mirror[3][3] = {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const std::vector<Vec3f> deformed = transformed(g.mesh.positions, box_center(source), mirror);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    Volume target = like(source, VoxelType::f32);
    const ResampleStats stats = resampler.resample(deformed, target);
    EXPECT_EQ(stats.num_inverted, static_cast<std::int64_t>(resampler.kept_tets().size()));
    const auto src = source.values<VoxelType::f32>();
    const auto got = target.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < 24; ++k) {
        for (std::int64_t j = 0; j < 24; ++j) {
            for (std::int64_t i = 0; i < 24; ++i) {
                ASSERT_NEAR(got[static_cast<std::size_t>(source.index(i, j, k))],
                            src[static_cast<std::size_t>(source.index(23 - i, j, k))], 1e-5f);
            }
        }
    }
    const Resampler skipping(source, g.mesh.tets, g.mesh.positions, {.skip_inverted = true});
    const ResampleStats skipped = skipping.resample(deformed, target);
    EXPECT_EQ(skipped.num_voxels_written, 0);
    for (const float x : got) {
        ASSERT_EQ(x, 0.0f);
    }
}

TEST(Resample, DegenerateTetsAreSkippedWithoutCrashing) {
    const Volume source = shepp_logan_3d({16, 16, 16});
    const pbd::TetGrid g = full_grid(source, 4);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    Volume target = like(source, VoxelType::f32);
    // Everything collapsed onto one voxel centre, then onto the plane of a layer of centres
    // (so that every tet's box still holds centres and reaches the per-tet kernel).
    const Vec3f centre = vec3_cast<float>(source.voxel_center(3, 4, 5));
    std::vector<Vec3f> point(g.mesh.positions.size(), centre);
    ResampleStats stats = resampler.resample(point, target);
    EXPECT_EQ(stats.num_degenerate, static_cast<std::int64_t>(resampler.kept_tets().size()));
    EXPECT_EQ(stats.num_voxels_written, 0);
    std::vector<Vec3f> flat = g.mesh.positions;
    for (Vec3f& p : flat) {
        p.z = centre.z;
    }
    stats = resampler.resample(flat, target);
    EXPECT_EQ(stats.num_degenerate, static_cast<std::int64_t>(resampler.kept_tets().size()));
    // Huge and tiny coordinates: no crash, finite output.
    std::vector<Vec3f> far = g.mesh.positions;
    far[0] = {1e30f, -1e30f, 1e30f};
    far[1] = {1e-30f, 0.0f, 0.0f};
    stats = resampler.resample(far, target);
    for (const float x : target.values<VoxelType::f32>()) {
        ASSERT_TRUE(std::isfinite(x));
    }
}

TEST(Resample, IntegerTargetsRoundAndClamp) {
    Volume source = Volume::allocate({8, 8, 8}, VoxelType::i16);
    auto values = source.values<VoxelType::i16>();
    for (std::size_t v = 0; v < values.size(); ++v) {
        values[v] = static_cast<std::int16_t>(static_cast<int>(v % 17) * 1000 - 8000);
    }
    const pbd::TetGrid g = full_grid(source, 2);
    const Resampler resampler(source, g.mesh.tets, g.mesh.positions);
    Volume same = like(source, VoxelType::i16);
    resampler.resample(g.mesh.positions, same);
    EXPECT_EQ(std::memcmp(same.bytes().data(), source.bytes().data(), source.size_bytes()), 0);
    Volume as_float = like(source, VoxelType::f32);
    resampler.resample(g.mesh.positions, as_float);
    EXPECT_NEAR(as_float.values<VoxelType::f32>()[5], static_cast<float>(values[5]), 1e-3f);
    EXPECT_EQ(detail::convert_sample<std::uint8_t>(300.0f, 1.0f), 255);
    EXPECT_EQ(detail::convert_sample<std::uint8_t>(-3.0f, 1.0f), 0);
    EXPECT_EQ(detail::convert_sample<std::uint8_t>(2.5f, 1.0f), 3);
    EXPECT_EQ(detail::convert_sample<std::int16_t>(-2.4f, 1.0f), -2);
    EXPECT_EQ(detail::convert_sample<std::int16_t>(-2.6f, 1.0f), -3);
    EXPECT_EQ(detail::convert_sample<std::int16_t>(-1e9f, 1.0f), -32768);
    EXPECT_EQ(detail::convert_sample<std::uint16_t>(std::nanf(""), 1.0f), 0);
}

TEST(Resample, SamplesClampWithinHalfAVoxelAndAreZeroOutside) {
    const float data[8] = {1, 2, 3, 4, 5, 6, 7, 8};  // 2 × 2 × 2
    const std::int64_t n[3] = {2, 2, 2};
    float out = -1.0f;
    detail::sample_trilinear<float, 1>(data, n, -0.5, 0.0, 0.0, &out);
    EXPECT_EQ(out, 1.0f);
    detail::sample_trilinear<float, 1>(data, n, 1.5, 1.5, 1.5, &out);
    EXPECT_EQ(out, 8.0f);
    detail::sample_trilinear<float, 1>(data, n, 0.5, 0.5, 0.5, &out);
    EXPECT_FLOAT_EQ(out, 4.5f);
    detail::sample_trilinear<float, 1>(data, n, -0.5001, 0.0, 0.0, &out);
    EXPECT_EQ(out, 0.0f);
    detail::sample_trilinear<float, 1>(data, n, 0.0, 1.5001, 0.0, &out);
    EXPECT_EQ(out, 0.0f);
    detail::sample_trilinear<float, 1>(data, n, std::nan(""), 0.0, 0.0, &out);
    EXPECT_EQ(out, 0.0f);
}

template <typename F>
void expect_invalid(F&& f, const std::string& fragment) {
    try {
        f();
        ADD_FAILURE() << "no InvalidInput; expected a message with '" << fragment << "'";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

TEST(Resample, BadInputsAreInvalidInputWithClearMessages) {
    const Volume source = shepp_logan_3d({8, 8, 8});
    const pbd::TetGrid g = full_grid(source, 4);
    const auto& tets = g.mesh.tets;
    const auto& rest = g.mesh.positions;
    expect_invalid([&] { Resampler(Volume{}, tets, rest); }, "source volume is empty");
    std::vector<geometry::Tet> bad_tets = tets;
    bad_tets[3][2] = static_cast<std::int32_t>(rest.size());
    expect_invalid([&] { Resampler(source, bad_tets, rest); }, "tets[3]");
    bad_tets[3][2] = -1;
    expect_invalid([&] { Resampler(source, bad_tets, rest); }, "outside [0, 27)");
    std::vector<Vec3f> nan_rest = rest;
    nan_rest[5].y = std::nanf("");
    expect_invalid([&] { Resampler(source, tets, nan_rest); }, "rest_positions[5]");

    const Resampler resampler(source, tets, rest);
    Volume target = like(source, VoxelType::f32);
    std::vector<Vec3f> short_positions(rest.begin(), rest.end() - 1);
    expect_invalid([&] { resampler.resample(short_positions, target); },
                   "deformed_positions.size() (26) != rest_positions.size() (27)");
    std::vector<Vec3f> inf_positions = rest;
    inf_positions[7].x = std::numeric_limits<float>::infinity();
    expect_invalid([&] { resampler.resample(inf_positions, target); }, "deformed_positions[7]");
    Volume u8_target = like(source, VoxelType::u8);
    expect_invalid([&] { resampler.resample(rest, u8_target); },
                   "cannot resample a f32 source into a u8 target");
    Volume empty;
    expect_invalid([&] { resampler.resample(rest, empty); }, "target volume is empty");
    std::vector<std::uint8_t> counts(10);
    expect_invalid([&] { resampler.count_coverage(rest, source, counts); }, "counts.size() (10)");
    EXPECT_TRUE(can_resample_into(VoxelType::u16, VoxelType::f32));
    EXPECT_FALSE(can_resample_into(VoxelType::f32, VoxelType::u16));
    EXPECT_FALSE(can_resample_into(VoxelType::rgba32f, VoxelType::rgba8));
}

}  // namespace
}  // namespace pliant::volume
