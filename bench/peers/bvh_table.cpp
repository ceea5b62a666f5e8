#include "peers/bvh_table.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <span>
#include <string>

#include "peers/embree_collide.hpp"
#include "peers/self_pairs.hpp"
#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::bench {
namespace {

constexpr std::int64_t MAX_TRIANGLES = 2LL * 16384 * 16384;

// The paper's Tables 1–3 (GPU and CPU columns), ms; refit converted from its printed "us".
constexpr std::array<PaperFigures, 3> PAPER = {{
    {2244, 23.94, 0.16, 1.19, 5.71, 0.31, 10.28},
    {27030, 59.12, 0.18, 12.52, 45.18, 1.28, 162.92},
    {35992, 210.0, 0.35, 410.0, 980.0, 4.81, 8650.0},
}};

std::int64_t peak_rss_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

std::string thousands(std::int64_t value) {
    std::string digits = fmt::format("{}", value < 0 ? -value : value);
    std::string out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) {
            out += ',';
        }
        out += digits[i];
    }
    return value < 0 ? "-" + out : out;
}

// Milliseconds with three significant-ish digits: 0.0123, 1.23, 12.3, 1234.
std::string format_ms(double ms) {
    if (ms < 0.1) {
        return fmt::format("{:.4f}", ms);
    }
    if (ms < 10.0) {
        return fmt::format("{:.3f}", ms);
    }
    if (ms < 100.0) {
        return fmt::format("{:.2f}", ms);
    }
    if (ms < 1000.0) {
        return fmt::format("{:.1f}", ms);
    }
    return fmt::format("{:.0f}", ms);
}

