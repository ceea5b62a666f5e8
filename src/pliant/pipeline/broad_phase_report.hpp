// Measuring the self-collision broad phase the way `pliant collide --repeat N` and `pliant demo`
// report it: N fresh builds (request_rebuild before each), then N refits — build_ms is the median
// over the builds; refit_ms, traverse_ms, features_ms and total_ms (one refit-based update end to
// end, the steady state of a simulation) are medians over the refits. Pair counts must be
// identical in every run (InternalError otherwise).
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <span>
#include <string>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::pipeline {

struct BroadPhaseReport {
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
    int repeat = 0;
    double inflation = 0.0;  // world units
    bool swept = false;
    // With the continuous narrow phase (collide --ccd): CCD on every VF and EE pair.
    bool has_narrow = false;
    std::int64_t vf_hits = 0;
    std::int64_t ee_hits = 0;
    double earliest_toi = 1.0;  // in [0, 1]; 1 without hits
    double narrow_ms = 0.0;     // median over the repeats
};

// Runs SelfCollisionBroadPhase<double> on the step mesh.positions → positions_t1. warm_up adds
// one untimed update first (allocation and thread start-up out of the numbers). narrow: also run
// collision::continuous_narrow_phase on the pairs, `repeat` times.
BroadPhaseReport measure_broad_phase(const geometry::TriangleMeshD& mesh,
                                     std::span<const Vec3d> positions_t1, double inflation,
                                     int repeat, bool swept, bool warm_up, bool narrow = false);

// The JSON object of `pliant collide --json` (schema in docs/formats.md).
nlohmann::ordered_json to_json(const BroadPhaseReport& report);

// 35912 → "35,912", as the BVH table prints counts.
std::string thousands(std::int64_t n);

}  // namespace pliant::pipeline
