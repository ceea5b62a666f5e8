#include "pliant/pipeline/memory_budget.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {
namespace {

// MappedRayCaster's bound covers what it holds at its peak: a shaded rgba8 source's bytes, its
// 16-byte packed records and the 2 bytes of their neighbourhood passes (22 per voxel); a scalar
// source's float copy and stored gradient (12).
TEST(MemoryBudget, MappedCasterBoundCoversItsPeak) {
    const volume::Dims dims{64, 48, 32};
    const std::uint64_t voxels = 64 * 48 * 32;
    EXPECT_GE(mapped_ray_cast_bytes(dims, 4), 22 * voxels);
    EXPECT_GE(mapped_ray_cast_bytes(dims, 1), 12 * voxels);
    EXPECT_EQ(mapped_ray_cast_bytes({0, 10, 10}, 4), 0u);
    const std::int64_t huge = std::int64_t{1} << 40;
    EXPECT_EQ(mapped_ray_cast_bytes({huge, huge, huge}, 4),
              std::numeric_limits<std::uint64_t>::max());
}

// deform with a video counts the larger caster of the two routes: at least the source, the
// resampling target, the mapped caster and the image beside the soft body.
TEST(MemoryBudget, DeformWithAVideoCountsTheMappedCaster) {
    const volume::Volume source =
        volume::Volume::allocate({32, 32, 32}, volume::VoxelType::rgba8, {1.0, 1.0, 1.0}, {});
    const std::uint64_t without = deform_need_bytes(source, 512, 0, 0);
    const std::uint64_t with = deform_need_bytes(source, 512, 64, 48);
    EXPECT_GE(with, without + mapped_ray_cast_bytes(source.dims(), 4) + image_bytes(64, 48));
    EXPECT_GE(with, without + ray_cast_bytes(source.dims(), 4) + image_bytes(64, 48));
}

}  // namespace
}  // namespace pliant::pipeline
