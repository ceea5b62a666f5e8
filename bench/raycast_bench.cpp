// bench_raycast: RayCaster::render (pliant/render/raycast.hpp) on the issue-5 scene, the 256³
// Kak–Slaney Shepp–Logan phantom (f32, box [−1, 1]³) under the mri-brain preset at 512 × 512,
// one sample per voxel (step = spacing), the preparation (float copy, lookup table, macro cells)
// outside the timed loop:
//   - Perspective/<az>: render::frame_box(bounds, az, 20) as `pliant render --camera az,20,0`;
//   - Orthographic/<axis>: render::view_camera(bounds, axis) as `pliant render --view axis`.
// Every hardware thread (core/parallel's default); Items processed = pixels. Counters: samples
// per frame (classified samples, RayCastStats::samples). Run: bin/bench_raycast
// [--benchmark_filter=...] [--benchmark_repetitions=5]. The phantom is generated on first use
// (about 1 s). Debian's libbenchmark prints "***WARNING*** Library was built as DEBUG": that is
// how the package was built, not pliant's flags (cosmetic).
#include <benchmark/benchmark.h>

#include <memory>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"

namespace {

using namespace pliant;

constexpr int SIZE = 512;

struct Scene {
    volume::Volume phantom;
    volume::TransferFunction tf;
    std::unique_ptr<render::RayCaster> caster;
};

const Scene& scene() {
    static const std::unique_ptr<Scene> s = [] {
        auto out = std::make_unique<Scene>();
        out->phantom = volume::shepp_logan_3d({256, 256, 256});
        out->tf = volume::preset("mri-brain", out->phantom);
        render::RayCastOptions options;
        options.step = out->phantom.spacing().x;
        out->caster = std::make_unique<render::RayCaster>(out->phantom, &out->tf, options);
        return out;
    }();
    return *s;
}

// The last argument of each benchmark: 1 lets the AVX2 kernel run (when the CPU has AVX2), 0 forces
// the scalar kernel (the same image, bit for bit).
void run(benchmark::State& state, const render::Camera& camera) {
    const Scene& s = scene();
    render::Image image;
    render::RayCastStats stats;
    allow_avx2(state.range(1) != 0);
    for (auto _ : state) {
        stats = s.caster->render(camera, image);
        benchmark::DoNotOptimize(image);
    }
    allow_avx2(true);
    state.SetItemsProcessed(state.iterations() * camera.width() * camera.height());
    state.counters["samples"] = static_cast<double>(stats.samples);
}

void BM_Perspective(benchmark::State& state) {
    const Scene& s = scene();
    run(state, render::frame_box(s.phantom.bounds(), static_cast<double>(state.range(0)), 20.0,
                                 SIZE, SIZE));
}
BENCHMARK(BM_Perspective)
    ->ArgNames({"az", "simd"})
    ->ArgsProduct({{30, 75}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Orthographic(benchmark::State& state) {
    const Scene& s = scene();
    const auto axis = static_cast<render::ViewAxis>(state.range(0));
    run(state, render::view_camera(s.phantom.bounds(), axis, SIZE, SIZE));
}
BENCHMARK(BM_Orthographic)
    ->ArgNames({"axis", "simd"})
    ->ArgsProduct({{static_cast<int>(render::ViewAxis::neg_y),
                    static_cast<int>(render::ViewAxis::neg_z)},
                   {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