std::string format_mib(std::int64_t bytes) {
    return fmt::format("{:.1f} MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
}

constexpr const char* DASH = "\u2014";  // what the table prints for "not measured"

// fmt pads by code points only for ASCII; the dash is one column wide but three bytes.
std::string right(const std::string& text, std::size_t width) {
    const std::size_t columns = text == DASH ? 1 : text.size();
    return columns >= width ? text : std::string(width - columns, ' ') + text;
}

void validate(const BvhTableOptions& options) {
    if (options.sizes.empty()) {
        throw InvalidInput("run_bvh_table: options.sizes is empty");
    }
    for (const std::int64_t size : options.sizes) {
        if (size < 2 || size > MAX_TRIANGLES) {
            throw InvalidInput(
                fmt::format("run_bvh_table: size ({}) not in [2, {}]", size, MAX_TRIANGLES));
        }
    }
    if (options.repeats < 1) {
        throw InvalidInput(
            fmt::format("run_bvh_table: options.repeats ({}) must be >= 1", options.repeats));
    }
    if (options.threads < 0) {
        throw InvalidInput(
            fmt::format("run_bvh_table: options.threads ({}) must be >= 0", options.threads));
    }
}

struct Samples {
    std::vector<double> build, refit, traverse;

    StageTimes medians() const { return {median(build), median(refit), median(traverse)}; }
};

BvhTableRow run_row(std::int64_t requested, const BvhTableOptions& options, bool use_embree,
                    int threads) {
    // Step 1: the workload and its boxes before (step 0) and after (step 1) one step of motion.
    const BvhWorkload workload = BvhWorkload::make(requested, options.workload);
    const std::vector<AABB> boxes0 = workload.boxes(0);
    const std::vector<AABB> boxes1 = workload.boxes(1);
    const std::span<const geometry::Triangle> triangles = workload.triangles();

    BvhTableRow row;
    row.requested_triangles = requested;
    row.triangles = static_cast<std::int64_t>(workload.num_triangles());
    row.quads_per_side = workload.quads_per_side;
    row.edge_length = workload.edge_length;
    row.paper = paper_figures(requested);
    const std::string label = fmt::format("{} triangles", thousands(row.triangles));

    // Step 2: one warm-up repetition (which also checks counts after the build), then the timed
    // ones.
    bvh::LBVH tree;
    std::optional<EmbreeSelfCollider> embree;
    if (use_embree) {
        embree.emplace(threads);
        row.embree.emplace();
    }
    Samples pliant_samples;
    Samples embree_samples;
    for (int rep = 0; rep <= options.repeats; ++rep) {
        const bool warm_up = rep == 0;

        Stopwatch watch;
        tree.build(boxes0);
        const double build_ms = watch.elapsed_ms();
        if (warm_up) {
            row.pliant.pairs_built = count_self_pairs(tree, triangles);
        }
        watch.restart();
        tree.refit(boxes1);
        const double refit_ms = watch.elapsed_ms();
        watch.restart();
        const std::int64_t pairs = count_self_pairs(tree, triangles);
        const double traverse_ms = watch.elapsed_ms();
        if (warm_up) {
            row.pliant.pairs = pairs;
        } else {
            pliant_samples.build.push_back(build_ms);
            pliant_samples.refit.push_back(refit_ms);
            pliant_samples.traverse.push_back(traverse_ms);
            if (pairs != row.pliant.pairs) {
                row.errors.push_back(
                    fmt::format("{}: pliant's pair count changed between repetitions ({} vs {})",
                                label, thousands(pairs), thousands(row.pliant.pairs)));
            }
        }

        if (embree) {
            EmbreeRow& e = *row.embree;
            const double e_build_ms = embree->build(boxes0);
            if (warm_up) {
                e.pairs_built = embree->collide(EmbreeSelfCollider::Scene::built, triangles).pairs;
            }
            embree->refit(boxes0);  // back to step 0 (the first call builds the scene)
            const double e_refit_ms = embree->refit(boxes1);
            const EmbreeCollideResult collided =
                embree->collide(EmbreeSelfCollider::Scene::refitted, triangles, warm_up);
            if (warm_up) {
                e.pairs = collided.pairs;
                e.mirrored_pairs = collided.mirrored_pairs;
                e.reported = collided.reported;
            } else {
                embree_samples.build.push_back(e_build_ms);
                embree_samples.refit.push_back(e_refit_ms);
                embree_samples.traverse.push_back(collided.ms);
                if (collided.pairs != e.pairs) {
                    row.errors.push_back(fmt::format(
                        "{}: Embree's pair count changed between repetitions ({} vs {})", label,
                        thousands(collided.pairs), thousands(e.pairs)));
                }
            }
        }
    }
    row.pairs = row.pliant.pairs;
    row.pliant.times = pliant_samples.medians();
    row.pliant.memory_bytes = static_cast<std::int64_t>(tree.memory_bytes());

    // Step 3: cross-checks and the brute force.
    if (embree) {
        EmbreeRow& e = *row.embree;
        e.times = embree_samples.medians();
        e.peak_memory_bytes = embree->peak_memory_bytes();
        if (e.pairs != row.pliant.pairs) {
            row.errors.push_back(
                fmt::format("{}: pair count mismatch after refit: pliant {}, Embree {}", label,
                            thousands(row.pliant.pairs), thousands(e.pairs)));
        }
        if (e.pairs_built != row.pliant.pairs_built) {
            row.errors.push_back(
                fmt::format("{}: pair count mismatch after build: pliant {}, Embree {}", label,
                            thousands(row.pliant.pairs_built), thousands(e.pairs_built)));
        }
        if (e.mirrored_pairs != e.pairs) {
            row.errors.push_back(fmt::format(
                "{}: rtcCollide did not report every pair in both orders ({} as (a, b), {} as "
                "(b, a)): its count is not reliable",
                label, thousands(e.pairs), thousands(e.mirrored_pairs)));
        }
    }
    if (options.include_brute_force && row.triangles <= options.brute_force_limit) {
        const Stopwatch watch;
        const std::int64_t pairs = brute_force_self_pairs(boxes1, triangles);
        row.brute_force = BruteForceRow{watch.elapsed_ms(), pairs};
        if (pairs != row.pliant.pairs) {
            row.errors.push_back(fmt::format("{}: pair count mismatch: pliant {}, brute force {}",
                                             label, thousands(row.pliant.pairs), thousands(pairs)));
        }
    }
    row.peak_rss_bytes = peak_rss_bytes();
    return row;
}

// The shortest decimal that reads back as the same float (0.1f → 0.1, not 0.10000000149…).
double shortest(float value) {
    return std::stod(fmt::format("{}", value));
}

nlohmann::json stage_json(const StageTimes& t) {
    return {{"build_ms", t.build_ms}, {"refit_ms", t.refit_ms}, {"traverse_ms", t.traverse_ms}};
}

}  // namespace

std::optional<PaperFigures> paper_figures(std::int64_t triangles) {
    for (const PaperFigures& p : PAPER) {
        if (p.triangles == triangles) {
            return p;
        }
    }
    return std::nullopt;
}

bool BvhTableResult::ok() const {
    return std::all_of(rows.begin(), rows.end(),
                       [](const BvhTableRow& row) { return row.errors.empty(); });
}

std::vector<std::string> BvhTableResult::errors() const {
    std::vector<std::string> out;
    for (const BvhTableRow& row : rows) {
        out.insert(out.end(), row.errors.begin(), row.errors.end());
    }
    return out;
}

