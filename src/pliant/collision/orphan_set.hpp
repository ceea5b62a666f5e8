// Orphan sets (Tang, Curtis, Yoon, Manocha 2008, "ICCD: Interactive Continuous Collision Detection
// between Deformable Models using Connectivity-Based Culling"): the feature pairs the
// triangle-level traversal can never produce. The traversal skips triangle pairs that share a
// vertex, yet such a pair can carry features that share nothing — a vertex its R-triangle owns
// against the neighbour's face (v ∉ face), or owned edges with four distinct vertices. Those pairs
// depend only on topology, so they are listed once here and their boxes tested directly every step.
//
// Together with the R-triangle pairs of non-adjacent triangles this covers every non-incident VF
// and EE pair exactly once.
//
// Size: O(Σ_v valence(v)²) — about 10 pairs per triangle on a regular cloth grid (valence 6), but a
// vertex shared by k triangles (a fan, a cylinder cap) contributes about k²/2 triangle pairs of up
// to 15 feature pairs each; such meshes pay for it in memory and in per-step tests.
#pragma once

#include <span>

#include "pliant/collision/feature_pairs.hpp"
#include "pliant/collision/representative_triangles.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::collision {

// The non-incident VF and EE pairs between the owned features of every pair of distinct triangles
// that share at least one vertex. Sorted, no duplicates.
FeaturePairs build_orphan_set(std::span<const geometry::Triangle> triangles,
                              const geometry::MeshTopology& topology,
                              const RepresentativeTriangles& owners);

}  // namespace pliant::collision
