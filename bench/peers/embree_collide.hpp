// Embree 3 as the BVH benchmark's peer: the same triangle boxes as an RTC_GEOMETRY_TYPE_USER
// geometry (a bounds callback reads the caller's boxes), Embree's own BVH build, refit and
// rtcCollide self-collision, counting exactly the pairs pliant counts (self_pairs.hpp).
//
// Two scenes, both RTC_SCENE_FLAG_DYNAMIC with scene quality RTC_BUILD_QUALITY_LOW (Embree's
// configuration for per-frame rebuilds; in Embree 3.13 a two-level build whose one geometry gets
// its own BVH, 8-wide on AVX machines):
//   - built:    geometry quality RTC_BUILD_QUALITY_LOW (Embree's Morton builder); build() commits
//               it again, which rebuilds it from scratch;
//   - refitted: geometry quality RTC_BUILD_QUALITY_REFIT (Embree's refit path: the first commit
//               builds with SAH, later commits of the same primitive count only refit the node
//               boxes).
// collide(): rtcCollide(scene, scene). Embree hands the callback every primitive pair of every
// pair of overlapping leaves, in both orders (a, b) and (b, a), never (a, a). The callback keeps
// a < b, re-tests the two boxes exactly (closed intervals, as pliant) and drops pairs that share
// a vertex. Counts are per thread (padded slots), added once per callback batch.
//
// The collider references the caller's boxes: they must stay alive and unchanged from build() /
// refit() until the next call that replaces them, including collide() on that scene.
// Thread safety: one thread drives an instance; Embree parallelizes inside (TBB), limited to the
// constructor's thread count. Built without Embree (PLIANT_HAS_EMBREE = 0), embree_available()
// is false and the constructor throws Unsupported.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "pliant/core/aabb.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::bench {

bool embree_available();
// "3.13.5", or "" without Embree.
std::string embree_version();

struct EmbreeCollideResult {
    std::int64_t pairs = 0;     // unordered pairs, overlapping boxes, no shared vertex
    std::int64_t reported = 0;  // ordered candidates rtcCollide passed to the callback
    // The same count from the mirrored reports (b, a), b > a, when asked for: equal to `pairs`
    // exactly when Embree reported both orders, which the deduplication relies on. -1 if not
    // counted.
    std::int64_t mirrored_pairs = -1;
    double ms = 0.0;  // wall time of rtcCollide, callback included
};

class EmbreeSelfCollider {
public:
    enum class Scene { built, refitted };

    // num_threads ≥ 1: Embree's device is created with "threads=N". Throws InvalidInput for
    // num_threads < 1, Unsupported without Embree, InternalError when Embree fails.
    explicit EmbreeSelfCollider(int num_threads);
    ~EmbreeSelfCollider();
    EmbreeSelfCollider(const EmbreeSelfCollider&) = delete;
    EmbreeSelfCollider& operator=(const EmbreeSelfCollider&) = delete;

    // Builds the `built` scene over `boxes` (creating it on the first call or when the count
    // changes). Returns the wall time in ms of the commit that builds the BVH.
    double build(std::span<const AABB> boxes);
    // Refits the `refitted` scene to `boxes` (same count as the last call; the first call, or a
    // count change, builds it instead). Returns the wall time in ms of the commit.
    double refit(std::span<const AABB> boxes);
    // Self-collision of a scene that has been built; triangles: #T vertex triples for the
    // shared-vertex filter. count_mirrored also tests the (b, a) reports (a check, not for
    // timing: it roughly doubles the callback's work).
    EmbreeCollideResult collide(Scene scene, std::span<const geometry::Triangle> triangles,
                                bool count_mirrored = false) const;

    // Bytes Embree holds now / held at most since construction (its memory monitor callback).
    std::int64_t memory_bytes() const;
    std::int64_t peak_memory_bytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace pliant::bench
