// Training on tiny synthetic scenes: a ground-truth field renders the views; training from a
// blank grid must reproduce them (train and held-out views), deterministically.
#include "pliant/nerf/trainer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/nerf/metrics.hpp"

namespace pliant::nerf {
namespace {

// Ground truth: a coloured ball (red core, blue shell) in a unit box.
RadianceGrid ball_field(int resolution) {
    RadianceGrid g(AABBd{{0, 0, 0}, {1, 1, 1}}, resolution, -12.0f, 0.0f);
    const auto& d = g.dims();
    auto p = g.params();
    for (int k = 0; k < d[2]; ++k) {
        for (int j = 0; j < d[1]; ++j) {
            for (int i = 0; i < d[0]; ++i) {
                const Vec3d c{(i + 0.5) / d[0] - 0.5, (j + 0.5) / d[1] - 0.5,
                              (k + 0.5) / d[2] - 0.5};
                const double r = norm(c);
                const std::size_t v = 4 * (i + d[0] * (j + static_cast<std::size_t>(d[1]) * k));
                if (r < 0.35) {
                    p[v] = density_raw_for_sigma(r < 0.2 ? 8.0f : 3.0f);
                    p[v + 1] = r < 0.2 ? 2.0f : -2.0f;
                    p[v + 2] = -1.0f;
                    p[v + 3] = r < 0.2 ? -2.0f : 2.0f;
                }
            }
        }
    }
    return g;
}

Dataset make_dataset(const RadianceGrid& truth, int views, int size, double offset) {
    Dataset ds;
    ds.box = truth.box();
    for (int i = 0; i < views; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / views;
        const double az = (i * 137.508 + offset);
        const render::Camera cam =
            render::frame_box(truth.box(), az, std::asin(z) * 180.0 / std::numbers::pi, size, size);
        ds.intrinsics = intrinsics_from_camera(cam);
        View v;
        v.name = "view" + std::to_string(i);
        v.camera_to_world = pose_from_camera(cam);
        v.rgb = render_view(truth, ds.intrinsics, v.camera_to_world, ds.background);
        ds.views.push_back(std::move(v));
    }
    return ds;
}

double mean_psnr(const RadianceGrid& grid, const Dataset& ds) {
    double sum = 0.0;
    for (const View& v : ds.views) {
        sum += psnr(render_view(grid, ds.intrinsics, v.camera_to_world, ds.background), v.rgb);
    }
    return sum / static_cast<double>(ds.views.size());
}

TrainOptions tiny_options() {
    TrainOptions o;
    o.resolution = 24;
    o.stages = 2;
    o.iterations = 300;
    o.batch_rays = 512;
    return o;
}

TEST(Trainer, TinySceneConvergesOnTrainAndHeldOutViews) {
    const RadianceGrid truth = ball_field(24);
    const Dataset train_set = make_dataset(truth, 24, 24, 0.0);
    const Dataset test_set = make_dataset(truth, 6, 24, 60.0);
    double first_loss = -1.0;
    const TrainResult r = train(train_set, tiny_options(), [&](const TrainProgress& p) {
        if (first_loss < 0.0) {
            first_loss = p.loss;
        }
        return true;
    });
    EXPECT_EQ(r.iterations, 300);
    EXPECT_LT(r.final_loss, 0.05 * first_loss);
    const double train_psnr = mean_psnr(r.grid, train_set);
    const double test_psnr = mean_psnr(r.grid, test_set);
    EXPECT_GT(train_psnr, 28.0);
    EXPECT_GT(test_psnr, 26.0);
}

TEST(Trainer, IsBitwiseIdenticalForOneAndTwoThreads) {
    const RadianceGrid truth = ball_field(16);
    const Dataset ds = make_dataset(truth, 8, 16, 0.0);
    TrainOptions o = tiny_options();
    o.iterations = 40;
    o.resolution = 16;
    const auto none = [](const TrainProgress&) {
        return true;
    };
    set_num_threads(1);
    const TrainResult a = train(ds, o, none);
    set_num_threads(2);
    const TrainResult b = train(ds, o, none);
    set_num_threads(0);
    ASSERT_EQ(a.grid.params().size(), b.grid.params().size());
    EXPECT_TRUE(
        std::equal(a.grid.params().begin(), a.grid.params().end(), b.grid.params().begin()));
    EXPECT_EQ(a.final_loss, b.final_loss);
}

TEST(Trainer, StopsWhenTheCallbackSaysSo) {
    const RadianceGrid truth = ball_field(16);
    const Dataset ds = make_dataset(truth, 4, 12, 0.0);
    const TrainResult r =
        train(ds, tiny_options(), [](const TrainProgress& p) { return p.iteration < 5; });
    EXPECT_TRUE(r.stopped);
    EXPECT_EQ(r.iterations, 5);
}

TEST(Trainer, RejectsBadOptions) {
    const RadianceGrid truth = ball_field(8);
    const Dataset ds = make_dataset(truth, 2, 8, 0.0);
    TrainOptions o = tiny_options();
    o.resolution = 2;
    try {
        train(ds, o, [](const TrainProgress&) { return true; });
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("resolution 2"), std::string::npos) << e.what();
    }
}

TEST(Trainer, RefusesAGridAboveTheMemoryLimitBeforeAllocating) {
    const RadianceGrid truth = ball_field(8);
    const Dataset ds = make_dataset(truth, 2, 8, 0.0);
    TrainOptions o = tiny_options();
    o.resolution = 1024;  // 1024^3 voxels: about 134 GiB of training state
    o.max_bytes = std::size_t{1} << 30;
    EXPECT_EQ(estimated_training_bytes(ds.box.value(), o),
              TRAIN_BYTES_PER_VOXEL * std::size_t{1024} * 1024 * 1024);
    try {
        train(ds, o, [](const TrainProgress&) { return true; });
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("1024 x 1024 x 1024"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("memory limit"), std::string::npos) << e.what();
    }
    // Within the limit, the same resolution's smaller cousin trains.
    o.resolution = 24;
    o.iterations = 2;
    EXPECT_EQ(train(ds, o, [](const TrainProgress&) { return true; }).iterations, 2);
}

}  // namespace
}  // namespace pliant::nerf
