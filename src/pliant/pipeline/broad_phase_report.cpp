#include "pliant/pipeline/broad_phase_report.hpp"

#include <fmt/format.h>

#include <vector>

#include "pliant/collision/narrow_phase.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::pipeline {

BroadPhaseReport measure_broad_phase(const geometry::TriangleMeshD& mesh,
                                     std::span<const Vec3d> positions_t1, double inflation,
                                     int repeat, bool swept, bool warm_up, bool narrow) {
    collision::SelfCollisionBroadPhase<double> broad_phase(mesh.triangles, mesh.num_vertices());
    const std::span<const Vec3d> positions_t0(mesh.positions);

    BroadPhaseReport report;
    report.triangles = static_cast<std::int64_t>(mesh.num_triangles());
    report.vertices = static_cast<std::int64_t>(mesh.num_vertices());
    report.edges = static_cast<std::int64_t>(broad_phase.topology().num_edges());
    report.repeat = repeat;
    report.inflation = inflation;
    report.swept = swept;

    bool has_counts = false;
    const auto record_counts = [&](const collision::FeaturePairs& pairs) {
        const auto triangle_pairs = broad_phase.stats().triangle_pairs;
        const auto vf = static_cast<std::int64_t>(pairs.vertex_face.size());
        const auto ee = static_cast<std::int64_t>(pairs.edge_edge.size());
        if (has_counts && (triangle_pairs != report.triangle_pairs || vf != report.vf_pairs ||
                           ee != report.ee_pairs)) {
            throw InternalError(fmt::format(
                "broad phase: repeated runs disagree: {}/{}/{} then {}/{}/{} triangle/VF/EE pairs",
                report.triangle_pairs, report.vf_pairs, report.ee_pairs, triangle_pairs, vf, ee));
        }
        report.triangle_pairs = triangle_pairs;
        report.vf_pairs = vf;
        report.ee_pairs = ee;
        has_counts = true;
    };

    if (warm_up) {
        record_counts(broad_phase.update(positions_t0, positions_t1, inflation));
    }
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
    report.build_ms = median(build_ms);
    report.refit_ms = median(refit_ms);
    report.traverse_ms = median(traverse_ms);
    report.features_ms = median(features_ms);
    report.total_ms = median(total_ms);
    report.memory_bytes = broad_phase.memory_bytes();
    if (narrow) {
        std::vector<double> narrow_ms;
        for (int i = 0; i < repeat; ++i) {
            Stopwatch watch;
            const collision::NarrowPhaseResult result = collision::continuous_narrow_phase(
                positions_t0, positions_t1, std::span<const geometry::Triangle>(mesh.triangles),
                std::span<const geometry::Edge>(broad_phase.topology().edges), broad_phase.pairs());
            narrow_ms.push_back(watch.elapsed_ms());
            report.vf_hits = result.vf_hits;
            report.ee_hits = result.ee_hits;
            report.earliest_toi = result.earliest_toi;
        }
        report.has_narrow = true;
        report.narrow_ms = median(narrow_ms);
    }
    return report;
}

nlohmann::ordered_json to_json(const BroadPhaseReport& r) {
    nlohmann::ordered_json out = {
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
        {"repeat", r.repeat},
        {"threads", num_threads()},
        {"inflation", r.inflation},
        {"swept", r.swept},
        {"memory_bytes", r.memory_bytes},
    };
    if (r.has_narrow) {
        out["vf_hits"] = r.vf_hits;
        out["ee_hits"] = r.ee_hits;
        out["earliest_toi"] = r.earliest_toi;
        out["narrow_ms"] = r.narrow_ms;
    }
    return out;
}

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

}  // namespace pliant::pipeline
