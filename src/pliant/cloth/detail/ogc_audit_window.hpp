// The state of the OGC audit's current window (detail/ogc_step.hpp, audit_ogc_window): where the
// window started, the contact's detection and frame shift then, and the audit's counters.
#pragma once

#include <cstdint>
#include <vector>

#include "pliant/cloth/detail/self_collision_pairs.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

struct OgcAuditWindow {
    std::vector<Vec3d> start;     // #V, the window's start (intersection-free)
    std::int64_t detections = 0;  // OgcContact::detections() at the window's start
    Vec3d shift{0.0, 0.0, 0.0};   // OgcContact::shift() at the window's start
    // Windows audited on the detection's pairs and by the full fail-safe, since the step's start.
    std::int64_t pair_audits = 0;
    std::int64_t full_audits = 0;
    std::vector<FeatureVertices> pairs;  // scratch: the detection's pairs
    std::vector<double> deviations;      // scratch: per vertex, its deviation over the window
};

}  // namespace pliant::cloth::detail
