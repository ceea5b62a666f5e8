// One XPBD soft-body substep (pbd::SoftBody: edges + tet volumes, coloured, SIMD, parallel) on
// full-box tet grids of 32³ and 64³ cells (cells of 4 voxels over 128³ and 256³ volumes; 64³
// cells = 1,310,720 tets, the size), beside a naive baseline in the same binary: the same
// constraints projected one after the other in index order (sequential Gauss–Seidel), Vec3f
// positions and a separate inverse-mass array, one thread. BM_SourceScaleStep: a whole 24 fps
// frame (SoftBody::step, all substeps, drivers included) at the source system's scale (issue 29,
// source_scale_phantom.hpp: 64³ cells over the visible voxels of a 256³ rgba8 phantom) under the
// twist, wave and bubble drivers (stiffness 0.8), after 24 frames (so that the drivers have ramped
// in); twist also with fewer substeps. Counters after those 24 frames: inverted tets, volume ratio
// and the mean vertex displacement from rest (world units; the box is [−1, 1]³): fewer substeps of
// one Gauss–Seidel sweep each carry the twist less far into the body.
//
//   bin/bench_pbd [--benchmark_filter=...] [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/volume/volume.hpp"
#include "source_scale_body.hpp"
#include "source_scale_phantom.hpp"

