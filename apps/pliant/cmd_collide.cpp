// pliant collide MESH [--to MESH_T1] [--inflate H] [--repeat N] [--ccd] [--intersections]
//                [--max-memory MIB] [--json]
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
//   - A mesh whose broad phase needs more than --max-memory MiB (default: the memory available;
//     pipeline/memory_budget.hpp) is refused after reading, before the broad phase allocates
//     (InvalidInput, exit 1).
//   - With --json, stdout is one JSON object (schema in docs/formats.md); otherwise a short
//     aligned summary.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>

#include "commands.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/pipeline/broad_phase_report.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct CollideOptions {
    std::string mesh;      // frame at t0 (or the static mesh)
    std::string mesh_t1;   // frame at t1; empty for a static query
    double inflate = 0.0;  // world units
    int repeat = 1;
    bool ccd = false;             // also run the continuous narrow phase on the pairs
    bool intersections = false;   // also count intersecting triangle pairs (exact)
    double max_memory_mib = 0.0;  // 0: the memory available
};

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

// Intersecting non-adjacent triangle pairs of MESH (and of MESH_T1), decided exactly.
struct IntersectionCounts {
    std::int64_t t0 = -1;
    std::int64_t t1 = -1;  // -1: no MESH_T1
    double ms = 0.0;
};

void print_human(const CollideOptions& options, const pipeline::BroadPhaseReport& r,
                 const IntersectionCounts& intersections) {
    const bool swept = !options.mesh_t1.empty();
    std::string text;
    if (swept) {
        text += fmt::format("collide {} -> {} (swept), inflation {}\n", options.mesh,
                            options.mesh_t1, options.inflate);
    } else {
        text += fmt::format("collide {} (static), inflation {}\n", options.mesh, options.inflate);
    }
    text += fmt::format("  {:<16}{:>12} vertices, {} edges, {} triangles\n", "mesh",
                        pipeline::thousands(r.vertices), pipeline::thousands(r.edges),
                        pipeline::thousands(r.triangles));
    text +=
        fmt::format("  {:<16}{:>12}\n", "triangle pairs", pipeline::thousands(r.triangle_pairs));
    text += fmt::format("  {:<16}{:>12}\n", "VF pairs", pipeline::thousands(r.vf_pairs));
    text += fmt::format("  {:<16}{:>12}\n", "EE pairs", pipeline::thousands(r.ee_pairs));
    const std::string runs = fmt::format("median of {}", options.repeat);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "build", r.build_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "refit", r.refit_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "traverse", r.traverse_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "features", r.features_ms, runs);
    text += fmt::format("  {:<16}{:>12.3f} ms   {}, refit-based update end to end\n", "total",
                        r.total_ms, runs);
    if (r.has_narrow) {
        text += fmt::format("  {:<16}{:>12}\n", "VF hits (CCD)", pipeline::thousands(r.vf_hits));
        text += fmt::format("  {:<16}{:>12}\n", "EE hits (CCD)", pipeline::thousands(r.ee_hits));
        text += fmt::format("  {:<16}{:>12.6g}\n", "earliest toi", r.earliest_toi);
        text += fmt::format("  {:<16}{:>12.3f} ms   {}\n", "narrow (CCD)", r.narrow_ms, runs);
    }
    if (options.intersections) {
        text += fmt::format("  {:<16}{:>12}   exact, MESH\n", "intersecting", intersections.t0);
        if (intersections.t1 >= 0) {
            text +=
                fmt::format("  {:<16}{:>12}   exact, MESH_T1\n", "intersecting", intersections.t1);
        }
    }
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
    pipeline::require_memory(
        fmt::format("collide: the broad phase over {} triangles", mesh.num_triangles()),
        pipeline::broad_phase_need_bytes(mesh.num_triangles()),
        pipeline::memory_limit_bytes(options.max_memory_mib));
    const std::span<const Vec3d> positions_t1 = options.mesh_t1.empty()
                                                    ? std::span<const Vec3d>(mesh.positions)
                                                    : std::span<const Vec3d>(mesh_t1.positions);
    const pipeline::BroadPhaseReport result = pipeline::measure_broad_phase(
        mesh, positions_t1, options.inflate, options.repeat, !options.mesh_t1.empty(),
        /*warm_up=*/false, options.ccd);
    IntersectionCounts intersections;
    if (options.intersections) {
        Stopwatch watch;
        intersections.t0 = collision::count_intersecting_pairs(
            std::span<const Vec3d>(mesh.positions),
            std::span<const geometry::Triangle>(mesh.triangles));
        if (!options.mesh_t1.empty()) {
            intersections.t1 = collision::count_intersecting_pairs(
                positions_t1, std::span<const geometry::Triangle>(mesh.triangles));
        }
        intersections.ms = watch.elapsed_ms();
    }
    if (global.json) {
        nlohmann::ordered_json json = pipeline::to_json(result);
        if (options.intersections) {
            json["intersecting_pairs"] = intersections.t0;
            if (intersections.t1 >= 0) {
                json["intersecting_pairs_t1"] = intersections.t1;
            }
            json["intersections_ms"] = intersections.ms;
        }
        std::fputs((json.dump(2) + "\n").c_str(), stdout);
    } else {
        print_human(options, result, intersections);
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
        ->check(finite_non_negative());
    cmd->add_option("--repeat", options->repeat, "Run N builds and N refits; timings are medians")
        ->type_name("N")
        ->check(CLI::Range(1, 1000000));
    cmd->add_flag(
        "--ccd", options->ccd,
        "Also run the continuous narrow phase (conservative CCD) on every VF and EE pair: "
        "vf_hits, ee_hits, earliest_toi, narrow_ms");
    cmd->add_flag("--intersections", options->intersections,
                  "Also count the intersecting pairs of triangles that share no vertex, decided "
                  "exactly (in MESH, and in MESH_T1 with --to): intersecting_pairs, "
                  "intersecting_pairs_t1, intersections_ms");
    add_max_memory_option(*cmd, options->max_memory_mib, "a mesh whose broad phase needs");
    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
    cmd->callback([options, &global] { run_collide(*options, global); });
}

}  // namespace pliant::cli
