#include "pliant/volume/reorient.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

// Rotation by `degrees` about +axis (0: x, 1: y, 2: z), as direction columns.
Direction rotation(int axis, double degrees) {
    const double t = degrees * std::numbers::pi / 180.0;
    const double c = std::cos(t);
    const double s = std::sin(t);
    Direction d = IDENTITY_DIRECTION;
    const int u = (axis + 1) % 3;
    const int v = (axis + 2) % 3;
    // Column u turns toward v, column v toward −u.
    d[static_cast<std::size_t>(u)] = {};
    d[static_cast<std::size_t>(v)] = {};
    d[static_cast<std::size_t>(u)][u] = c;
    d[static_cast<std::size_t>(u)][v] = s;
    d[static_cast<std::size_t>(v)][u] = -s;
    d[static_cast<std::size_t>(v)][v] = c;
    return d;
}

// f32 volume whose voxel value encodes its index: i + 100 j + 10000 k.
Volume indexed(const Dims& dims) {
    Volume v = Volume::allocate(dims, VoxelType::f32);
    auto values = v.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < dims[2]; ++k) {
        for (std::int64_t j = 0; j < dims[1]; ++j) {
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                values[static_cast<std::size_t>(v.index(i, j, k))] =
                    static_cast<float>(i + 100 * j + 10000 * k);
            }
        }
    }
    return v;
}

TEST(Direction, DefaultsToIdentityAndPlacesVoxelsInTheWorld) {
    Volume v = Volume::allocate({4, 3, 2}, VoxelType::u8, {1.0, 2.0, 3.0}, {10.0, 20.0, 30.0});
    EXPECT_TRUE(v.is_axis_aligned());
    EXPECT_EQ(v.direction(), IDENTITY_DIRECTION);
    // 90° about z: i runs along +y, j along −x.
    v.set_direction(rotation(2, 90.0));
    EXPECT_FALSE(v.is_axis_aligned());
    const Vec3d c = v.voxel_center(1, 0, 0);  // 1.5 voxels (1.5 world units) along +y
    EXPECT_NEAR(c.x, 10.0 - 0.5 * 2.0, 1e-12);
    EXPECT_NEAR(c.y, 20.0 + 1.5, 1e-12);
    EXPECT_NEAR(c.z, 30.0 + 1.5, 1e-12);
    const AABBd box = v.world_bounds();
    EXPECT_NEAR(box.lo.x, 10.0 - 6.0, 1e-12);
    EXPECT_NEAR(box.hi.x, 10.0, 1e-12);
    EXPECT_NEAR(box.hi.y, 24.0, 1e-12);
    EXPECT_NEAR(box.hi.z, 36.0, 1e-12);
    // bounds() stays the box in the grid's own frame.
    EXPECT_EQ(v.bounds().hi.x, 14.0);
}

TEST(Direction, RefusesColumnsThatAreNotOrthonormal) {
    Volume v = Volume::allocate({2, 2, 2}, VoxelType::u8);
    Direction d = IDENTITY_DIRECTION;
    d[1] = {0.1, 1.0, 0.0};
    try {
        v.set_direction(d);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("direction"), std::string::npos) << e.what();
    }
    d = IDENTITY_DIRECTION;
    d[2] = {0.0, 0.0, std::numeric_limits<double>::quiet_NaN()};
    EXPECT_THROW(v.set_direction(d), InvalidInput);
    d = IDENTITY_DIRECTION;
    d[0] = {2.0, 0.0, 0.0};
    EXPECT_THROW(v.set_direction(d), InvalidInput);
    // A reflection is a valid direction.
    d = IDENTITY_DIRECTION;
    d[0] = {-1.0, 0.0, 0.0};
    EXPECT_NO_THROW(v.set_direction(d));
    EXPECT_TRUE(Volume::allocate({1, 1, 1}, VoxelType::u8).is_axis_aligned());
}

