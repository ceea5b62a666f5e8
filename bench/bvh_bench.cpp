// bench_bvh: pliant's LBVH beside Embree 3 and a brute force, Google Benchmark style — build,
// refit and self-collision traversal on the BVH table's workload (peers/bvh_workload.hpp: folded
// square sheets nearest to 2,244 / 27,030 / 35,992 / 250,000 / 1,000,000 triangles), the brute
// force at the three small sizes only.
//
// Each benchmark measures one stage, as `pliant bench bvh` does (peers/bvh_table.hpp): build on
// the step-0 boxes, refit to the step-1 boxes (alternating with step 0 so every refit moves the
// boxes), traversal of the refitted structure counting non-adjacent overlapping pairs. Items
// processed = triangles. Wall time (UseRealTime): the stages run on several threads.
// Threads: all hardware threads, or PLIANT_THREADS=N in the environment.
// Debian's libbenchmark prints "***WARNING*** Library was built as DEBUG": that is how the
// package was built, not pliant's flags, and does not affect the timed code (cosmetic).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "peers/bvh_workload.hpp"
#include "peers/embree_collide.hpp"
#include "peers/self_pairs.hpp"
#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/parallel.hpp"

namespace {

using pliant::AABB;
using pliant::bench::BvhWorkload;
using pliant::bench::EmbreeSelfCollider;

struct Prepared {
    BvhWorkload workload;
    std::vector<AABB> boxes0;
    std::vector<AABB> boxes1;
};

// Workloads are deterministic (no seed needed) and cached per size across benchmarks.
const Prepared& prepared(std::int64_t triangles) {
    static std::map<std::int64_t, std::unique_ptr<Prepared>> cache;
    std::unique_ptr<Prepared>& slot = cache[triangles];
    if (!slot) {
        slot = std::make_unique<Prepared>();
        slot->workload = BvhWorkload::make(triangles);
        slot->boxes0 = slot->workload.boxes(0);
        slot->boxes1 = slot->workload.boxes(1);
    }
    return *slot;
}

int configure_threads() {
    const char* env = std::getenv("PLIANT_THREADS");
    pliant::set_num_threads(env != nullptr ? std::atoi(env) : 0);
    return pliant::num_threads();
}

const int THREADS = configure_threads();

const bool CONTEXT_ADDED = [] {
    benchmark::AddCustomContext("pliant_threads", std::to_string(THREADS));
    benchmark::AddCustomContext("pliant_embree", pliant::bench::embree_available()
                                                     ? pliant::bench::embree_version()
                                                     : "not available");
    benchmark::AddCustomContext(
        "pliant_workload",
        "1 m square sheet folded into 8 panels, layers 1.5 e apart, boxes inflated 0.25 e, "
        "travelling wave 0.1 e");
    benchmark::AddCustomContext(
        "pliant_note",
        "the 'Library was built as DEBUG' warning comes from Debian's libbenchmark package and is "
        "cosmetic; pliant and its peers are built in the build type you chose");
    return true;
}();

void set_items(benchmark::State& state, const Prepared& p) {
    state.SetItemsProcessed(state.iterations() *
                            static_cast<std::int64_t>(p.workload.num_triangles()));
    state.counters["triangles"] = static_cast<double>(p.workload.num_triangles());
}

void BM_PliantBuild(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    pliant::bvh::LBVH tree;
    for (auto _ : state) {
        tree.build(p.boxes0);
        benchmark::ClobberMemory();
    }
    set_items(state, p);
}

void BM_PliantRefit(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    pliant::bvh::LBVH tree;
    tree.build(p.boxes0);
    bool odd = false;
    for (auto _ : state) {
        tree.refit(odd ? p.boxes0 : p.boxes1);
        odd = !odd;
        benchmark::ClobberMemory();
    }
    set_items(state, p);
}

void BM_PliantTraverse(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    pliant::bvh::LBVH tree;
    tree.build(p.boxes0);
    tree.refit(p.boxes1);
    std::int64_t pairs = 0;
    for (auto _ : state) {
        pairs = pliant::bench::count_self_pairs(tree, p.workload.triangles());
        benchmark::DoNotOptimize(pairs);
    }
    set_items(state, p);
    state.counters["pairs"] = static_cast<double>(pairs);
}

void BM_BruteForce(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    std::int64_t pairs = 0;
    for (auto _ : state) {
        pairs = pliant::bench::brute_force_self_pairs(p.boxes1, p.workload.triangles());
        benchmark::DoNotOptimize(pairs);
    }
    set_items(state, p);
    state.counters["pairs"] = static_cast<double>(pairs);
}

// Without Embree (PLIANT_HAS_EMBREE = 0) its benchmarks are not compiled.
#if PLIANT_HAS_EMBREE
void BM_EmbreeBuild(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    EmbreeSelfCollider embree(THREADS);
    embree.build(p.boxes0);
    for (auto _ : state) {
        benchmark::DoNotOptimize(embree.build(p.boxes0));
    }
    set_items(state, p);
}

void BM_EmbreeRefit(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    EmbreeSelfCollider embree(THREADS);
    embree.refit(p.boxes0);  // the first commit builds
    bool odd = false;
    for (auto _ : state) {
        benchmark::DoNotOptimize(embree.refit(odd ? p.boxes0 : p.boxes1));
        odd = !odd;
    }
    set_items(state, p);
}

void BM_EmbreeCollide(benchmark::State& state) {
    const Prepared& p = prepared(state.range(0));
    EmbreeSelfCollider embree(THREADS);
    embree.refit(p.boxes0);
    embree.refit(p.boxes1);
    std::int64_t pairs = 0;
    for (auto _ : state) {
        pairs = embree.collide(EmbreeSelfCollider::Scene::refitted, p.workload.triangles()).pairs;
        benchmark::DoNotOptimize(pairs);
    }
    set_items(state, p);
    state.counters["pairs"] = static_cast<double>(pairs);
}

#endif  // PLIANT_HAS_EMBREE

void all_sizes(benchmark::internal::Benchmark* b) {
    for (const std::int64_t size : {2244, 27030, 35992, 250000, 1000000}) {
        b->Arg(size);
    }
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

void small_sizes(benchmark::internal::Benchmark* b) {
    for (const std::int64_t size : {2244, 27030, 35992}) {
        b->Arg(size);
    }
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_PliantBuild)->Apply(all_sizes);
#if PLIANT_HAS_EMBREE
BENCHMARK(BM_EmbreeBuild)->Apply(all_sizes);
#endif
BENCHMARK(BM_PliantRefit)->Apply(all_sizes);
#if PLIANT_HAS_EMBREE
BENCHMARK(BM_EmbreeRefit)->Apply(all_sizes);
#endif
BENCHMARK(BM_PliantTraverse)->Apply(all_sizes);
#if PLIANT_HAS_EMBREE
BENCHMARK(BM_EmbreeCollide)->Apply(all_sizes);
#endif
BENCHMARK(BM_BruteForce)->Apply(small_sizes);

}  // namespace
