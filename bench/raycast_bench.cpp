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

// The source system's scale (issue 29): the phantom classified by mri-brain into an RGBA volume
// (256³ rgba32f, opacity per smallest spacing), the default step (half a voxel, as `pliant deform
// --render`), perspective at 30°, 512²; shading off / on. And the dense transfer function of
// issue 29 (`grayscale`: every voxel of the phantom seen) at one sample per voxel, and the
// scalar phantom shaded and as a MIP. The preparation is timed apart: counter prepare_ms.
struct RgbaScene {
    volume::Volume rgba;
    std::unique_ptr<render::RayCaster> casters[2];  // shading off, on
};

const RgbaScene& rgba_scene() {
    static const std::unique_ptr<RgbaScene> s = [] {
        auto out = std::make_unique<RgbaScene>();
        const Scene& scalar = scene();
        out->rgba = volume::apply(scalar.phantom, scalar.tf);
        for (int shade = 0; shade < 2; ++shade) {
            render::RayCastOptions options;
            options.shading = shade != 0;
            out->casters[shade] = std::make_unique<render::RayCaster>(out->rgba, nullptr, options);
        }
        return out;
    }();
    return *s;
}

void run_caster(benchmark::State& state, const render::RayCaster& caster,
                const render::Camera& camera, bool simd) {
    render::Image image;
    render::RayCastStats stats;
    allow_avx2(simd);
    for (auto _ : state) {
        stats = caster.render(camera, image);
        benchmark::DoNotOptimize(image);
    }
    allow_avx2(true);
    state.SetItemsProcessed(state.iterations() * camera.width() * camera.height());
    state.counters["samples"] = static_cast<double>(stats.samples);
    state.counters["prepare_ms"] = caster.prepare_ms();
}

void BM_Rgba(benchmark::State& state) {
    const RgbaScene& s = rgba_scene();
    const render::RayCaster& caster = *s.casters[state.range(0) != 0 ? 1 : 0];
    run_caster(state, caster, render::frame_box(s.rgba.bounds(), 30.0, 20.0, SIZE, SIZE),
               state.range(1) != 0);
}
BENCHMARK(BM_Rgba)
    ->ArgNames({"shade", "simd"})
    ->ArgsProduct({{0, 1}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// kind 0: dense (grayscale, step = spacing); 1: mri-brain shaded; 2: mri-brain MIP.
void BM_ScalarKind(benchmark::State& state) {
    const Scene& s = scene();
    static const std::unique_ptr<render::RayCaster> casters[3] = {
        [] {
            static const volume::TransferFunction grey =
                volume::preset("grayscale", scene().phantom);
            render::RayCastOptions o;
            o.step = scene().phantom.spacing().x;
            return std::make_unique<render::RayCaster>(scene().phantom, &grey, o);
        }(),
        [] {
            render::RayCastOptions o;
            o.step = scene().phantom.spacing().x;
            o.shading = true;
            return std::make_unique<render::RayCaster>(scene().phantom, &scene().tf, o);
        }(),
        [] {
            render::RayCastOptions o;
            o.step = scene().phantom.spacing().x;
            o.mode = render::RayCastMode::mip;
            return std::make_unique<render::RayCaster>(scene().phantom, &scene().tf, o);
        }(),
    };
    run_caster(state, *casters[state.range(0)],
               render::frame_box(s.phantom.bounds(), 30.0, 20.0, SIZE, SIZE), state.range(1) != 0);
}
BENCHMARK(BM_ScalarKind)
    ->ArgNames({"kind", "simd"})
    ->ArgsProduct({{0, 1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The preparation of a 256³ RGBA caster (float copy, α apart when shaded, macro cells, empty
// cubes), paid once per volume: every frame where the volume changes (`pliant deform --render`).
// reuse 0: a new RayCaster per frame; 1: RayCaster::update of one caster (no allocation).
void BM_RgbaPrepare(benchmark::State& state) {
    const RgbaScene& s = rgba_scene();
    render::RayCastOptions options;
    options.shading = state.range(0) != 0;
    render::RayCaster reused(s.rgba, nullptr, options);
    for (auto _ : state) {
        if (state.range(1) != 0) {
            reused.update(s.rgba, nullptr);
            benchmark::DoNotOptimize(reused.num_cells());
        } else {
            const render::RayCaster caster(s.rgba, nullptr, options);
            benchmark::DoNotOptimize(caster.num_cells());
        }
    }
}
BENCHMARK(BM_RgbaPrepare)
    ->ArgNames({"shade", "reuse"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