BvhTableResult run_bvh_table(const BvhTableOptions& options) {
    validate(options);
    set_num_threads(options.threads);

    BvhTableResult result;
    result.options = options;
    result.threads = num_threads();
    result.hardware_threads = hardware_threads();
    const bool use_embree = options.include_embree && embree_available();
    if (use_embree) {
        result.embree_version = embree_version();
    }
    for (const std::int64_t size : options.sizes) {
        if (options.progress) {
            options.progress(fmt::format("bench bvh: {} triangles", thousands(size)));
        }
        result.rows.push_back(run_row(size, options, use_embree, result.threads));
    }
    return result;
}

std::string format_bvh_table(const BvhTableResult& result) {
    const BvhTableOptions& o = result.options;
    const BvhWorkloadOptions& w = o.workload;
    const bool has_embree = !result.embree_version.empty();
    const auto paper_cell = [](const BvhTableRow& row, double PaperFigures::*field) {
        return row.paper ? format_ms((*row.paper).*field) : std::string(DASH);
    };
    std::string out;

    // Header and workload.
    out += fmt::format(
        "pliant bench bvh: {} m square sheet folded into {:g} panels, layers {:g} e apart, boxes "
        "inflated {:g} e,\ntravelling wave {:g} e (e = edge length). {} thread{} ({} hardware); "
        "median of {} run{} after 1 warm-up.\nTimes in ms. Embree: {}.\n\n",
        w.sheet_size, 1.0f / w.panel_fraction, w.gap_edges, w.inflation_edges, w.amplitude_edges,
        result.threads, result.threads == 1 ? "" : "s", result.hardware_threads, o.repeats,
        o.repeats == 1 ? "" : "s",
        has_embree         ? result.embree_version
        : o.include_embree ? "not available (pliant was built without it)"
                           : "not run");
    out += fmt::format("{:>11}  {:>8}  {:>9}  {:>11}  {}\n", "triangles", "(paper)", "quads",
                       "pairs", "check");
    for (const BvhTableRow& row : result.rows) {
        std::string check;
        if (!row.errors.empty()) {
            check = "MISMATCH (see errors)";
        } else {
            check = "pliant";
            if (row.embree) {
                check += " = Embree";
            }
            if (row.brute_force) {
                check += " = brute force";
            }
        }
        out += fmt::format(
            "{:>11}  {}  {:>9}  {:>11}  {}\n", thousands(row.triangles),
            right(row.paper ? fmt::format("({})", thousands(row.paper->triangles)) : DASH, 8),
            fmt::format("{}x{}", row.quads_per_side, row.quads_per_side), thousands(row.pairs),
            check);
    }

    // The three tables.
    struct Stage {
        const char* title;
        double StageTimes::*time;
        double PaperFigures::*gpu;
        double PaperFigures::*cpu;
        const char* paper_mark;
    };
    const std::array<Stage, 3> stages = {{
        {"Table 1. BVH build", &StageTimes::build_ms, &PaperFigures::gpu_build_ms,
         &PaperFigures::cpu_build_ms, ""},
        {"Table 2. BVH refit", &StageTimes::refit_ms, &PaperFigures::gpu_refit_ms,
         &PaperFigures::cpu_refit_ms, "*"},
        {"Table 3. Self-collision traversal (pairs of non-adjacent triangles)",
         &StageTimes::traverse_ms, &PaperFigures::gpu_traverse_ms, &PaperFigures::cpu_traverse_ms,
         ""},
    }};
    for (std::size_t s = 0; s < stages.size(); ++s) {
        const Stage& stage = stages[s];
        const bool with_brute = s == 2;
        out += fmt::format("\n{}\n", stage.title);
        out += fmt::format("{:>11}  {:>10}  {:>10}", "triangles", "pliant", "Embree");
        if (with_brute) {
            out += fmt::format("  {:>11}", "brute force");
        }
        out += fmt::format("  {:>11}  {:>11}\n", fmt::format("paper GPU{}", stage.paper_mark),
                           fmt::format("paper CPU{}", stage.paper_mark));
        for (const BvhTableRow& row : result.rows) {
            out += fmt::format(
                "{:>11}  {:>10}  {}", thousands(row.triangles),
                format_ms(row.pliant.times.*stage.time),
                right(row.embree ? format_ms(row.embree->times.*stage.time) : DASH, 10));
            if (with_brute) {
                out += "  " + right(row.brute_force ? format_ms(row.brute_force->ms) : DASH, 11);
            }
            out += fmt::format("  {}  {}\n", right(paper_cell(row, stage.gpu), 11),
                               right(paper_cell(row, stage.cpu), 11));
        }
    }

    // Footnotes.
    out += fmt::format(
        "\nRows use the square sheet nearest to the paper's size (in parentheses). Paper figures "
        "are its own\nhardware's, copied for reference. {} = not run (brute force only up to {} "
        "triangles, run once).\n",
        DASH, thousands(o.brute_force_limit));
    out +=
        "* The paper prints its refit times in \"us\"; beside its build and traversal times "
        "they only make\n  sense as ms, and are shown as ms.\n";
    if (!result.rows.empty()) {
        const auto largest = std::max_element(
            result.rows.begin(), result.rows.end(),
            [](const BvhTableRow& a, const BvhTableRow& b) { return a.triangles < b.triangles; });
        out += fmt::format("Memory at {} triangles: LBVH {}", thousands(largest->triangles),
                           format_mib(largest->pliant.memory_bytes));
        if (largest->embree) {
            out += fmt::format(", Embree peak {} (both of its scenes)",
                               format_mib(largest->embree->peak_memory_bytes));
        }
        out += fmt::format("; process peak RSS {}.\n", format_mib(largest->peak_rss_bytes));
    }
    const std::vector<std::string> errors = result.errors();
    if (!errors.empty()) {
        out += "\nERRORS:\n";
        for (const std::string& e : errors) {
            out += "  " + e + "\n";
        }
    }
    return out;
}

