// bench_resample: volume::Resampler (row spans from the face planes, slab-parallel) beside the
// naive brute force (one thread, every tet, every voxel of its bounding box tested against the
// four face planes) on the issue-6 workload: an N³ volume (the Shepp–Logan phantom, f32, or the
// RGBA test object, rgba8), a full-box pbd::TetGrid of cells of 4 voxels ((N/4)³ cells, 5 tets
// each: 1.31 M tets at N = 256), rotated rigidly by 30° about z through the box centre and
// resampled into a grid like the source. Kind 2 is the source system's scale (issue 29,
// source_scale_phantom.hpp; N = 256 only): the 256³ rgba8 phantom with a grid of 64³ cells over
// its visible voxels, twisted about z through the box centre by 0° at the bottom to 60° at the top
// (a frame of the twist driver).
//
// Items processed = target voxels. Wall time (UseRealTime). Arguments: N, threads. The brute force
// runs on one thread and checks once that its output is bitwise equal to the Resampler's (same
// kernels, same tie rule; counter `identical`). Prepare = the Resampler's constructor (visibility
// of the source, per-tet rest-footprint test), paid once per rest mesh.
// Debian's libbenchmark prints "***WARNING*** Library was built as DEBUG": that is how the
// package was built, not pliant's flags (cosmetic).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
#include "source_scale_phantom.hpp"

