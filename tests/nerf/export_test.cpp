// Export of a trained field as an RGBA volume: the closed form for a uniform field, and the
// pipeline's promise: a field trained on ray-cast views of a volume, exported and ray-cast again
// with the same cameras, reproduces the training views.
#include "pliant/nerf/export.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "ball_scene.hpp"
#include "pliant/core/error.hpp"
#include "pliant/nerf/crop.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/trainer.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::nerf {
namespace {

TEST(Export, UniformFieldGivesTheClosedFormOpacity) {
    // σ = 2 per normalized unit over a 4 × 2 × 2 box (scale 4): σ_world = 0.5 per world unit.
    const RadianceGrid grid(AABBd{{0, 0, 0}, {4, 2, 2}}, 8, density_raw_for_sigma(2.0f), 0.0f);
    ExportOptions o;
    o.resolution = 16;
    o.type = volume::VoxelType::rgba32f;
    const volume::Volume v = export_volume(grid, o);
    EXPECT_EQ(v.dims(), (volume::Dims{16, 8, 8}));
    EXPECT_DOUBLE_EQ(v.spacing().x, 0.25);
    const auto rgba = v.values<volume::VoxelType::rgba32f>();
    const double u = 0.25;  // the smallest spacing: the opacity unit
    EXPECT_NEAR(rgba[3], 1.0 - std::exp(-0.5 * u), 1e-6);
    EXPECT_NEAR(rgba[0], 0.5, 1e-7);  // sigmoid(0)
    o.type = volume::VoxelType::rgba8;
    const volume::Volume v8 = export_volume(grid, o);
    EXPECT_EQ(v8.values<volume::VoxelType::rgba8>()[3],
              std::lround(255.0 * (1.0 - std::exp(-0.5 * u))));
}

TEST(Export, RejectsBadOptions) {
    const RadianceGrid grid(AABBd{{0, 0, 0}, {1, 1, 1}}, 4, 0.0f, 0.0f);
    ExportOptions o;
    o.resolution = 0;
    EXPECT_THROW(export_volume(grid, o), InvalidInput);
    o.resolution = 8;
    o.type = volume::VoxelType::f32;
    EXPECT_THROW(export_volume(grid, o), InvalidInput);
}

// An RGBA ball: a red core (α 0.5 per voxel) inside a translucent blue shell (α 0.15).
volume::Volume rgba_ball(int n) {
    volume::Volume v = volume::Volume::allocate({n, n, n}, volume::VoxelType::rgba8);
    auto p = v.values<volume::VoxelType::rgba8>();
    for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const Vec3d c = v.voxel_center(i, j, k) - Vec3d{0.5 * n, 0.5 * n, 0.5 * n};
                const double r = norm(c) / n;
                const std::int64_t q = 4 * v.index(i, j, k);
                if (r < 0.2) {
                    p[q] = 230, p[q + 1] = 60, p[q + 2] = 40, p[q + 3] = 128;
                } else if (r < 0.38) {
                    p[q] = 40, p[q + 1] = 90, p[q + 2] = 220, p[q + 3] = 38;
                }
            }
        }
    }
    return v;
}

TEST(Export, RayCastExportReproducesTheTrainingViews) {
    const volume::Volume truth = rgba_ball(20);
    const render::RayCaster caster(truth, nullptr, {});
    Dataset ds;
    ds.box = truth.bounds();
    std::vector<render::Camera> cameras;
    render::Image image;
    const int views = 20;
    for (int i = 0; i < views; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / views;
        cameras.push_back(render::frame_box(truth.bounds(), i * 137.508,
                                            std::asin(z) * 180.0 / std::numbers::pi, 24, 24));
        caster.render(cameras.back(), image);
        ds.intrinsics = intrinsics_from_camera(cameras.back());
        View v;
        v.camera_to_world = pose_from_camera(cameras.back());
        v.rgb = from_image(image);
        ds.views.push_back(std::move(v));
    }
    TrainOptions o;
    o.resolution = 20;
    o.stages = 2;
    o.iterations = 300;
    o.batch_rays = 512;
    const TrainResult r = train(ds, o, [](const TrainProgress&) { return true; });
    ExportOptions eo;
    eo.resolution = 20;
    const volume::Volume exported = export_volume(r.grid, eo);
    const render::RayCaster back(exported, nullptr, {});
    double sum = 0.0;
    for (int i = 0; i < views; ++i) {
        back.render(camera_from_view(ds.intrinsics, ds.views[i].camera_to_world), image);
        sum += psnr(from_image(image), ds.views[i].rgb);
    }
    // Measured 35.0 dB (300 iterations, 20 views of 24 x 24). The margin covers the two
    // renderers' differences: the ray caster interpolates exported (α·c, α) where the field
    // interpolates raw parameters, and it stops rays at A > 0.99.
    EXPECT_GT(sum / views, 25.0);
    RecordProperty("psnr", std::to_string(sum / views));
}

