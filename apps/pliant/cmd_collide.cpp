// pliant collide MESH [--to MESH_T1] [--inflate H] [--repeat N] [--json]
//
// The self-collision broad phase (collision::SelfCollisionBroadPhase<double>) on one mesh file
// (static: both ends of the step are MESH) or between two frames of the same mesh (swept: MESH at
// t0, MESH_T1 at t1). Files are OBJ or PLY, read at full precision.
//
// Contract:
//   - MESH_T1 must have MESH's vertex count and exactly its triangles, else InvalidInput naming
//     both files and both counts (exit 1). Unreadable or broken files: IoError (exit 1).
//   - H (world units, default 0) grows every feature box on every side; it must be finite and
//     ≥ 0, else a usage error (exit 2).
//   - N ≥ 1 (default 1). The broad phase runs 2N times: N fresh builds (request_rebuild before
//     each), then N refits. build_ms is the median over the builds; refit_ms, traverse_ms,
//     features_ms and total_ms (one refit-based update end to end) are medians over the refits,
//     the steady state of a simulation. Pair counts are identical in every run (checked).
//   - With --json, stdout is one JSON object (schema in docs/formats.md); otherwise a short
//     aligned summary.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "commands.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::cli {
namespace {

struct CollideOptions {
    std::string mesh;      // frame at t0 (or the static mesh)
    std::string mesh_t1;   // frame at t1; empty for a static query
    double inflate = 0.0;  // world units
    int repeat = 1;
};

struct CollideResult {
    std::int64_t triangles = 0;
    std::int64_t vertices = 0;
    std::int64_t edges = 0;
    std::int64_t triangle_pairs = 0;
    std::int64_t vf_pairs = 0;
    std::int64_t ee_pairs = 0;
    double build_ms = 0.0;
    double refit_ms = 0.0;
    double traverse_ms = 0.0;
    double features_ms = 0.0;
    double total_ms = 0.0;
    std::size_t memory_bytes = 0;
};

// CLI11's NonNegativeNumber lets NaN through; this one wants a finite number ≥ 0.
const CLI::Validator FINITE_NON_NEGATIVE(
    [](std::string& text) -> std::string {
        double value = 0.0;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, value);
        if (ec != std::errc() || ptr != end || !std::isfinite(value) || value < 0.0) {
            return fmt::format("must be a finite number >= 0, got '{}'", text);
        }
        return {};
    },
    "", "FINITE_NON_NEGATIVE");

// 35912 → "35,912", as the BVH table prints counts.
std::string thousands(std::int64_t n) {
    const std::string digits = std::to_string(n < 0 ? -n : n);
    std::string out = n < 0 ? "-" : "";
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) {
            out.push_back(',');
        }
        out.push_back(digits[i]);
    }
    return out;
}

// The frame at t1 must be the same mesh as the frame at t0, moved.
void check_same_mesh(const geometry::TriangleMeshD& mesh, const std::string& mesh_path,
                     const geometry::TriangleMeshD& mesh_t1, const std::string& mesh_t1_path) {
    if (mesh.num_vertices() != mesh_t1.num_vertices() ||
        mesh.num_triangles() != mesh_t1.num_triangles()) {
        throw InvalidInput(fmt::format(
            "collide: {} has {} vertices and {} triangles but --to {} has {} vertices and {} "
            "triangles; the two frames must be the same mesh",
            mesh_path, mesh.num_vertices(), mesh.num_triangles(), mesh_t1_path,
            mesh_t1.num_vertices(), mesh_t1.num_triangles()));
    }
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const geometry::Triangle& a = mesh.triangles[t];
        const geometry::Triangle& b = mesh_t1.triangles[t];
        if (a != b) {
            throw InvalidInput(fmt::format(
                "collide: triangle {} is ({}, {}, {}) in {} but ({}, {}, {}) in --to {}; the two "
                "frames must have identical triangles",
                t, a[0], a[1], a[2], mesh_path, b[0], b[1], b[2], mesh_t1_path));
        }
    }
}

CollideResult measure(const geometry::TriangleMeshD& mesh, std::span<const Vec3d> positions_t1,
                      double inflation, int repeat) {
    collision::SelfCollisionBroadPhase<double> broad_phase(mesh.triangles, mesh.num_vertices());
    const std::span<const Vec3d> positions_t0(mesh.positions);

    CollideResult result;
    result.triangles = static_cast<std::int64_t>(mesh.num_triangles());
    result.vertices = static_cast<std::int64_t>(mesh.num_vertices());
    result.edges = static_cast<std::int64_t>(broad_phase.topology().num_edges());

    bool has_counts = false;
    const auto record_counts = [&](const collision::FeaturePairs& pairs) {
        const auto triangle_pairs = broad_phase.stats().triangle_pairs;
        const auto vf = static_cast<std::int64_t>(pairs.vertex_face.size());
        const auto ee = static_cast<std::int64_t>(pairs.edge_edge.size());
        if (has_counts && (triangle_pairs != result.triangle_pairs || vf != result.vf_pairs ||
                           ee != result.ee_pairs)) {
            throw InternalError(fmt::format(
                "collide: repeated runs disagree: {}/{}/{} then {}/{}/{} triangle/VF/EE pairs",
                result.triangle_pairs, result.vf_pairs, result.ee_pairs, triangle_pairs, vf, ee));
        }
        result.triangle_pairs = triangle_pairs;
        result.vf_pairs = vf;
        result.ee_pairs = ee;
        has_counts = true;
    };

    // Step 1: fresh builds.
    std::vector<double> build_ms;
    for (int i = 0; i < repeat; ++i) {
        broad_phase.request_rebuild();
        record_counts(broad_phase.update(positions_t0, positions_t1, inflation));
        build_ms.push_back(broad_phase.stats().build_ms);
    }

    // Step 2: refits, the per-step path of a simulation.
    std::vector<double> refit_ms;
    std::vector<double> traverse_ms;
    std::vector<double> features_ms;
    std::vector<double> total_ms;
    for (int i = 0; i < repeat; ++i) {
        Stopwatch watch;
        const collision::FeaturePairs& pairs =
            broad_phase.update(positions_t0, positions_t1, inflation);
        total_ms.push_back(watch.elapsed_ms());
        record_counts(pairs);
        const collision::BroadPhaseStats& stats = broad_phase.stats();
        refit_ms.push_back(stats.refit_ms);
        traverse_ms.push_back(stats.traverse_ms);
        features_ms.push_back(stats.features_ms);
    }

    result.build_ms = median(build_ms);
    result.refit_ms = median(refit_ms);
    result.traverse_ms = median(traverse_ms);
    result.features_ms = median(features_ms);
    result.total_ms = median(total_ms);
    result.memory_bytes = broad_phase.memory_bytes();
    return result;
}

