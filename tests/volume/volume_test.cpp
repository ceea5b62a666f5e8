#include "pliant/volume/volume.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pliant/core/error.hpp"

namespace pliant::volume {
namespace {

TEST(Volume, SizesPlacementAndTypedViews) {
    Volume v = Volume::allocate({4, 3, 2}, VoxelType::rgba8, {0.5, 1.0, 2.0}, {-1.0, 0.0, 10.0});
    EXPECT_EQ(v.num_voxels(), 24);
    EXPECT_EQ(v.size_bytes(), 96u);
    EXPECT_EQ(v.values<VoxelType::rgba8>().size(), 96u);
    // Voxel centres at origin + (i + 0.5) · spacing; the box is [origin, origin + dims · spacing].
    const Vec3d c = v.voxel_center(3, 2, 1);
    EXPECT_DOUBLE_EQ(c.x, -1.0 + 3.5 * 0.5);
    EXPECT_DOUBLE_EQ(c.y, 2.5);
    EXPECT_DOUBLE_EQ(c.z, 10.0 + 1.5 * 2.0);
    EXPECT_DOUBLE_EQ(v.bounds().hi.x, 1.0);
    EXPECT_DOUBLE_EQ(v.bounds().hi.z, 14.0);
    EXPECT_EQ(v.index(1, 2, 1), 1 + 4 * (2 + 3 * 1));
    EXPECT_THROW(v.values<VoxelType::f32>(), InvalidInput);
    Volume f = Volume::allocate({2, 2, 2}, VoxelType::f32);
    f.values<VoxelType::f32>()[7] = 1.5f;
    EXPECT_EQ(f.size_bytes(), 32u);
    EXPECT_FLOAT_EQ(f.values<VoxelType::f32>()[7], 1.5f);
    EXPECT_EQ(f.values<VoxelType::f32>()[0], 0.0f);  // zero-filled
    EXPECT_EQ(name(VoxelType::i16), "i16");
    EXPECT_EQ(bytes_per_voxel(VoxelType::rgba32f), 16u);
}

TEST(Volume, RefusesBadDimsSpacingAndHugeSizes) {
    EXPECT_THROW(Volume::allocate({0, 1, 1}, VoxelType::u8), InvalidInput);
    EXPECT_THROW(Volume::allocate({1, 1, 1}, VoxelType::u8, {0.0, 1.0, 1.0}), InvalidInput);
    EXPECT_THROW(Volume::allocate({1, 1, 1}, VoxelType::u8, {1.0, 1.0, 1.0},
                                  {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}),
                 InvalidInput);
    // 2^21 cubed would overflow 64-bit byte counts: refused by the limit, no allocation.
    try {
        Volume::allocate({1 << 21, 1 << 21, 1 << 21}, VoxelType::rgba32f);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("limit"), std::string::npos) << e.what();
    }
    EXPECT_THROW(Volume::allocate({64, 64, 64}, VoxelType::u8, {1, 1, 1}, {0, 0, 0}, 1000),
                 InvalidInput);
    EXPECT_NO_THROW(Volume::allocate({10, 10, 10}, VoxelType::u8, {1, 1, 1}, {0, 0, 0}, 1000));
}

}  // namespace
}  // namespace pliant::volume