namespace {

using namespace pliant;

const pbd::TetGrid& grid_of(int cells) {
    static std::map<int, std::unique_ptr<pbd::TetGrid>> grids;
    auto& g = grids[cells];
    if (!g) {
        const volume::Volume v = volume::Volume::allocate({4 * cells, 4 * cells, 4 * cells},
                                                          volume::VoxelType::u8, {1.0, 1.0, 1.0});
        g = std::make_unique<pbd::TetGrid>(
            pbd::build_tet_grid(v, {.cell_voxels = 4, .full_box = true}));
    }
    return *g;
}

// args: cells, threads, analytic (1) or greedy (0) colouring, widest SIMD kernels allowed (4: SSE,
// 8: AVX2 when the CPU has it; both give the same bits).
void BM_SoftBodySubstep(benchmark::State& state) {
    const int cells = static_cast<int>(state.range(0));
    set_num_threads(static_cast<int>(state.range(1)));
    pliant::allow_avx2(state.range(3) >= 8);
    const pbd::TetGrid& grid = grid_of(cells);
    pbd::SoftBody body = state.range(2) != 0 ? pbd::SoftBody(grid, {.substeps = 1})
                                             : pbd::SoftBody(grid.mesh, {.substeps = 1});
    body.add_driver(pbd::TwistDriver{.angle = 90.0, .ramp_time = 1.0});
    for (auto _ : state) {
        body.step(1.0 / 240.0);  // one substep of a 24 fps frame at 10 substeps
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(grid.mesh.num_tets()));
    state.counters["tets"] = static_cast<double>(grid.mesh.num_tets());
    state.counters["edge_colors"] = body.edge_coloring().num_colors();
    state.counters["tet_colors"] = body.tet_coloring().num_colors();
    state.counters["inverted"] = static_cast<double>(body.stats().inverted_tets);
    state.counters["lanes"] = pliant::has_avx2() ? 8 : 4;
    set_num_threads(0);
    pliant::allow_avx2(true);
}
BENCHMARK(BM_SoftBodySubstep)
    ->ArgNames({"cells", "threads", "analytic", "simd"})
    ->Args({32, 1, 1, 8})
    ->Args({32, 2, 1, 8})
    ->Args({64, 1, 1, 4})
    ->Args({64, 1, 1, 8})
    ->Args({64, 2, 1, 8})
    ->Args({64, 2, 0, 8})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The source-scale body under driver d with solver options o (source_scale_body.hpp), after 24
// frames.
pbd::SoftBody source_scale_body(int d, pbd::SoftBodyOptions o) {
    bench::DrivenBody driven = bench::source_scale_driven_body(d, o);
    for (int frame = 0; frame < 24; ++frame) {
        driven.step(frame);
    }
    return std::move(driven.body);
}

double mean_displacement(const pbd::SoftBody& body) {
    double displacement = 0.0;
    for (std::size_t v = 0; v < body.positions().size(); ++v) {
        displacement += norm(vec3_cast<double>(body.positions()[v]) -
                             vec3_cast<double>(body.rest_positions()[v]));
    }
    return displacement / static_cast<double>(std::max<std::size_t>(body.positions().size(), 1));
}

// Mean distance of the body's vertices from the 10-substep reference body's (world units).
double mean_distance(const pbd::SoftBody& a, const pbd::SoftBody& b) {
    double sum = 0.0;
    for (std::size_t v = 0; v < a.positions().size(); ++v) {
        sum += norm(vec3_cast<double>(a.positions()[v]) - vec3_cast<double>(b.positions()[v]));
    }
    return sum / static_cast<double>(std::max<std::size_t>(a.positions().size(), 1));
}

// The reference: 10 substeps of one plain sweep (today's default), per driver.
const pbd::SoftBody& reference_body(int d) {
    static std::map<int, std::unique_ptr<pbd::SoftBody>> bodies;
    auto& b = bodies[d];
    if (!b) {
        b = std::make_unique<pbd::SoftBody>(source_scale_body(d, {.substeps = 10}));
    }
    return *b;
}

// args: driver (0 twist, 1 wave, 2 bubble, 3 drag), substeps per frame, threads, iterations per
// substep, Chebyshev ρ and γ in percent (0 and 100: plain). Counters after 24 frames: inverted
// tets, volume ratio, mean displacement from rest, and (for the accelerated or reduced solvers)
// the ratio of that displacement to the 10-substep reference's and the mean distance from the
// reference's vertices.
void BM_SourceScaleStep(benchmark::State& state) {
    const pbd::TetGrid& grid = bench::source_scale_workload().grid;
    const int d = static_cast<int>(state.range(0));
    set_num_threads(static_cast<int>(state.range(2)));
    const pbd::SoftBodyOptions options{
        .substeps = static_cast<int>(state.range(1)),
        .iterations = static_cast<int>(state.range(3)),
        .chebyshev_rho = static_cast<double>(state.range(4)) / 100.0,
        .chebyshev_gamma = static_cast<double>(state.range(5)) / 100.0};
    pbd::SoftBody body = source_scale_body(d, options);
    constexpr double DT = 1.0 / 24.0;
    // The shape after 24 frames (before the timed steps): how far the deformation has reached.
    const pbd::SoftBodyStats stats = body.stats();
    const double displacement = mean_displacement(body);
    if (options.substeps != 10 || options.iterations != 1 || options.chebyshev_rho > 0.0) {
        const pbd::SoftBody& reference = reference_body(d);
        state.counters["displacement_vs_ref"] = displacement / mean_displacement(reference);
        state.counters["distance_to_ref"] = mean_distance(body, reference);
    }
    std::vector<Vec3f> before;
    for (auto _ : state) {
        state.PauseTiming();
        before.assign(body.positions().begin(), body.positions().end());
        state.ResumeTiming();
        body.step(DT);
    }
    // Vertices whose position changed (bitwise) in the last step: what dirty-brick resampling
    // could skip.
    std::int64_t moved = 0;
    for (std::size_t v = 0; v < before.size(); ++v) {
        const Vec3f& p = body.positions()[v];
        moved += p.x != before[v].x || p.y != before[v].y || p.z != before[v].z ? 1 : 0;
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(grid.mesh.num_tets()));
    state.counters["tets"] = static_cast<double>(grid.mesh.num_tets());
    state.counters["moved_fraction"] =
        static_cast<double>(moved) / static_cast<double>(std::max<std::size_t>(before.size(), 1));
    state.counters["inverted_24"] = static_cast<double>(stats.inverted_tets);
    state.counters["volume_ratio_24"] = stats.volume_ratio;
    state.counters["mean_displacement_24"] = displacement;
    set_num_threads(0);
}
BENCHMARK(BM_SourceScaleStep)
    ->ArgNames({"driver", "substeps", "threads", "iters", "rho", "gamma"})
    ->Args({0, 10, 1, 1, 0, 100})
    ->Args({0, 10, 2, 1, 0, 100})
    ->Args({1, 10, 1, 1, 0, 100})
    ->Args({1, 10, 2, 1, 0, 100})
    ->Args({2, 10, 1, 1, 0, 100})
    ->Args({2, 10, 2, 1, 0, 100})
    ->Args({3, 10, 1, 1, 0, 100})
    ->Args({3, 10, 2, 1, 0, 100})
    ->Args({0, 5, 1, 1, 0, 100})
    ->Args({0, 3, 1, 1, 0, 100})
    ->Args({0, 2, 1, 1, 0, 100})
    ->Args({0, 2, 1, 3, 0, 100})
    ->Args({0, 2, 1, 3, 97, 90})
    ->Args({0, 3, 1, 2, 90, 100})
    ->Args({0, 1, 1, 6, 97, 90})
    ->Args({0, 2, 1, 4, 0, 100})
    ->Args({0, 2, 1, 4, 97, 90})
    ->Args({0, 1, 1, 8, 0, 100})
    ->Args({0, 1, 1, 8, 99, 90})
    ->Args({0, 1, 1, 8, 99, 100})
    ->Args({0, 1, 1, 8, 98, 90})
    ->Args({0, 2, 1, 4, 98, 90})
    ->Args({0, 20, 1, 1, 0, 100})
    ->Args({1, 2, 1, 4, 97, 90})
    ->Args({2, 2, 1, 4, 97, 90})
    ->Args({3, 2, 1, 4, 97, 90})
    ->Args({0, 2, 2, 4, 97, 90})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The naive substep: predict, every edge then every tet in index order, velocities.
struct Naive {
    std::vector<Vec3f> x, previous, v;
    std::vector<float> w, rest_lengths, rest_volumes;
    std::vector<std::array<std::int32_t, 2>> edges;
    std::vector<geometry::Tet> tets;

