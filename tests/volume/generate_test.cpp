#include "pliant/volume/generate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

TEST(SheppLogan, ValuesAtKnownPoints) {
    // Centre: skull (2.0) + brain (−0.98).
    EXPECT_FLOAT_EQ(shepp_logan_value({0.0, 0.0, 0.0}), 1.02f);
    // Between the skull's outer (a = 0.69) and inner (a = 0.6624) ellipsoid on +x: bone only.
    EXPECT_FLOAT_EQ(shepp_logan_value({0.68, 0.0, 0.0}), 2.0f);
    EXPECT_FLOAT_EQ(shepp_logan_value({0.0, 0.0, 0.89}), 2.0f);  // c = 0.9 vs 0.88
    // Outside the head.
    EXPECT_FLOAT_EQ(shepp_logan_value({0.7, 0.0, 0.0}), 0.0f);
    EXPECT_FLOAT_EQ(shepp_logan_value({0.9, 0.9, 0.9}), 0.0f);
    // Centre of ellipsoid 5 (0, 0.35, −0.25): brain + 0.02.
    EXPECT_FLOAT_EQ(shepp_logan_value({0.0, 0.35, -0.25}), 1.04f);
    // Ellipsoid 3 at (−0.22, 0, −0.25), a = 0.41 along 108°: its a-axis is nearly along y.
    const double phi = 108.0 * std::numbers::pi / 180.0;
    const Vec3d along_a{-0.22 + 0.35 * std::cos(phi), 0.35 * std::sin(phi), -0.25};
    EXPECT_FLOAT_EQ(shepp_logan_value(along_a), 1.0f);  // 2 − 0.98 − 0.02
    const Vec3d along_x{-0.22 - 0.2, 0.0, -0.25};       // beyond b = 0.16 along the rotated b-axis
    EXPECT_FLOAT_EQ(shepp_logan_value(along_x), 1.02f);
    // The higher-contrast variant: skull 1.0, brain 0.2.
    EXPECT_FLOAT_EQ(shepp_logan_value({0.68, 0.0, 0.0}, SheppLoganVariant::yu_ye_wang), 1.0f);
    EXPECT_NEAR(shepp_logan_value({0.0, 0.0, 0.0}, SheppLoganVariant::yu_ye_wang), 0.2f, 1e-6f);
}

TEST(SheppLogan, VolumeSpansTheUnitBoxAndSamplesVoxelCentres) {
    const Volume v = shepp_logan_3d({64, 48, 32});
    EXPECT_EQ(v.type(), VoxelType::f32);
    EXPECT_DOUBLE_EQ(v.bounds().lo.x, -1.0);
    EXPECT_DOUBLE_EQ(v.bounds().hi.y, 1.0);
    EXPECT_DOUBLE_EQ(v.spacing().z, 2.0 / 32.0);
    const auto values = v.values<VoxelType::f32>();
    // Voxel (53, 24, 16): centre (0.671875, 0.0208, 0.03125) lies in the skull shell.
    EXPECT_FLOAT_EQ(values[static_cast<std::size_t>(v.index(53, 24, 16))], 2.0f);
    EXPECT_FLOAT_EQ(values[static_cast<std::size_t>(v.index(32, 24, 16))], 1.02f);
    EXPECT_FLOAT_EQ(values[0], 0.0f);
    for (std::int64_t k = 0; k < 32; k += 7) {
        for (std::int64_t j = 0; j < 48; j += 5) {
            for (std::int64_t i = 0; i < 64; i += 3) {
                ASSERT_EQ(values[static_cast<std::size_t>(v.index(i, j, k))],
                          shepp_logan_value(v.voxel_center(i, j, k)));
            }
        }
    }
    EXPECT_THROW(shepp_logan_3d({0, 4, 4}), InvalidInput);
}

TEST(UniformSphere, VoxelCountMatchesAnalyticVolume) {
    const double r = 12.3;
    // Radius 12.3 world units in a 20-unit box: clipped by the box, still a valid volume.
    const Volume v = uniform_sphere({40, 40, 40}, r, 3.0f, {.spacing = {0.5, 0.5, 0.5}});
    const Volume w = uniform_sphere({40, 40, 40}, 8.0, 3.0f, {.spacing = {0.5, 0.5, 0.5}});
    double count = 0;
    for (const float x : w.values<VoxelType::f32>()) {
        ASSERT_TRUE(x == 0.0f || x == 3.0f);
        count += x == 3.0f ? 1 : 0;
    }
    const double analytic = 4.0 / 3.0 * std::numbers::pi * 8.0 * 8.0 * 8.0;
    const double measured = count * 0.125;
    // Discretization error ~ surface area × half a voxel.
    const double bound = 4.0 * std::numbers::pi * 64.0 * 0.25;
    EXPECT_NEAR(measured, analytic, bound);
    EXPECT_NEAR(measured, analytic, 0.02 * analytic);
    EXPECT_EQ(v.dims()[0], 40);
    // Supersampling: coverage-weighted sum is closer to the analytic volume.
    const Volume s =
        uniform_sphere({40, 40, 40}, 8.0, 1.0f, {.spacing = {0.5, 0.5, 0.5}, .supersample = 4});
    double sum = 0;
    for (const float x : s.values<VoxelType::f32>()) {
        ASSERT_GE(x, 0.0f);
        ASSERT_LE(x, 1.0f);
        sum += x;
    }
    EXPECT_LT(std::abs(sum * 0.125 - analytic), std::abs(measured - analytic) + 1e-9);
    EXPECT_NEAR(sum * 0.125, analytic, 0.005 * analytic);
}