TEST(PlaceNearestAxes, FlippedAxisIsReindexedExactly) {
    // The x axis runs toward −x: the voxels are reversed along i, the volume is axis-aligned, and
    // the origin is what the axis-aligned readers always computed.
    GridPlacement p;
    p.centre0 = {5.0, -3.0, 7.25};
    p.steps = {Vec3d{-0.7, 0.0, 0.0}, Vec3d{0.0, 1.1, 0.0}, Vec3d{0.0, 0.0, 2.5}};
    const Volume v = place_nearest_axes(indexed({4, 3, 2}), p);
    EXPECT_TRUE(v.is_axis_aligned());
    EXPECT_EQ(v.dims(), (Dims{4, 3, 2}));
    EXPECT_EQ(v.spacing(), (Vec3d{0.7, 1.1, 2.5}));
    EXPECT_EQ(v.origin().x, (5.0 - 3.0 * 0.7) - 0.5 * 0.7);
    EXPECT_EQ(v.origin().y, -3.0 - 0.5 * 1.1);
    EXPECT_EQ(v.origin().z, 7.25 - 0.5 * 2.5);
    const auto values = v.values<VoxelType::f32>();
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(0, 1, 1))], 3.0f + 100.0f + 10000.0f);
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(3, 2, 0))], 0.0f + 200.0f);
}

TEST(PlaceNearestAxes, KeepsTheWorldPositionOfEveryVoxel) {
    // Axes swapped and flipped (a sagittal-like grid), then the same tilted by 5°.
    for (const double tilt : {0.0, 5.0}) {
        const Direction r = rotation(0, tilt);
        GridPlacement p;
        p.centre0 = {1.0, 2.0, 3.0};
        const Vec3d along_i{0.0, 0.0, -2.0};  // grid i runs toward −z
        const Vec3d along_j{0.5, 0.0, 0.0};   // j toward +x
        const Vec3d along_k{0.0, 1.5, 0.0};   // k toward +y
        const auto turn = [&](const Vec3d& a) {
            return r[0] * a.x + r[1] * a.y + r[2] * a.z;
        };
        p.steps = {turn(along_i), turn(along_j), turn(along_k)};
        const Dims file_dims{5, 4, 3};
        const Volume v = place_nearest_axes(indexed(file_dims), p);
        EXPECT_EQ(v.dims(), (Dims{4, 3, 5}));
        EXPECT_EQ(v.is_axis_aligned(), tilt == 0.0);
        EXPECT_NEAR(v.spacing().x, 0.5, 1e-12);
        EXPECT_NEAR(v.spacing().y, 1.5, 1e-12);
        EXPECT_NEAR(v.spacing().z, 2.0, 1e-12);
        const auto values = v.values<VoxelType::f32>();
        for (std::int64_t k = 0; k < v.dims()[2]; ++k) {
            for (std::int64_t j = 0; j < v.dims()[1]; ++j) {
                for (std::int64_t i = 0; i < v.dims()[0]; ++i) {
                    const auto code = static_cast<std::int64_t>(
                        values[static_cast<std::size_t>(v.index(i, j, k))]);
                    const std::int64_t fi = code % 100;
                    const std::int64_t fj = (code / 100) % 100;
                    const std::int64_t fk = code / 10000;
                    const Vec3d expected = p.centre0 + p.steps[0] * static_cast<double>(fi) +
                                           p.steps[1] * static_cast<double>(fj) +
                                           p.steps[2] * static_cast<double>(fk);
                    const Vec3d got = v.voxel_center(i, j, k);
                    ASSERT_NEAR(got.x, expected.x, 1e-9) << i << " " << j << " " << k;
                    ASSERT_NEAR(got.y, expected.y, 1e-9);
                    ASSERT_NEAR(got.z, expected.z, 1e-9);
                }
            }
        }
    }
}

TEST(PlaceNearestAxes, RefusesShearAndZeroSteps) {
    GridPlacement p;
    p.steps[2] = {0.0, 0.3, 1.0};  // 17° off the k axis toward j: sheared
    try {
        place_nearest_axes(indexed({2, 2, 2}), p);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("sheared"), std::string::npos) << e.what();
    }
    p.steps[2] = {0.0, 0.0, 0.0};
    EXPECT_THROW(place_nearest_axes(indexed({2, 2, 2}), p), InvalidInput);
    // Rounding in files (six-decimal cosines) is not shear.
    p.steps[2] = {0.0, 1e-6, 1.0};
    EXPECT_TRUE(place_nearest_axes(indexed({2, 2, 2}), p).is_axis_aligned());
}

