// The continuous narrow phase on the broad phase's feature pairs: every vertex-face and edge-edge
// pair of FeaturePairs tested with the conservative CCD of ccd.hpp over the step
// positions_t0 → positions_t1 (linear motion).
//
// Counts are sums, the earliest time of impact is a minimum and the hit pairs are concatenated in
// chunk order, so the result is identical for 1 and N threads. Positions are converted to double
// for the CCD (exact for float input). O(pairs) CCD queries, in parallel over fixed chunks.
#pragma once

#include <cstdint>
#include <span>

#include "pliant/collision/ccd.hpp"
#include "pliant/collision/feature_pairs.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::collision {

struct NarrowPhaseResult {
    std::int64_t vf_hits = 0;   // vertex-face pairs the CCD cannot exclude
    std::int64_t ee_hits = 0;   // edge-edge pairs the CCD cannot exclude
    double earliest_toi = 1.0;  // smallest toi over all hits, in [0, 1]; 1 without hits
    FeaturePairs hits;          // those pairs, in the order of the input pairs
};

// positions_t0 / positions_t1: #V each; triangles and edges index them (edges as in
// MeshTopology::edges, which EdgeEdgePair refers to). Throws InvalidInput when the sizes differ
// or a pair's index is out of range.
template <typename Real>
NarrowPhaseResult continuous_narrow_phase(std::span<const Vec3<Real>> positions_t0,
                                          std::span<const Vec3<Real>> positions_t1,
                                          std::span<const geometry::Triangle> triangles,
                                          std::span<const geometry::Edge> edges,
                                          const FeaturePairs& pairs,
                                          const CcdOptions& options = {});

}  // namespace pliant::collision