// A scene as a capture sees it: a table top (a dense slab over the whole box, z ∈ [0.25, 0.3])
// with a ball on it (centre (0.4, 0.6, 0.45), radius 0.15) and a small floater in the air (centre
// (0.9, 0.1, 0.9), radius 0.03) in the box [0, 1]³, world units.
RadianceGrid table_and_ball(int resolution) {
    RadianceGrid g = test::unit_box_field(resolution, [](const Vec3d& c, float* q) {
        const bool table = c.z >= 0.25 && c.z <= 0.3;
        const bool ball = norm(c - Vec3d{0.4, 0.6, 0.45}) <= 0.15;
        const bool floater = norm(c - Vec3d{0.9, 0.1, 0.9}) <= 0.03;
        if (table || ball || floater) {
            q[0] = density_raw_for_sigma(400.0f);
        }
    });
    g.update_occupancy(1e-3f);
    return g;
}

TEST(AutoCrop, KeepsTheObjectAndDropsTheTable) {
    const RadianceGrid grid = table_and_ball(64);
    const AABBd crop = auto_crop(grid, AutoCropOptions{});
    // The ball above the table top (z > 0.3) lies inside, within a few voxels' margin.
    const double voxel = 1.0 / 64.0;
    EXPECT_LE(crop.lo.x, 0.25 + voxel);
    EXPECT_GE(crop.hi.x, 0.55 - voxel);
    EXPECT_LE(crop.lo.y, 0.45 + voxel);
    EXPECT_GE(crop.hi.y, 0.75 - voxel);
    EXPECT_GE(crop.hi.z, 0.6 - voxel);
    // The table is outside: the crop starts above its top, and is not as wide as the table.
    EXPECT_GT(crop.lo.z, 0.3);
    EXPECT_LT(crop.lo.z, 0.3 + 3 * voxel);
    EXPECT_LT(crop.hi.x - crop.lo.x, 0.45);
    EXPECT_GT(crop.lo.x, 0.15);
    // The floater is left out.
    EXPECT_LT(crop.hi.x, 0.7);
    EXPECT_GT(crop.lo.y, 0.3);
    EXPECT_LT(crop.hi.z, 0.7);

    // The exported volume covers the crop and holds the ball but no table voxel.
    ExportOptions o;
    o.resolution = 48;
    o.box = crop;
    const volume::Volume v = export_volume(grid, o);
    EXPECT_NEAR(v.bounds().lo.x, crop.lo.x, 1e-12);
    EXPECT_NEAR(v.bounds().hi.z, crop.hi.z, 1e-9);
    const auto rgba = v.values<volume::VoxelType::rgba8>();
    std::int64_t opaque = 0;
    for (std::int64_t k = 0; k < v.dims()[2]; ++k) {
        for (std::int64_t j = 0; j < v.dims()[1]; ++j) {
            for (std::int64_t i = 0; i < v.dims()[0]; ++i) {
                if (rgba[4 * v.index(i, j, k) + 3] > 128) {
                    ++opaque;
                    EXPECT_LT(norm(v.voxel_center(i, j, k) - Vec3d{0.4, 0.6, 0.45}), 0.17);
                }
            }
        }
    }
    EXPECT_GT(opaque, 0);
}

TEST(AutoCrop, WithoutATableKeepsAllOfTheObject) {
    RadianceGrid grid = table_and_ball(32);
    // Remove the table: only the ball remains.
    const auto& d = grid.dims();
    auto p = grid.params();
    for (int k = 0; k < d[2]; ++k) {
        const double z = (k + 0.5) / d[2];
        for (std::int64_t v = static_cast<std::int64_t>(k) * d[0] * d[1];
             z >= 0.25 && z <= 0.3 && v < static_cast<std::int64_t>(k + 1) * d[0] * d[1]; ++v) {
            p[4 * v] = -12.0f;
        }
    }
    grid.update_occupancy(1e-3f);
    const AABBd crop = auto_crop(grid, AutoCropOptions{});
    EXPECT_LE(crop.lo.z, 0.3);
    EXPECT_GE(crop.hi.z, 0.6 - 1.0 / 32);
    // An empty field: the whole box.
    const RadianceGrid empty(AABBd{{0, 0, 0}, {1, 1, 1}}, 8, -12.0f, 0.0f);
    const AABBd all = auto_crop(empty, AutoCropOptions{});
    EXPECT_EQ(all.lo, (Vec3d{0, 0, 0}));
    EXPECT_EQ(all.hi, (Vec3d{1, 1, 1}));
}

TEST(Export, OutsideTheGridIsEmptyAndBadBoxesAreRefused) {
    const RadianceGrid grid(AABBd{{0, 0, 0}, {1, 1, 1}}, 8, density_raw_for_sigma(50.0f), 0.0f);
    ExportOptions o;
    o.resolution = 4;
    o.box = AABBd{{0.5, 0.5, 0.5}, {1.5, 1.5, 1.5}};  // half of each axis outside
    const volume::Volume v = export_volume(grid, o);
    const auto rgba = v.values<volume::VoxelType::rgba8>();
    EXPECT_GT(rgba[4 * v.index(0, 0, 0) + 3], 0);
    EXPECT_EQ(rgba[4 * v.index(3, 3, 3) + 3], 0);
    o.box = AABBd{{0, 0, 0}, {1, 0, 1}};
    EXPECT_THROW(export_volume(grid, o), InvalidInput);
}

}  // namespace
}  // namespace pliant::nerf