TEST(ResampleToAxisAligned, Rotation90AboutZIsTheExactPermutation) {
    for (const VoxelType type : {VoxelType::i16, VoxelType::f32, VoxelType::rgba8}) {
        const Dims dims{4, 5, 6};
        Volume source = Volume::allocate(dims, type, {1.0, 1.0, 1.0}, {3.0, -2.0, 1.0});
        auto bytes = source.bytes();
        for (std::size_t b = 0; b < bytes.size(); ++b) {
            bytes[b] = static_cast<std::byte>((b * 37 + 11) % 97);  // any pattern, small values
        }
        source.set_direction(rotation(2, 90.0));  // i → +y, j → −x
        const Volume out = resample_to_axis_aligned(source);
        ASSERT_TRUE(out.is_axis_aligned());
        ASSERT_EQ(out.dims(), (Dims{5, 4, 6}));
        EXPECT_EQ(out.spacing(), (Vec3d{1.0, 1.0, 1.0}));
        EXPECT_NEAR(out.origin().x, 3.0 - 5.0, 1e-12);
        EXPECT_NEAR(out.origin().y, -2.0, 1e-12);
        EXPECT_NEAR(out.origin().z, 1.0, 1e-12);
        const std::size_t voxel = bytes_per_voxel(type);
        for (std::int64_t k = 0; k < 6; ++k) {
            for (std::int64_t j = 0; j < 4; ++j) {
                for (std::int64_t i = 0; i < 5; ++i) {
                    // out (i, j, k) sits at source (j, 4 − i, k).
                    const auto o = static_cast<std::size_t>(out.index(i, j, k)) * voxel;
                    const auto s = static_cast<std::size_t>(source.index(j, 4 - i, k)) * voxel;
                    ASSERT_EQ(std::memcmp(out.bytes().data() + o, source.bytes().data() + s, voxel),
                              0)
                        << name(type) << " at " << i << " " << j << " " << k;
                }
            }
        }
    }
}

TEST(ResampleToAxisAligned, SphereTiltedBy5DegreesStaysASphere) {
    // A sphere of radius 9 (world units) sampled on a grid tilted 5° about x, then 5° about z
    // (x then z), centred at c. After resampling, voxels clearly inside (d < r − δ) are 1 and
    // clearly outside (d > r + δ) are 0, δ the source voxel's diagonal (the farthest a trilinear
    // sample reaches): the sphere is where it was, within a voxel.
    const Vec3d c{4.0, -3.0, 2.0};
    const double radius = 9.0;
    const Dims dims{28, 26, 24};
    const Vec3d spacing{0.8, 0.9, 1.0};
    const Direction rx = rotation(0, 5.0);
    const Direction rz = rotation(2, 5.0);
    Direction d{};
    for (std::size_t a = 0; a < 3; ++a) {
        d[a] = rz[0] * rx[a].x + rz[1] * rx[a].y + rz[2] * rx[a].z;
    }
    Volume source = Volume::allocate(dims, VoxelType::f32, spacing);
    source.set_direction(d);
    // Centre the grid on c: origin = c − D · (dims · spacing / 2).
    const Vec3d half{0.5 * 28 * 0.8, 0.5 * 26 * 0.9, 0.5 * 24 * 1.0};
    source.set_origin(c - d[0] * half.x - d[1] * half.y - d[2] * half.z);
    auto values = source.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < dims[2]; ++k) {
        for (std::int64_t j = 0; j < dims[1]; ++j) {
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                values[static_cast<std::size_t>(source.index(i, j, k))] =
                    norm(source.voxel_center(i, j, k) - c) <= radius ? 1.0f : 0.0f;
            }
        }
    }
    const Volume out = resample_to_axis_aligned(source);
    ASSERT_TRUE(out.is_axis_aligned());
    EXPECT_EQ(out.spacing(), (Vec3d{0.8, 0.8, 0.8}));
    // The new box covers the turned box.
    const AABBd turned = source.world_bounds();
    EXPECT_LE(out.bounds().lo.x, turned.lo.x + 1e-9);
    EXPECT_GE(out.bounds().hi.z, turned.hi.z - 1e-9);
    EXPECT_LT(out.bounds().hi.z - out.bounds().lo.z, turned.hi.z - turned.lo.z + 0.8 + 1e-9);
    const auto got = out.values<VoxelType::f32>();
    const double voxel = norm(spacing);
    std::int64_t inside = 0;
    std::int64_t outside = 0;
    Vec3d weighted{0.0, 0.0, 0.0};
    double mass = 0.0;
    for (std::int64_t k = 0; k < out.dims()[2]; ++k) {
        for (std::int64_t j = 0; j < out.dims()[1]; ++j) {
            for (std::int64_t i = 0; i < out.dims()[0]; ++i) {
                const double dist = norm(out.voxel_center(i, j, k) - c);
                const float v = got[static_cast<std::size_t>(out.index(i, j, k))];
                weighted += out.voxel_center(i, j, k) * static_cast<double>(v);
                mass += static_cast<double>(v);
                if (dist < radius - voxel) {
                    ASSERT_NEAR(v, 1.0f, 1e-6f) << i << " " << j << " " << k;
                    ++inside;
                } else if (dist > radius + voxel) {
                    ASSERT_NEAR(v, 0.0f, 1e-6f) << i << " " << j << " " << k;
                    ++outside;
                }
            }
        }
    }
    EXPECT_GT(inside, 3000);
    EXPECT_GT(outside, 3000);
    // Its centre of mass is c within a tenth of a voxel.
    const Vec3d centroid = weighted / mass;
    EXPECT_LT(norm(centroid - c), 0.08) << centroid.x << " " << centroid.y << " " << centroid.z;
}

