// The paper's BVH table (its Tables 1–3: build, refit, self-collision traversal at 2,244, 27,030
// and 35,992 triangles), measured on this machine for pliant's LBVH, Embree 3 and an O(n²)
// brute force, with the paper's own GPU and CPU figures printed beside.
//
// Workload: bvh_workload.hpp (folded square sheet nearest to each requested size, boxes
// inflated by e/4). Per row and repetition, all on one set of boxes per step:
//   build    pliant LBVH::build(boxes at step 0) on one LBVH per row (buffers reused, as in a
//            simulation that rebuilds every step) | Embree commit of its existing `built` scene
//            (a full rebuild, RTC_BUILD_QUALITY_LOW);
//   refit    pliant LBVH::refit(boxes at step 1) | Embree commit of the `refitted` scene
//            (RTC_BUILD_QUALITY_REFIT) from step-0 to step-1 boxes;
//   traverse pliant count_self_pairs on the refitted tree | rtcCollide on the refitted scene,
//            both counting non-adjacent overlapping pairs (self_pairs.hpp);
//   brute    brute_force_self_pairs on the step-1 boxes, once per row, rows ≤ brute_force_limit.
// One warm-up repetition, then `repeats` timed ones; each time is the median. Pair counts must
// agree — pliant = Embree = brute force at step 1, pliant = Embree at step 0 (after build), and
// Embree's mirrored reports equal its pairs — or the row records an error (never thrown: the
// table is still printed; the caller decides).
//
// run_bvh_table sets pliant's thread limit to options.threads for the whole process
// (set_num_threads) and gives Embree the same count. Memory: LBVH::memory_bytes(), Embree's
// peak as reported by its memory monitor, and the process's peak RSS (getrusage) after each row.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "peers/bvh_workload.hpp"

namespace pliant::bench {

// One row of the paper's tables, all times in ms. The paper prints its refit times with the unit
// "us"; beside its build and traversal times they only make sense as ms, and they are taken as ms.
struct PaperFigures {
    std::int64_t triangles = 0;
    double gpu_build_ms = 0.0, gpu_refit_ms = 0.0, gpu_traverse_ms = 0.0;
    double cpu_build_ms = 0.0, cpu_refit_ms = 0.0, cpu_traverse_ms = 0.0;
};

// The paper's figures for a triangle count it reported (2,244, 27,030, 35,992), else nullopt.
std::optional<PaperFigures> paper_figures(std::int64_t triangles);

struct BvhTableOptions {
    // Requested triangle counts; each row uses the nearest square sheet.
    std::vector<std::int64_t> sizes = {2244, 27030, 35992, 250000, 1000000};
    int repeats = 5;                         // timed repetitions per row (≥ 1), after one warm-up
    int threads = 0;                         // worker threads, 0 = all hardware threads
    bool include_embree = true;              // ignored when Embree is not available
    bool include_brute_force = true;         // O(n²), only rows up to brute_force_limit
    std::int64_t brute_force_limit = 40000;  // triangles
    BvhWorkloadOptions workload;
    // Called before each row with a short message (for progress on a terminal); may be empty.
    std::function<void(const std::string&)> progress;
};

struct StageTimes {
    double build_ms = 0.0;  // medians
    double refit_ms = 0.0;
    double traverse_ms = 0.0;
};

struct PliantRow {
    StageTimes times;
    std::int64_t pairs = 0;         // at step 1, on the refitted tree
    std::int64_t pairs_built = 0;   // at step 0, on the freshly built tree
    std::int64_t memory_bytes = 0;  // LBVH::memory_bytes()
};

struct EmbreeRow {
    StageTimes times;
    std::int64_t pairs = 0;           // at step 1, on the refitted scene
    std::int64_t pairs_built = 0;     // at step 0, on the built scene
    std::int64_t mirrored_pairs = 0;  // from the (b, a) reports; must equal pairs
    std::int64_t reported = 0;        // ordered candidates rtcCollide reported (step 1)
    std::int64_t peak_memory_bytes = 0;
};

struct BruteForceRow {
    double ms = 0.0;  // one run
    std::int64_t pairs = 0;
};

struct BvhTableRow {
    std::int64_t requested_triangles = 0;
    std::int64_t triangles = 0;
    int quads_per_side = 0;
    float edge_length = 0.0f;  // m
    std::int64_t pairs = 0;    // pliant's count at step 1 (the row's reported pair count)
    PliantRow pliant;
    std::optional<EmbreeRow> embree;
    std::optional<BruteForceRow> brute_force;
    std::optional<PaperFigures> paper;
    std::int64_t peak_rss_bytes = 0;  // process peak resident set after this row
    std::vector<std::string> errors;  // pair count mismatches
};

struct BvhTableResult {
    BvhTableOptions options;
    int threads = 0;  // effective
    int hardware_threads = 0;
    std::string embree_version;  // empty when Embree was not run
    std::vector<BvhTableRow> rows;

    bool ok() const;
    std::vector<std::string> errors() const;  // every row's errors, prefixed with its size
};

// Runs the table. Throws InvalidInput for an empty size list, sizes < 2 or > 2·16384²,
// repeats < 1 or threads < 0.
BvhTableResult run_bvh_table(const BvhTableOptions& options);

// The human form: a workload summary and the three tables, aligned, with footnotes.
std::string format_bvh_table(const BvhTableResult& result);

// The JSON form: the same numbers (times in ms, memory in bytes).
nlohmann::json bvh_table_json(const BvhTableResult& result);

}  // namespace pliant::bench
