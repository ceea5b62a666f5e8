// bench_cloth: the cloth solver's stretch constraints, single edges (Gauss-Seidel, one sweep per
// substep) beside chains solved as a whole (material.stretch_solver, cloth/stretch_chains.hpp),
// on the drape scene's grid (2 m, 134 × 134 quads, 35,912 triangles) hanging from its top edge
// for one second (24 frames) at 10, 20 and 40 substeps per frame: time for the 24 frames (and
// frames per second, a counter) and the strain the sheet is left with (edge length / rest length
// − 1: p99 and max over the edges, counters).
// The sheet hangs in the x-z plane; no obstacles, no self-collision.
// BM_SceneSolver: the XPBD solver alone (self-collision off, the scene's other keys) on the
// built-in scenes' first frames (scenes/NAME.json): the drape's 12 frames of free fall and first
// contact with the sphere, the flag's 24 frames in gusty wind; wall time for those frames.
//   bin/bench_cloth [--benchmark_filter=...]     (PLIANT_THREADS=N limits the threads)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_setup.hpp"

namespace {

using namespace pliant;

struct HangingSheet {
    geometry::TriangleMeshD mesh;
    std::vector<std::int32_t> top;
    std::vector<geometry::Edge> edges;  // for the strain
    std::vector<double> rest_lengths;
};

const HangingSheet& hanging_sheet() {
    static const HangingSheet sheet = [] {
        HangingSheet s;
        s.mesh =
            geometry::convert_precision<double>(geometry::make_grid_sheet(134, 134, 2.0f, 2.0f));
        for (std::size_t v = 0; v < s.mesh.positions.size(); ++v) {
            Vec3d& p = s.mesh.positions[v];
            p = {p.x, 0.0, 1.0 + p.y};  // stand it up: y becomes height
            if (p.z == 2.0) {
                s.top.push_back(static_cast<std::int32_t>(v));
            }
        }
        s.edges = geometry::build_topology(s.mesh.triangles, s.mesh.positions.size()).edges;
        for (const geometry::Edge& e : s.edges) {
            s.rest_lengths.push_back(norm(s.mesh.positions[static_cast<std::size_t>(e[0])] -
                                          s.mesh.positions[static_cast<std::size_t>(e[1])]));
        }
        return s;
    }();
    return sheet;
}

void set_threads_from_environment() {
    if (const char* threads = std::getenv("PLIANT_THREADS")) {
        set_num_threads(std::atoi(threads));
    }
}

// Args: stretch solver (0 edges, 1 chains), substeps per frame.
void BM_HangingSheet(benchmark::State& state) {
    set_threads_from_environment();
    const HangingSheet& sheet = hanging_sheet();
    cloth::ClothMaterial material;
    material.stretch_solver =
        state.range(0) == 0 ? cloth::StretchSolver::edges : cloth::StretchSolver::chains;
    const int substeps = static_cast<int>(state.range(1));
    const int frames = 24;
    std::vector<double> strains;
    for (auto _ : state) {
        state.PauseTiming();
        cloth::ClothSolver solver(sheet.mesh, material, sheet.top);
        state.ResumeTiming();
        for (int f = 0; f < frames; ++f) {
            solver.step(1.0 / 24.0, substeps);
        }
        state.PauseTiming();
        strains.clear();
        for (std::size_t i = 0; i < sheet.edges.size(); ++i) {
            const auto a = static_cast<std::size_t>(sheet.edges[i][0]);
            const auto b = static_cast<std::size_t>(sheet.edges[i][1]);
            strains.push_back(
                norm(solver.positions()[a] - solver.positions()[b]) / sheet.rest_lengths[i] - 1.0);
        }
        std::sort(strains.begin(), strains.end());
        state.ResumeTiming();
    }
    // Frames per second of wall time (the time column is for the 24 frames).
    state.counters["frames_per_second"] =
        benchmark::Counter(frames, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["strain_p99"] = strains[strains.size() * 99 / 100];
    state.counters["strain_max"] = strains.back();
    state.SetLabel(state.range(0) == 0 ? "edges" : "chains");
}
BENCHMARK(BM_HangingSheet)
    ->ArgsProduct({{0, 1}, {10, 20, 40}})
    ->ArgNames({"chains", "substeps"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

// Arg: 0 the drape (12 frames), 1 the flag (24 frames).
void BM_SceneSolver(benchmark::State& state) {
    set_threads_from_environment();
    const bool drape = state.range(0) == 0;
    const std::string name = drape ? "drape" : "flag";
    cloth::ClothScene scene =
        pipeline::read_cloth_scene(std::string(PLIANT_SOURCE_DIR) + "/scenes/" + name + ".json");
    scene.self_collision = false;
    const pipeline::ClothSetup setup = pipeline::load_cloth_setup(scene, name);
    const int frames = drape ? 12 : 24;
    for (auto _ : state) {
        state.PauseTiming();
        const std::unique_ptr<cloth::ClothSolver> solver = pipeline::make_solver(scene, setup);
        state.ResumeTiming();
        for (int f = 0; f < frames; ++f) {
            solver->step(1.0 / scene.frames_per_second, scene.substeps);
        }
    }
    state.counters["ms_per_frame"] = benchmark::Counter(
        frames * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
    state.SetLabel(name);
}
BENCHMARK(BM_SceneSolver)
    ->Arg(0)
    ->Arg(1)
    ->ArgNames({"scene"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

}  // namespace
