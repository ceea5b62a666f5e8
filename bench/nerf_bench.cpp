// bench_nerf: radiance-field training (nerf::train, pliant/nerf/trainer.hpp) with its
// empty-space skipping beside the same training sampling every step densely (the brute force:
// FieldRenderOptions::use_occupancy = false, in training and in the held-out renders).
//
// Scene: the 128³ Kak–Slaney Shepp–Logan phantom under the mri-brain preset, ray-cast
// (render::RayCaster, as `pliant dataset` does) from 40 views of 100 × 100 on a Fibonacci sphere;
// every 10th view is held out. One benchmark iteration trains from a blank grid for a fixed
// number of iterations (coarse to fine in 2 stages up to the resolution argument, 4096 rays per
// iteration): the schedule does not depend on the machine's speed, so both contestants do the
// same work and reach comparable quality. Counters: ms per training iteration, samples per ray
// (mean over the run), held-out PSNR (dB) of the trained field. Every hardware thread.
//
// Run: bin/bench_nerf [--benchmark_filter=...] [--benchmark_repetitions=3]. Debian's libbenchmark
// prints "***WARNING*** Library was built as DEBUG": how the package was built, not pliant's
// flags.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "pliant/core/timer.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/render.hpp"
#include "pliant/nerf/trainer.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"

namespace {

using namespace pliant;

constexpr int VIEWS = 40;
constexpr int SIZE = 100;
constexpr int TEST_EVERY = 10;
constexpr std::int64_t ITERATIONS = 400;

struct Scene {
    nerf::Dataset train;
    nerf::Dataset test;
};

const Scene& scene() {
    static const std::unique_ptr<Scene> s = [] {
        auto out = std::make_unique<Scene>();
        const volume::Volume phantom = volume::shepp_logan_3d({128, 128, 128});
        const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
        const render::RayCaster caster(phantom, &tf, render::RayCastOptions{});
        const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
        render::Image image;
        for (int i = 0; i < VIEWS; ++i) {
            const double z = 1.0 - (2.0 * i + 1.0) / VIEWS;
            const render::Camera camera = render::frame_box(
                phantom.bounds(),
                std::fmod(i * golden, 2.0 * std::numbers::pi) * 180.0 / std::numbers::pi,
                std::asin(z) * 180.0 / std::numbers::pi, SIZE, SIZE);
            caster.render(camera, image);
            nerf::Dataset& split = i % TEST_EVERY == 0 ? out->test : out->train;
            split.intrinsics = nerf::intrinsics_from_camera(camera);
            split.box = phantom.bounds();
            split.views.push_back({"view" + std::to_string(i), nerf::pose_from_camera(camera),
                                   nerf::from_image(image)});
        }
        return out;
    }();
    return *s;
}

// range(0): final resolution; range(1): 1 = empty-space skipping, 0 = dense sampling.
void BM_Train(benchmark::State& state) {
    const Scene& s = scene();
    nerf::TrainOptions options;
    options.resolution = static_cast<int>(state.range(0));
    options.stages = 2;
    options.iterations = ITERATIONS;
    options.render.use_occupancy = state.range(1) != 0;
    double samples = 0.0;
    double psnr = 0.0;
    double train_ms = 0.0;
    for (auto _ : state) {
        samples = 0.0;
        const Stopwatch watch;
        const nerf::TrainResult result =
            nerf::train(s.train, options, [&](const nerf::TrainProgress& p) {
                samples += static_cast<double>(p.samples);
                return true;
            });
        train_ms = watch.elapsed_ms();
        state.PauseTiming();
        nerf::FieldRenderOptions render_options;
        render_options.use_occupancy = options.render.use_occupancy;
        psnr = 0.0;
        for (const nerf::View& v : s.test.views) {
            psnr += nerf::psnr(nerf::render_view(result.grid, s.test.intrinsics, v.camera_to_world,
                                                 s.test.background, render_options),
                               v.rgb);
        }
        psnr /= static_cast<double>(s.test.views.size());
        state.ResumeTiming();
    }
    state.SetLabel(state.range(1) != 0 ? "skipping" : "dense (brute force)");
    state.counters["ms_per_iteration"] = train_ms / static_cast<double>(ITERATIONS);
    state.counters["samples_per_ray"] =
        samples / (static_cast<double>(ITERATIONS) * options.batch_rays);
    state.counters["held_out_psnr"] = psnr;
}
BENCHMARK(BM_Train)
    ->Args({64, 1})
    ->Args({64, 0})
    ->Args({128, 1})
    ->Args({128, 0})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