TEST(UniformSphere, RgbaAndPlacement) {
    const Volume v =
        uniform_sphere({10, 10, 10}, 1.5, std::array<float, 4>{1.0f, 0.5f, 0.0f, 0.25f},
                       {.has_center = true, .center = {2.0, 2.0, 2.0}});
    EXPECT_EQ(v.type(), VoxelType::rgba32f);
    const auto c = v.values<VoxelType::rgba32f>();
    const auto at = [&](int i, int j, int k, int ch) {
        return c[static_cast<std::size_t>(4 * v.index(i, j, k) + ch)];
    };
    EXPECT_FLOAT_EQ(at(1, 1, 1, 0), 1.0f);  // centre (1.5, 1.5, 1.5): 0.87 from the centre
    EXPECT_FLOAT_EQ(at(1, 1, 1, 3), 0.25f);
    EXPECT_FLOAT_EQ(at(5, 5, 5, 3), 0.0f);
    EXPECT_FLOAT_EQ(at(5, 5, 5, 1), 0.0f);
    EXPECT_THROW(uniform_sphere({4, 4, 4}, 0.0, 1.0f), InvalidInput);
    EXPECT_THROW(uniform_sphere({4, 4, 4}, 1.0, 1.0f, {.supersample = 0}), InvalidInput);
    EXPECT_THROW(uniform_sphere({4, 4, 4}, 1.0, std::array<float, 4>{2.0f, 0, 0, 0}), InvalidInput);
}

TEST(RgbaTestObject, ArrowsHaveTheirAxisColours) {
    const Volume v = rgba_test_object({40, 40, 40});
    const auto c = v.values<VoxelType::rgba32f>();
    // Voxel whose centre is nearest a world point.
    const auto at = [&](double x, double y, double z) {
        const auto idx = [](double p) {
            return static_cast<std::int64_t>((p + 1.0) / 0.05);
        };
        const auto base = static_cast<std::size_t>(4 * v.index(idx(x), idx(y), idx(z)));
        return std::array<float, 4>{c[base], c[base + 1], c[base + 2], c[base + 3]};
    };
    EXPECT_EQ(at(0.45, 0.0, 0.0), (std::array<float, 4>{1.0f, 0.0f, 0.0f, 0.6f}));
    EXPECT_EQ(at(0.0, 0.7, 0.0), (std::array<float, 4>{0.0f, 1.0f, 0.0f, 0.6f}));
    EXPECT_EQ(at(0.0, 0.0, 0.45), (std::array<float, 4>{0.0f, 0.0f, 1.0f, 0.6f}));
    EXPECT_EQ(at(-0.45, 0.0, 0.0)[3], 0.0f);  // no arrow along −x
    EXPECT_EQ(at(0.0, 0.0, 0.0), (std::array<float, 4>{0.5f, 0.5f, 0.5f, 0.1f}));
    EXPECT_EQ(at(-0.6, -0.6, -0.6), (std::array<float, 4>{1.0f, 1.0f, 0.0f, 0.6f}));
    EXPECT_EQ(at(0.6, 0.6, 0.6)[3], 0.0f);
    const Volume b = rgba_test_object({40, 40, 40}, VoxelType::rgba8);
    const auto bytes = b.values<VoxelType::rgba8>();
    const auto base = static_cast<std::size_t>(4 * b.index(29, 20, 20));  // x = 0.475
    EXPECT_EQ(bytes[base], 255);
    EXPECT_EQ(bytes[base + 1], 0);
    EXPECT_EQ(bytes[base + 3], 153);  // round(255 · 0.6)
    EXPECT_THROW(rgba_test_object({4, 4, 4}, VoxelType::f32), InvalidInput);
}

TEST(Generate, BitwiseIdenticalForOneAndTwoThreads) {
    set_num_threads(1);
    const Volume a = shepp_logan_3d({24, 20, 16});
    const Volume b = uniform_sphere({16, 16, 16}, 5.0, 1.0f, {.supersample = 3});
    const Volume c = rgba_test_object({16, 16, 16});
    set_num_threads(2);
    const Volume a2 = shepp_logan_3d({24, 20, 16});
    const Volume b2 = uniform_sphere({16, 16, 16}, 5.0, 1.0f, {.supersample = 3});
    const Volume c2 = rgba_test_object({16, 16, 16});
    set_num_threads(0);
    EXPECT_EQ(std::memcmp(a.bytes().data(), a2.bytes().data(), a.size_bytes()), 0);
    EXPECT_EQ(std::memcmp(b.bytes().data(), b2.bytes().data(), b.size_bytes()), 0);
    EXPECT_EQ(std::memcmp(c.bytes().data(), c2.bytes().data(), c.size_bytes()), 0);
}

}  // namespace
}  // namespace pliant::volume
