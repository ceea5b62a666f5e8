// bench_ccd: pliant's conservative CCD (pliant/collision/ccd.hpp, default options) beside the plain
// floating-point coplanarity cubic (peers/cubic_ccd.hpp), over the query sets with ground truth:
//   - Sample-Queries: PLIANT_SHARED_DATA_DIR/ccd-queries/<set>/{vertex-face,edge-edge}/*.csv,
//     one benchmark per set and kind, all files of the kind together;
//   - cloth-funnel: PLIANT_SHARED_DATA_DIR/cloth-funnel/queries/227{vf,ee}.csv, truth from
//     mma_bool/227{vf,ee}_mma_bool.json.
// Each iteration runs every query of the set once, on one thread. Items processed = queries, so
// items_per_second is queries per second. Counters: queries, hits, false_negatives (truth 1,
// reported 0: a missed contact) and false_positives (truth 0, reported 1) against the ground
// truth; for pliant also boxes_mean / boxes_max (evaluated boxes per query) and iteration_limit
// (queries that stopped at max_iterations), measured outside the timed loop. When the data
// directory is absent (a user's own clone) a single benchmark reports the skip with SkipWithError.
// Debian's libbenchmark prints "***WARNING*** Library was built as DEBUG": that is how the
// package was built, not pliant's flags, and does not affect the timed code (cosmetic).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "peers/cubic_ccd.hpp"
#include "pliant/collision/ccd.hpp"
#include "pliant/io/ccd_queries.hpp"

namespace {

namespace fs = std::filesystem;
using pliant::io::CcdQuery;
using pliant::io::CcdQueryKind;

const fs::path DATA_DIR = fs::path(PLIANT_SHARED_DATA_DIR);

// A benchmarked set: where its queries come from, loaded on first use.
struct SetSource {
    std::string name;
    CcdQueryKind kind = CcdQueryKind::vertex_face;
    std::vector<fs::path> csv_files;
    fs::path truth_json;  // empty: the truth column of the CSV files
};

struct LoadedSet {
    std::vector<CcdQuery> queries;
    std::string error;  // non-empty: loading failed, the benchmark skips with this message
};

// Loads (once per set, cached) the queries and their truth; every query must have a truth.
const LoadedSet& load(const SetSource& source) {
    static std::map<std::string, std::unique_ptr<LoadedSet>> cache;
    std::unique_ptr<LoadedSet>& slot = cache[source.name];
    if (slot) {
        return *slot;
    }
    slot = std::make_unique<LoadedSet>();
    try {
        for (const fs::path& csv : source.csv_files) {
            pliant::io::CcdQuerySet set = pliant::io::read_ccd_queries(csv, source.kind);
            slot->queries.insert(slot->queries.end(), set.queries.begin(), set.queries.end());
        }
        if (!source.truth_json.empty()) {
            const std::vector<bool> truth = pliant::io::read_mathematica_bools(source.truth_json);
            if (truth.size() != slot->queries.size()) {
                slot->error = source.truth_json.string() + ": " + std::to_string(truth.size()) +
                              " booleans for " + std::to_string(slot->queries.size()) + " queries";
                return *slot;
            }
            for (std::size_t i = 0; i < truth.size(); ++i) {
                slot->queries[i].truth = truth[i] ? 1 : 0;
            }
        }
        const bool all_known = std::all_of(slot->queries.begin(), slot->queries.end(),
                                           [](const CcdQuery& q) { return q.truth >= 0; });
        if (!all_known) {
            slot->error = source.name + ": some queries have no ground truth";
        } else if (slot->queries.empty()) {
            slot->error = source.name + ": no queries";
        }
    } catch (const std::exception& e) {
        slot->error = e.what();
    }
    return *slot;
}

bool pliant_ccd(CcdQueryKind kind, const CcdQuery& q) {
    const auto& p = q.points;
    const pliant::collision::CcdResult r =
        kind == CcdQueryKind::vertex_face
            ? pliant::collision::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7])
            : pliant::collision::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]);
    return r.hit;
}

bool cubic_ccd(CcdQueryKind kind, const CcdQuery& q) {
    const auto& p = q.points;
    double toi = 1.0;
    return kind == CcdQueryKind::vertex_face
               ? pliant::bench::cubic_vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6],
                                                      p[7], toi)
               : pliant::bench::cubic_edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7],
                                                    toi);
}

// Runs `method` over every query of the set per iteration; counts against the truth.
template <bool (*Method)(CcdQueryKind, const CcdQuery&)>
void run_set(benchmark::State& state, const SetSource& source) {
    const LoadedSet& set = load(source);
    if (!set.error.empty()) {
        state.SkipWithError(set.error.c_str());
        return;
    }
    std::int64_t hits = 0;
    std::int64_t false_negatives = 0;
    std::int64_t false_positives = 0;
    for (auto _ : state) {
        hits = 0;
        false_negatives = 0;
        false_positives = 0;
        for (const CcdQuery& q : set.queries) {
            const bool hit = Method(source.kind, q);
            hits += hit ? 1 : 0;
            false_negatives += (!hit && q.truth == 1) ? 1 : 0;
            false_positives += (hit && q.truth == 0) ? 1 : 0;
        }
        benchmark::DoNotOptimize(hits);
    }
    const auto queries = static_cast<std::int64_t>(set.queries.size());
    state.SetItemsProcessed(state.iterations() * queries);
    state.counters["queries"] = static_cast<double>(queries);
    state.counters["hits"] = static_cast<double>(hits);
    state.counters["false_negatives"] = static_cast<double>(false_negatives);
    state.counters["false_positives"] = static_cast<double>(false_positives);
}

