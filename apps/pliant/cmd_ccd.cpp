// pliant ccd PATH [--min-separation D] [--json]
//
// Continuous collision detection (collision::vertex_face_ccd / edge_edge_ccd) on query files in
// the Sample-Queries format (io/ccd_queries.hpp). PATH is one file or a folder searched for *.csv;
// "edge-edge" / "vertex-face" in the path (or a file name ending in ee.csv / vf.csv) tells the
// kind. Ground truth: the file's 7th column, or, for 6-column files, the Mathematica booleans of
// the cloth-funnel layout (queries/227vf.csv ↔ mma_bool/227vf_mma_bool.json) when present.
//
// Per file: queries, hits, ground-truth positives, false negatives (a colliding query the CCD
// missed: must be 0), false positives, mean milliseconds per query. With --json, stdout is
// {"sets": [{"name", "kind", "queries", "hits", "positives", "false_negatives",
// "false_positives", "ms_per_query"}…], "false_negatives": total}; counts that need a ground truth
// are null for sets without one. Malformed files: IoError naming file and line (exit 1).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "pliant/collision/ccd.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/ccd_queries.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct CcdCommandOptions {
    std::string path;
    double min_separation = 0.0;  // world units
};

struct SetReport {
    std::string name;
    io::CcdQueryKind kind = io::CcdQueryKind::vertex_face;
    std::int64_t queries = 0;
    std::int64_t hits = 0;
    std::optional<std::int64_t> positives;  // empty without ground truth
    std::int64_t false_negatives = 0;
    std::int64_t false_positives = 0;
    double ms_per_query = 0.0;
};

// Ground truth per query: the file's column, or the cloth-funnel Mathematica booleans.
std::optional<std::vector<bool>> ground_truth(const std::filesystem::path& file,
                                              const io::CcdQuerySet& set) {
    if (!set.queries.empty() && set.queries.front().truth >= 0) {
        std::vector<bool> truth;
        truth.reserve(set.queries.size());
        for (const io::CcdQuery& q : set.queries) {
            truth.push_back(q.truth == 1);
        }
        return truth;
    }
    const std::filesystem::path mma =
        file.parent_path().parent_path() / "mma_bool" / (file.stem().string() + "_mma_bool.json");
    if (set.queries.empty() || !std::filesystem::exists(mma)) {
        return std::nullopt;
    }
    std::vector<bool> truth = io::read_mathematica_bools(mma);
    if (truth.size() != set.queries.size()) {
        throw IoError(fmt::format("{}: {} booleans, expected one per query of {} ({})",
                                  mma.string(), truth.size(), file.string(), set.queries.size()));
    }
    return truth;
}

SetReport run_set(const std::filesystem::path& file, double min_separation) {
    const io::CcdQuerySet set = io::read_ccd_queries(file);
    const std::optional<std::vector<bool>> truth = ground_truth(file, set);
    collision::CcdOptions options;
    options.min_separation = min_separation;
    SetReport report;
    report.name = file.string();
    report.kind = set.kind;
    report.queries = static_cast<std::int64_t>(set.queries.size());
    if (truth) {
        report.positives = 0;
    }
    Stopwatch watch;
    for (std::size_t i = 0; i < set.queries.size(); ++i) {
        const auto& p = set.queries[i].points;
        const collision::CcdResult result =
            set.kind == io::CcdQueryKind::vertex_face
                ? collision::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7],
                                             options)
                : collision::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], options);
        report.hits += result.hit ? 1 : 0;
        if (truth) {
            const bool colliding = (*truth)[i];
            *report.positives += colliding ? 1 : 0;
            report.false_negatives += colliding && !result.hit ? 1 : 0;
            report.false_positives += !colliding && result.hit ? 1 : 0;
        }
    }
    report.ms_per_query =
        report.queries > 0 ? watch.elapsed_ms() / static_cast<double>(report.queries) : 0.0;
    return report;
}

nlohmann::ordered_json to_json(const std::vector<SetReport>& reports) {
    nlohmann::ordered_json sets = nlohmann::ordered_json::array();
    std::int64_t false_negatives = 0;
    for (const SetReport& r : reports) {
        const bool known = r.positives.has_value();
        sets.push_back({
            {"name", r.name},
            {"kind", std::string(io::to_string(r.kind))},
            {"queries", r.queries},
            {"hits", r.hits},
            {"positives", known ? nlohmann::ordered_json(*r.positives) : nullptr},
            {"false_negatives", known ? nlohmann::ordered_json(r.false_negatives) : nullptr},
            {"false_positives", known ? nlohmann::ordered_json(r.false_positives) : nullptr},
            {"ms_per_query", r.ms_per_query},
        });
        false_negatives += r.false_negatives;
    }
    return {{"sets", sets}, {"false_negatives", false_negatives}};
}

std::string format_human(const std::vector<SetReport>& reports) {
    std::string text = fmt::format("{:<64} {:>11} {:>7} {:>6} {:>9} {:>4} {:>4} {:>8}\n", "file",
                                   "kind", "queries", "hits", "positives", "FN", "FP", "ms/query");
    std::int64_t queries = 0, false_negatives = 0, false_positives = 0;
    for (const SetReport& r : reports) {
        const auto known = [&](std::int64_t v) {
            return r.positives ? std::to_string(v) : std::string("-");
        };
        std::string name = r.name;
        if (name.size() > 64) {
            name = "..." + name.substr(name.size() - 61);
        }
        text += fmt::format("{:<64} {:>11} {:>7} {:>6} {:>9} {:>4} {:>4} {:>8.4f}\n", name,
                            io::to_string(r.kind), r.queries, r.hits,
                            r.positives ? std::to_string(*r.positives) : std::string("-"),
                            known(r.false_negatives), known(r.false_positives), r.ms_per_query);
        queries += r.queries;
        false_negatives += r.false_negatives;
        false_positives += r.false_positives;
    }
    text += fmt::format("total: {} queries in {} files, {} false negatives, {} false positives\n",
                        queries, reports.size(), false_negatives, false_positives);
    return text;
}

void run_ccd(const CcdCommandOptions& options, const GlobalOptions& global) {
    const std::vector<std::filesystem::path> files = io::find_ccd_query_files(options.path);
    if (files.empty()) {
        throw InvalidInput(fmt::format("ccd: no .csv query files under {}", options.path));
    }
    std::vector<SetReport> reports;
    reports.reserve(files.size());
    for (const std::filesystem::path& file : files) {
        reports.push_back(run_set(file, options.min_separation));
    }
    const std::string out = global.json ? to_json(reports).dump(2) + "\n" : format_human(reports);
    std::fputs(out.c_str(), stdout);
}

}  // namespace

void register_ccd(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<CcdCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "ccd",
        "Continuous collision detection on query files (Sample-Queries format): false negatives "
        "and positives against the ground truth, time per query");
    cmd->add_option("PATH", options->path, "A query .csv file, or a folder searched for them")
        ->required();
    cmd->add_option("--min-separation", options->min_separation,
                    "Report contacts closer than D (world units, >= 0)")
        ->type_name("D")
        ->check(finite_non_negative());
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_ccd(*options, global); });
}

}  // namespace pliant::cli