nlohmann::json bvh_table_json(const BvhTableResult& result) {
    const BvhTableOptions& o = result.options;
    const BvhWorkloadOptions& w = o.workload;
    nlohmann::json rows = nlohmann::json::array();
    for (const BvhTableRow& row : result.rows) {
        nlohmann::json j = {
            {"requested_triangles", row.requested_triangles},
            {"triangles", row.triangles},
            {"quads_per_side", row.quads_per_side},
            {"edge_length_m", shortest(row.edge_length)},
            {"pairs", row.pairs},
            {"pliant",
             {{"times", stage_json(row.pliant.times)},
              {"pairs", row.pliant.pairs},
              {"pairs_after_build", row.pliant.pairs_built},
              {"memory_bytes", row.pliant.memory_bytes}}},
            {"embree", nullptr},
            {"brute_force", nullptr},
            {"paper", nullptr},
            {"peak_rss_bytes", row.peak_rss_bytes},
            {"errors", row.errors},
        };
        if (row.embree) {
            const EmbreeRow& e = *row.embree;
            j["embree"] = {
                {"times", stage_json(e.times)},       {"pairs", e.pairs},
                {"pairs_after_build", e.pairs_built}, {"mirrored_pairs", e.mirrored_pairs},
                {"reported_candidates", e.reported},  {"peak_memory_bytes", e.peak_memory_bytes}};
        }
        if (row.brute_force) {
            j["brute_force"] = {{"ms", row.brute_force->ms}, {"pairs", row.brute_force->pairs}};
        }
        if (row.paper) {
            const PaperFigures& p = *row.paper;
            j["paper"] = {{"triangles", p.triangles},
                          {"gpu", stage_json({p.gpu_build_ms, p.gpu_refit_ms, p.gpu_traverse_ms})},
                          {"cpu", stage_json({p.cpu_build_ms, p.cpu_refit_ms, p.cpu_traverse_ms})},
                          {"note", "refit printed as \"us\" in the paper, taken as ms"}};
        }
        rows.push_back(std::move(j));
    }
    return {
        {"benchmark", "bvh"},
        {"threads", result.threads},
        {"hardware_threads", result.hardware_threads},
        {"repeats", o.repeats},
        {"statistic", "median after 1 warm-up; brute force: one run"},
        {"embree", result.embree_version.empty() ? nlohmann::json(nullptr)
                                                 : nlohmann::json(result.embree_version)},
        {"workload",
         {{"sheet_size_m", shortest(w.sheet_size)},
          {"panel_fraction", shortest(w.panel_fraction)},
          {"gap_edges", shortest(w.gap_edges)},
          {"inflation_edges", shortest(w.inflation_edges)},
          {"amplitude_edges", shortest(w.amplitude_edges)},
          {"wavelength_m", shortest(w.wavelength)},
          {"phase_per_step_rad", shortest(w.phase_per_step)}}},
        {"brute_force_limit", o.brute_force_limit},
        {"rows", std::move(rows)},
        {"ok", result.ok()},
        {"errors", result.errors()},
    };
}

}  // namespace pliant::bench