// pliant's search statistics over the set, outside the timed loop: the largest and mean number of
// evaluated boxes per query and the queries that stopped at max_iterations.
void add_pliant_search_counters(benchmark::State& state, const SetSource& source) {
    const LoadedSet& set = load(source);
    if (!set.error.empty() || set.queries.empty()) {
        return;
    }
    std::int64_t total = 0;
    std::int64_t largest = 0;
    std::int64_t at_limit = 0;
    for (const CcdQuery& q : set.queries) {
        const auto& p = q.points;
        const pliant::collision::CcdResult r =
            source.kind == CcdQueryKind::vertex_face
                ? pliant::collision::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7])
                : pliant::collision::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]);
        total += r.iterations;
        largest = std::max<std::int64_t>(largest, r.iterations);
        at_limit += r.hit_iteration_limit ? 1 : 0;
    }
    state.counters["boxes_mean"] =
        static_cast<double>(total) / static_cast<double>(set.queries.size());
    state.counters["boxes_max"] = static_cast<double>(largest);
    state.counters["iteration_limit"] = static_cast<double>(at_limit);
}

// The sets present under DATA_DIR, in a fixed order: Sample-Queries sets sorted by name, then the
// cloth funnel. Missing kinds or files are left out.
std::vector<SetSource> discover_sets() {
    std::vector<SetSource> sets;
    const std::pair<const char*, CcdQueryKind> kinds[] = {
        {"vertex-face", CcdQueryKind::vertex_face}, {"edge-edge", CcdQueryKind::edge_edge}};
    std::error_code ec;
    const fs::path queries_dir = DATA_DIR / "ccd-queries";
    if (fs::is_directory(queries_dir, ec)) {
        std::vector<fs::path> set_dirs;
        for (const fs::directory_entry& entry : fs::directory_iterator(queries_dir, ec)) {
            if (entry.is_directory(ec)) {
                set_dirs.push_back(entry.path());
            }
        }
        std::sort(set_dirs.begin(), set_dirs.end());
        for (const fs::path& dir : set_dirs) {
            for (const auto& [kind_dir, kind] : kinds) {
                if (!fs::is_directory(dir / kind_dir, ec)) {
                    continue;
                }
                SetSource source;
                source.name = dir.filename().string() + "/" + kind_dir;
                source.kind = kind;
                try {
                    source.csv_files = pliant::io::find_ccd_query_files(dir / kind_dir);
                } catch (const std::exception&) {
                    continue;
                }
                if (!source.csv_files.empty()) {
                    sets.push_back(std::move(source));
                }
            }
        }
    }
    const fs::path funnel = DATA_DIR / "cloth-funnel";
    const std::pair<const char*, CcdQueryKind> funnel_kinds[] = {{"vf", CcdQueryKind::vertex_face},
                                                                 {"ee", CcdQueryKind::edge_edge}};
    for (const auto& [suffix, kind] : funnel_kinds) {
        const std::string stem = std::string("227") + suffix;
        const fs::path csv = funnel / "queries" / (stem + ".csv");
        const fs::path json = funnel / "mma_bool" / (stem + "_mma_bool.json");
        if (fs::is_regular_file(csv, ec) && fs::is_regular_file(json, ec)) {
            sets.push_back({"cloth-funnel/" + stem, kind, {csv}, json});
        }
    }
    return sets;
}

void missing_data(benchmark::State& state) {
    const std::string message =
        "no CCD query data under " + DATA_DIR.string() + " (ccd-queries/, cloth-funnel/): skipped";
    state.SkipWithError(message.c_str());
    for (auto _ : state) {
    }
}

// Short default run: the sets take 1-100 ms per pass, so a 0.1 s minimum gives a stable rate.
void configure(benchmark::internal::Benchmark* b) {
    b->Unit(benchmark::kMillisecond)->MinTime(0.1);
}

const bool REGISTERED = [] {
    benchmark::AddCustomContext("pliant_ccd_data", DATA_DIR.string());
    benchmark::AddCustomContext(
        "pliant_ccd_note",
        "pliant: conservative inclusion CCD, default options (tolerance 1e-6, delta 0); cubic: "
        "floating-point coplanarity cubic, not conservative. One thread.");
    const std::vector<SetSource> sets = discover_sets();
    if (sets.empty()) {
        configure(benchmark::RegisterBenchmark("BM_Ccd/missing_data", missing_data));
        return true;
    }
    for (const SetSource& source : sets) {
        configure(benchmark::RegisterBenchmark(("BM_PliantCcd/" + source.name).c_str(),
                                               [source](benchmark::State& state) {
                                                   run_set<pliant_ccd>(state, source);
                                                   add_pliant_search_counters(state, source);
                                               }));
        configure(benchmark::RegisterBenchmark(
            ("BM_CubicCcd/" + source.name).c_str(),
            [source](benchmark::State& state) { run_set<cubic_ccd>(state, source); }));
    }
    return true;
}();

}  // namespace