void print_json(const CollideOptions& options, const CollideResult& r) {
    const nlohmann::ordered_json out = {
        {"triangles", r.triangles},
        {"vertices", r.vertices},
        {"edges", r.edges},
        {"triangle_pairs", r.triangle_pairs},
        {"vf_pairs", r.vf_pairs},
        {"ee_pairs", r.ee_pairs},
        {"build_ms", r.build_ms},
        {"refit_ms", r.refit_ms},
        {"traverse_ms", r.traverse_ms},
        {"features_ms", r.features_ms},
        {"total_ms", r.total_ms},
        {"repeat", options.repeat},
        {"threads", num_threads()},
        {"inflation", options.inflate},
        {"swept", !options.mesh_t1.empty()},
        {"memory_bytes", r.memory_bytes},
    };
    std::fputs((out.dump(2) + "\n").c_str(), stdout);
}

void print_human(const CollideOptions& options, const CollideResult& r) {
    const bool swept = !options.mesh_t1.empty();
    std::string text;
    if (swept) {
        text += fmt::format("collide {} -> {} (swept), inflation {}\n", options.mesh,
                            options.mesh_t1, options.inflate);
    } else {
        text += fmt::format("collide {} (static), inflation {}\n", options.mesh, options.inflate);
    }
    text += fmt::format("  {:<16}{:>12} vertices, {} edges, {} triangles\n", "mesh",
                        thousands(r.vertices), thousands(r.edges), thousands(r.triangles));
    text += fmt::format("  {:<16}{:>12}\n", "triangle pairs", thousands(r.triangle_pairs));
    text += fmt::format("  {:<16}{:>12}\n", "VF pairs", thousands(r.vf_pairs));
    text += fmt::format("  {:<16}{:>12}\n", "EE pairs", thousands(r.ee_pairs));
    const std::string runs = fmt::format("median of {}", options.repeat);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "build", r.build_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "refit", r.refit_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "traverse", r.traverse_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "features", r.features_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}, refit-based update end to end\n", "total",
                        r.total_ms, runs);
    text += fmt::format("  {:<16}{:>12.2f} MiB\n", "memory",
                        static_cast<double>(r.memory_bytes) / (1024.0 * 1024.0));
    text += fmt::format("  {:<16}{:>12}\n", "threads", num_threads());
    std::fputs(text.c_str(), stdout);
}

void run_collide(const CollideOptions& options, const GlobalOptions& global) {
    const geometry::TriangleMeshD mesh = io::read_mesh(options.mesh);
    geometry::TriangleMeshD mesh_t1;
    if (!options.mesh_t1.empty()) {
        mesh_t1 = io::read_mesh(options.mesh_t1);
        check_same_mesh(mesh, options.mesh, mesh_t1, options.mesh_t1);
    }
    const std::span<const Vec3d> positions_t1 = options.mesh_t1.empty()
                                                    ? std::span<const Vec3d>(mesh.positions)
                                                    : std::span<const Vec3d>(mesh_t1.positions);
    const CollideResult result = measure(mesh, positions_t1, options.inflate, options.repeat);
    if (global.json) {
        print_json(options, result);
    } else {
        print_human(options, result);
    }
}

}  // namespace

void register_collide(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<CollideOptions>();
    CLI::App* cmd = app.add_subcommand(
        "collide",
        "Self-collision broad phase (LBVH + R-triangles + orphan sets) on a mesh, or swept "
        "between two frames of it: pair counts and stage timings");
    cmd->add_option("MESH", options->mesh, "Mesh file (.obj or .ply); the frame at t0")->required();
    cmd->add_option("--to", options->mesh_t1,
                    "Frame at t1 (same vertices and triangles); boxes span both frames (swept)")
        ->type_name("MESH_T1");
    cmd->add_option("--inflate", options->inflate,
                    "Grow every feature box by H on every side (world units, finite, >= 0)")
        ->type_name("H")
        ->check(FINITE_NON_NEGATIVE);
    cmd->add_option("--repeat", options->repeat, "Run N builds and N refits; timings are medians")
        ->type_name("N")
        ->check(CLI::Range(1, 1000000));
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_collide(*options, global); });
}

}  // namespace pliant::cli