    explicit Naive(const pbd::TetGrid& grid) : x(grid.mesh.positions), tets(grid.mesh.tets) {
        const pbd::SoftBody body(grid);  // masses and edges as the solver has them
        w.assign(body.inv_masses().begin(), body.inv_masses().end());
        edges.assign(body.edges().begin(), body.edges().end());
        previous = x;
        v.assign(x.size(), Vec3f{});
        for (const auto& e : edges) {
            rest_lengths.push_back(
                norm(x[static_cast<std::size_t>(e[0])] - x[static_cast<std::size_t>(e[1])]));
        }
        for (const auto& t : tets) {
            rest_volumes.push_back(geometry::signed_volume(
                x[static_cast<std::size_t>(t[0])], x[static_cast<std::size_t>(t[1])],
                x[static_cast<std::size_t>(t[2])], x[static_cast<std::size_t>(t[3])]));
        }
        // A little motion so that the constraints have work.
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i].x += 0.01f * std::sin(static_cast<float>(i));
        }
    }

    void substep(float h) {
        for (std::size_t i = 0; i < x.size(); ++i) {
            previous[i] = x[i];
            if (w[i] > 0.0f) {
                x[i] += v[i] * h;
            }
        }
        for (std::size_t k = 0; k < edges.size(); ++k) {
            const auto a = static_cast<std::size_t>(edges[k][0]);
            const auto b = static_cast<std::size_t>(edges[k][1]);
            const Vec3f d = x[a] - x[b];
            const float length = norm(d);
            const float ws = w[a] + w[b];
            if (!(ws > 0.0f) || !(length > 0.0f)) {
                continue;
            }
            const float dlambda = -(length - rest_lengths[k]) / (ws * 20.0f);
            const Vec3f n = d * (1.0f / length);
            x[a] += n * (w[a] * dlambda);
            x[b] -= n * (w[b] * dlambda);
        }
        for (std::size_t k = 0; k < tets.size(); ++k) {
            const auto& t = tets[k];
            Vec3f& p0 = x[static_cast<std::size_t>(t[0])];
            Vec3f& p1 = x[static_cast<std::size_t>(t[1])];
            Vec3f& p2 = x[static_cast<std::size_t>(t[2])];
            Vec3f& p3 = x[static_cast<std::size_t>(t[3])];
            const Vec3f g1 = cross(p2 - p0, p3 - p0) * (1.0f / 6.0f);
            const Vec3f g2 = cross(p3 - p0, p1 - p0) * (1.0f / 6.0f);
            const Vec3f g3 = cross(p1 - p0, p2 - p0) * (1.0f / 6.0f);
            const Vec3f g0 = -(g1 + g2 + g3);
            const float volume = dot(p1 - p0, g1);
            const float* wt[4] = {
                &w[static_cast<std::size_t>(t[0])], &w[static_cast<std::size_t>(t[1])],
                &w[static_cast<std::size_t>(t[2])], &w[static_cast<std::size_t>(t[3])]};
            const float weight = *wt[0] * squared_norm(g0) + *wt[1] * squared_norm(g1) +
                                 *wt[2] * squared_norm(g2) + *wt[3] * squared_norm(g3);
            if (!(weight > 0.0f)) {
                continue;
            }
            const float dlambda = -(volume - rest_volumes[k]) / weight;
            p0 += g0 * (*wt[0] * dlambda);
            p1 += g1 * (*wt[1] * dlambda);
            p2 += g2 * (*wt[2] * dlambda);
            p3 += g3 * (*wt[3] * dlambda);
        }
        for (std::size_t i = 0; i < x.size(); ++i) {
            v[i] = (x[i] - previous[i]) * (1.0f / h);
        }
    }
};

void BM_NaiveGaussSeidelSubstep(benchmark::State& state) {
    const pbd::TetGrid& grid = grid_of(static_cast<int>(state.range(0)));
    Naive naive(grid);
    for (auto _ : state) {
        naive.substep(1.0f / 240.0f);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(grid.mesh.num_tets()));
    state.counters["tets"] = static_cast<double>(grid.mesh.num_tets());
}
BENCHMARK(BM_NaiveGaussSeidelSubstep)
    ->ArgNames({"cells"})
    ->Arg(32)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