TEST(ResampleToAxisAligned, OutsideValueClampingAndIdentity) {
    Volume source = Volume::allocate({3, 3, 3}, VoxelType::i16, {1, 1, 1}, {0, 0, 0});
    for (auto& v : source.values<VoxelType::i16>()) {
        v = 100;
    }
    // Axis-aligned, default spacing: unchanged.
    const Volume same = resample_to_axis_aligned(source);
    EXPECT_EQ(same.dims(), source.dims());
    EXPECT_TRUE(std::equal(same.bytes().begin(), same.bytes().end(), source.bytes().begin()));
    // Turned 45° about z: the corners of the new box are outside the source → the outside value,
    // clamped to int16.
    source.set_direction(rotation(2, 45.0));
    AxisAlignedOptions options;
    options.outside = -1e9;
    const Volume out = resample_to_axis_aligned(source, options);
    const auto values = out.values<VoxelType::i16>();
    EXPECT_EQ(values[0], -32768);
    const Dims& n = out.dims();
    EXPECT_EQ(values[static_cast<std::size_t>(out.index(n[0] / 2, n[1] / 2, n[2] / 2))], 100);
    options.spacing = {0.5, -1.0, 1.0};
    EXPECT_THROW(resample_to_axis_aligned(source, options), InvalidInput);
    options.spacing = {1e-6, 1e-6, 1e-6};
    options.max_bytes = 1 << 20;
    EXPECT_THROW(resample_to_axis_aligned(source, options), InvalidInput);
}

TEST(ResampleToAxisAligned, OneAndFourThreadsAgreeBitwise) {
    Volume source = indexed({9, 7, 5});
    source.set_direction(rotation(1, 17.0));
    set_num_threads(1);
    const Volume one = resample_to_axis_aligned(source, {.spacing = {0.7, 0.6, 0.5}});
    set_num_threads(4);
    const Volume four = resample_to_axis_aligned(source, {.spacing = {0.7, 0.6, 0.5}});
    set_num_threads(0);
    ASSERT_EQ(one.size_bytes(), four.size_bytes());
    EXPECT_TRUE(std::equal(one.bytes().begin(), one.bytes().end(), four.bytes().begin()));
}

}  // namespace
}  // namespace pliant::volume
