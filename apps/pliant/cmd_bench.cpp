// pliant bench bvh: the paper's BVH table (build / refit / self-collision traversal) measured on
// this machine for pliant's LBVH beside Embree 3 and a brute force, with the paper's figures.
// Human table on stdout, or one JSON object with --json. A pair count mismatch between the
// contestants is an error (exit 1) after the table is printed.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "peers/bvh_table.hpp"
#include "pliant/core/error.hpp"

namespace pliant::cli {
namespace {

struct BenchBvhArgs {
    std::vector<std::int64_t> sizes = bench::BvhTableOptions{}.sizes;
    int repeat = 5;
    bool no_brute_force = false;
    bool no_embree = false;
    std::int64_t brute_force_limit = bench::BvhTableOptions{}.brute_force_limit;
};

void run_bench_bvh(const BenchBvhArgs& args, const GlobalOptions& global) {
    bench::BvhTableOptions options;
    options.sizes = args.sizes;
    options.repeats = args.repeat;
    options.threads = global.threads;
    options.include_brute_force = !args.no_brute_force;
    options.include_embree = !args.no_embree;
    options.brute_force_limit = args.brute_force_limit;
    for (const std::int64_t size : options.sizes) {
        if (size < 2) {
            throw InvalidInput(
                fmt::format("bench bvh: --sizes: {} is not a triangle count >= 2", size));
        }
    }
    if (isatty(fileno(stderr)) != 0) {
        options.progress = [](const std::string& message) {
            std::fprintf(stderr, "%s\n", message.c_str());
        };
    }

    const bench::BvhTableResult result = bench::run_bvh_table(options);
    if (global.json) {
        std::fputs((bench::bvh_table_json(result).dump(2) + "\n").c_str(), stdout);
    } else {
        std::fputs(bench::format_bvh_table(result).c_str(), stdout);
    }
    std::fflush(stdout);
    if (!result.ok()) {
        std::string message = "bench bvh: pair counts disagree:";
        for (const std::string& e : result.errors()) {
            message += "\n  " + e;
        }
        throw InternalError(message);
    }
}

}  // namespace

void register_bench(CLI::App& app, const GlobalOptions& global) {
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks beside their peers");
    bench->require_subcommand(1);
    bench->fallthrough();

    auto args = std::make_shared<BenchBvhArgs>();
    CLI::App* bvh = bench->add_subcommand(
        "bvh",
        "The paper's BVH table: build / refit / self-collision traversal for pliant's LBVH, "
        "Embree 3 and a brute force, at 2,244, 27,030, 35,992, 250,000 and 1,000,000 triangles");
    bvh->fallthrough();
    bvh->add_option("--sizes", args->sizes,
                    "Triangle counts, comma separated (each row uses the nearest square sheet)")
        ->delimiter(',');
    bvh->add_option("--repeat", args->repeat, "Timed repetitions per row (median reported)")
        ->check(CLI::Range(1, 1000));
    bvh->add_flag("--no-brute-force", args->no_brute_force, "Skip the O(n^2) brute force");
    bvh->add_flag("--no-embree", args->no_embree, "Skip the Embree peer");
    bvh->add_option("--brute-force-limit", args->brute_force_limit,
                    "Largest row (triangles) that runs the brute force")
        ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 40));
    bvh->callback([args, &global] { run_bench_bvh(*args, global); });
}

}  // namespace pliant::cli
