// SelfCollisionStats: what the self-collision's parts (self_collision.hpp) did over one frame.
#pragma once

#include <cstdint>

namespace pliant::cloth {

// Over one frame (SelfCollision::reset_stats() to the next): times in ms and counts, summed over
// its windows. Steps 1-3 are those of self_collision.hpp.
struct SelfCollisionStats {
    double gather_ms = 0.0;   // step 1, all calls
    double project_ms = 0.0;  // step 2, all calls
    double enforce_ms = 0.0;  // step 3, all calls
    // The same time by kind of work, over steps 1-3:
    double refit_ms = 0.0;             // LBVH builds and refits
    double traverse_ms = 0.0;          // BVH traversal, feature boxes and R-triangle feature tests
    double narrow_ms = 0.0;            // candidate filters, proximity tests (step 2), CCD (step 3)
    double response_ms = 0.0;          // pushing contacts apart with friction (2), reverting (3)
    std::int64_t candidate_pairs = 0;  // candidates at the end of the last call
    std::int64_t contacts = 0;         // pairs pushed apart in the last substep
    std::int64_t ccd_hits = 0;         // pairs the CCD could not clear in the first round, summed
    std::int64_t reverted_vertices = 0;  // vertices put back by the fail-safe, summed over calls
    int enforce_rounds = 0;              // most rounds of one call
    std::int64_t ccd_pairs = 0;          // pairs the fail-safe's CCD tested, summed
    // Fail-safe windows whose pairs exceeded its budget (CCDFailSafe::pair_budget), and the
    // vertices those put back without a CCD test, summed.
    std::int64_t budget_exceeded = 0;
    std::int64_t frozen_vertices = 0;
    std::int64_t gathers = 0;       // full broad phases
    std::int64_t path_updates = 0;  // partial broad phases (vertices given new paths)
    std::int64_t new_paths = 0;     // vertices given new paths by them, summed
};

}  // namespace pliant::cloth
