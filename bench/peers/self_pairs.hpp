// Self-collision pair counts over triangle boxes, as the BVH benchmark's contestants compute
// them. All of them count the same set: unordered pairs {a, b}, a ≠ b, of triangles whose boxes
// overlap (closed intervals: touching boxes overlap) and that share no vertex.
//
// boxes: #T boxes, one per triangle; triangles: #T vertex triples. Both counts run in parallel
// through pliant's parallel layer and are identical for any number of threads.
#pragma once

#include <cstdint>
#include <span>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::bench {

// pliant: bvh::for_each_self_overlap over a built (or refitted) tree, each chunk of leaves
// counting its accepted pairs into its own cache-line-padded counter; no allocation per pair.
// O(n log n + pairs) for well-behaved inputs. tree must index `triangles` (same #T).
std::int64_t count_self_pairs(const bvh::LBVH& tree, std::span<const geometry::Triangle> triangles);

// The O(n²) reference: every pair (i < j) tested, branch-free over a struct-of-arrays copy of the
// boxes and vertex ids (vectorizable). Rows are spread over threads. Feasible up to ~10⁵ boxes.
// boxes.size() must equal triangles.size() (InvalidInput otherwise).
std::int64_t brute_force_self_pairs(std::span<const AABB> boxes,
                                    std::span<const geometry::Triangle> triangles);

}  // namespace pliant::bench