namespace {

using namespace pliant;
using volume::Volume;
using volume::VoxelType;

enum Kind : std::int64_t { PHANTOM = 0, RGBA = 1, SOURCE_SCALE = 2 };

struct Workload {
    Volume source;
    pbd::TetGrid grid;
    std::vector<Vec3f> deformed;
    std::unique_ptr<volume::Resampler> resampler;
};

// Cached per (kind, N); nothing random.
const Workload& workload(Kind kind, std::int64_t n) {
    static std::map<std::pair<std::int64_t, std::int64_t>, std::unique_ptr<Workload>> cache;
    std::unique_ptr<Workload>& slot = cache[{kind, n}];
    if (!slot) {
        slot = std::make_unique<Workload>();
        Workload& w = *slot;
        if (kind == SOURCE_SCALE) {
            const bench::SourceScaleWorkload& s = bench::source_scale_workload();
            w.source = s.source;
            w.grid = s.grid;
        } else {
            w.source = kind == PHANTOM ? volume::shepp_logan_3d({n, n, n})
                                       : volume::rgba_test_object({n, n, n}, VoxelType::rgba8);
            w.grid = pbd::build_tet_grid(w.source, {.cell_voxels = 4, .full_box = true});
        }
        const AABBd box = w.source.bounds();
        const Vec3d c = (box.lo + box.hi) * 0.5;
        w.deformed.resize(w.grid.mesh.positions.size());
        for (std::size_t v = 0; v < w.deformed.size(); ++v) {
            const Vec3d d = vec3_cast<double>(w.grid.mesh.positions[v]) - c;
            const double height = (d.z + (box.hi.z - box.lo.z) * 0.5) / (box.hi.z - box.lo.z);
            const double a =
                (kind == SOURCE_SCALE ? 60.0 * height : 30.0) * std::numbers::pi / 180.0;
            w.deformed[v] = vec3_cast<float>(Vec3d{std::cos(a) * d.x - std::sin(a) * d.y,
                                                   std::sin(a) * d.x + std::cos(a) * d.y, d.z} +
                                             c);
        }
        w.resampler =
            std::make_unique<volume::Resampler>(w.source, w.grid.mesh.tets, w.grid.mesh.positions);
    }
    return *slot;
}

Volume make_target(const Volume& source) {
    return Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
}

using volume::detail::frame_of;

// The naive baseline: one thread, every tet in index order, every voxel centre of its bounding
// box tested against the four face planes (the same tie rule), trilinear sample, write.
template <typename S, int C>
void brute_force(const Workload& w, Volume& target) {
    std::memset(target.bytes().data(), 0, target.size_bytes());
    const volume::detail::GridFrame tf = frame_of(target);
    const volume::detail::GridFrame sf = frame_of(w.source);
    const S* src = reinterpret_cast<const S*>(w.source.bytes().data());
    S* dst = reinterpret_cast<S*>(target.bytes().data());
    for (const geometry::Tet& tet : w.grid.mesh.tets) {
        Vec3f p[4];
        Vec3f r[4];
        for (int v = 0; v < 4; ++v) {
            p[v] = w.deformed[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
            r[v] =
                w.grid.mesh.positions[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
        }
        volume::detail::TetRaster t;
        if (!volume::detail::setup_tet(p, tet.data(), r, tf, sf, t)) {
            continue;
        }
        for (std::int64_t k = t.lo[2]; k <= t.hi[2]; ++k) {
            for (std::int64_t j = t.lo[1]; j <= t.hi[1]; ++j) {
                for (std::int64_t i = t.lo[0]; i <= t.hi[0]; ++i) {
                    if (!volume::detail::inside(t, i, j, k)) {
                        continue;
                    }
                    float s[C];
                    volume::detail::sample_trilinear<S, C>(
                        src, sf.n, volume::detail::map_coord(t.map[0], i, j, k),
                        volume::detail::map_coord(t.map[1], i, j, k),
                        volume::detail::map_coord(t.map[2], i, j, k), s);
                    S* out = dst + C * (i + tf.n[0] * (j + tf.n[1] * k));
                    for (int c = 0; c < C; ++c) {
                        out[c] = volume::detail::convert_sample<S>(s[c], 1.0f);
                    }
                }
            }
        }
    }
}

void run_brute_force(const Workload& w, Volume& target) {
    if (w.source.type() == VoxelType::f32) {
        brute_force<float, 1>(w, target);
    } else {
        brute_force<std::uint8_t, 4>(w, target);
    }
}

void set_counters(benchmark::State& state, const Workload& w, std::int64_t n) {
    state.SetItemsProcessed(state.iterations() * n * n * n);
    state.counters["tets"] = static_cast<double>(w.grid.mesh.tets.size());
    state.counters["kept_tets"] = static_cast<double>(w.resampler->kept_tets().size());
}

void BM_Resample(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    set_num_threads(static_cast<int>(state.range(2)));
    Volume target = make_target(w.source);
    volume::ResampleStats stats;
    for (auto _ : state) {
        stats = w.resampler->resample(w.deformed, target);
        benchmark::DoNotOptimize(target.bytes().data());
    }
    set_counters(state, w, n);
    state.counters["voxels_written"] = static_cast<double>(stats.num_voxels_written);
    state.counters["threads"] = num_threads();
}

void BM_BruteForce(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    Volume target = make_target(w.source);
    for (auto _ : state) {
        run_brute_force(w, target);
        benchmark::DoNotOptimize(target.bytes().data());
    }
    set_counters(state, w, n);
    // Same output as the Resampler, bit for bit?
    Volume fast = make_target(w.source);
    w.resampler->resample(w.deformed, fast);
    state.counters["identical"] =
        std::memcmp(fast.bytes().data(), target.bytes().data(), fast.size_bytes()) == 0 ? 1 : 0;
}

void BM_Prepare(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    set_num_threads(static_cast<int>(state.range(2)));
    for (auto _ : state) {
        volume::Resampler r(w.source, w.grid.mesh.tets, w.grid.mesh.positions);
        benchmark::DoNotOptimize(r.kept_tets().data());
    }
    set_counters(state, w, n);
}

// The inverse-map route of issue 29 (volume/inverse_map.hpp; not yet used by the pipeline):
// instead of resampling every voxel every frame, rasterize the rest coordinates of the deformed
// tets at every 4th voxel centre and let the ray caster sample the source through that map.
// BM_InverseMapRoute times the map's construction and reports, against the exact resample of the
// same deformation, the PSNR (premultiplied colour and alpha) of every voxel sampled through the
// map, over all voxels and over the voxels the exact resample gives alpha > 0.
// PSNR (dB, peak 255) of b against a, premultiplied (r·α, g·α, b·α, α with α in [0, 1]: what a
// ray caster composites; colour under α = 0 does not count), over all voxels or over the voxels
// where a's alpha > 0.
double psnr_rgba8(const Volume& a, const Volume& b, bool visible_only) {
    const auto* x = reinterpret_cast<const std::uint8_t*>(a.bytes().data());
    const auto* y = reinterpret_cast<const std::uint8_t*>(b.bytes().data());
    double sum = 0.0;
    std::int64_t count = 0;
    for (std::int64_t v = 0; v < a.num_voxels(); ++v) {
        if (visible_only && x[4 * v + 3] == 0) {
            continue;
        }
        const double ax = x[4 * v + 3] / 255.0;
        const double ay = y[4 * v + 3] / 255.0;
        for (int c = 0; c < 4; ++c) {
            const double wx = c < 3 ? ax : 1.0;
            const double wy = c < 3 ? ay : 1.0;
            const double d = wx * x[4 * v + c] - wy * y[4 * v + c];
            sum += d * d;
        }
        count += 4;
    }
    return count == 0 || sum == 0.0 ? 999.0 : 10.0 * std::log10(255.0 * 255.0 * count / sum);
}

void BM_InverseMapRoute(benchmark::State& state) {
    const Workload& w = workload(SOURCE_SCALE, 256);
    set_num_threads(static_cast<int>(state.range(0)));
    Volume exact = make_target(w.source);
    w.resampler->resample(w.deformed, exact);
    volume::InverseMap map;
    volume::InverseMapStats stats;
    for (auto _ : state) {
        stats = map.build(w.source, exact, w.grid.mesh.tets, w.grid.mesh.positions, w.deformed,
                          {.node_voxels = w.grid.cell_voxels});
        benchmark::DoNotOptimize(map.node_coordinates().data());
    }
    Volume through = make_target(w.source);
    volume::resample_through(map, w.source, through);
    state.counters["nodes"] = static_cast<double>(stats.num_nodes);
    state.counters["inside"] = static_cast<double>(stats.num_inside);
    state.counters["extrapolated"] = static_cast<double>(stats.num_extrapolated);
    state.counters["psnr_all_dB"] = psnr_rgba8(exact, through, false);
    state.counters["psnr_visible_dB"] = psnr_rgba8(exact, through, true);
    set_num_threads(0);
}
BENCHMARK(BM_InverseMapRoute)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Arguments: kind (0 phantom f32, 1 RGBA rgba8, 2 source scale rgba8), N, threads.
void resample_args(benchmark::internal::Benchmark* b) {
    b->ArgNames({"rgba", "N", "threads"});
    for (const std::int64_t kind : {PHANTOM, RGBA}) {
        for (const std::int64_t n : {128, 256}) {
            for (const std::int64_t threads : {1, 2}) {
                b->Args({kind, n, threads});
            }
        }
    }
    for (const std::int64_t threads : {1, 2}) {
        b->Args({SOURCE_SCALE, 256, threads});
    }
}

void brute_force_args(benchmark::internal::Benchmark* b) {
    b->ArgNames({"rgba", "N"});
    for (const std::int64_t kind : {PHANTOM, RGBA}) {
        for (const std::int64_t n : {128, 256}) {
            b->Args({kind, n});
        }
    }
    b->Args({SOURCE_SCALE, 256});
}

BENCHMARK(BM_Resample)->Apply(resample_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BruteForce)
    ->Apply(brute_force_args)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);
BENCHMARK(BM_Prepare)->Apply(resample_args)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
