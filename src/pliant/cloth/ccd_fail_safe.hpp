// CCDFailSafe: the self-collision's fail-safe (step 3 of self_collision.hpp): at the end of a
// window of substeps, every vertex whose motion over the window may make the cloth pass through
// itself is put back where the window started, so that a window that starts intersection-free
// ends intersection-free.
//
// enforce(), on the candidate set of self_collision_candidates.hpp: a vertex whose deviation at
// the window's start or end exceeds its slack + half the thickness has escaped: its motion over
// the window (in the frame) is its box and its pairs are searched (a partial broad phase; for
// more than a quarter of the vertices, every vertex's motion with boxes grown by the rounding
// margin only, as thin as the CCD allows). Every other vertex's motion lies within its slack +
// half the thickness (convex: the deviation along the straight motion, the frame's translation
// interpolated, is at most the larger of its ends'), so inside its grown box; then every pair
// that can touch is a candidate whose distance bound over the window is not positive, or a pair
// of an escaped vertex — in both cases only when its start distance minus its relative sweep over
// the window is not positive either; the conservative CCD (collision/ccd.hpp) runs on those. The
// vertices of every pair that may touch are put back at their window-start positions with zero
// velocity, and the check repeats on the changed motion (only pairs with a vertex just put back;
// a vertex put back stands still, which in the translating frame is a motion of its own: if that
// leaves its slack or box, it escapes and its pairs are searched) until no pair touches. Every
// round puts back at least one more vertex or stops, so this ends, at worst with every vertex at
// its start. Since the window's start is intersection-free, the CCD never misses a contact and
// reverted vertices do not move, its end is intersection-free too (the fail-safe of Bridson,
// Fedkiw, Anderson, "Robust Treatment of Collisions, Contact and Friction for Cloth Animation",
// SIGGRAPH 2002, §7.4 taken to its simplest, rigid form: a vertex that cannot move safely does
// not move in that window). Escaped vertices get new paths in the next prepare().
//
// Bounded work (graceful degradation under violent input: pins or obstacles that jump, cloth
// thrown far within a window): the CCD tests at most pair_budget() pairs per window, summed over
// its rounds. In a round whose pairs exceed what is left, the CCD tests those whose fastest vertex
// moves farthest (test_within_budget) and every other pair that may touch counts as a hit, so its
// vertices are put back (frozen for the window, Bridson et al. 2002 §7.4's rigid fallback at its
// simplest); later rounds test nothing. The hits are a superset of the CCD's, so the end stays
// intersection-free; the rounds continue as above on the changed motion and end as above. The
// price is motion: frozen vertices lose the window's motion, and where every window exceeds the
// budget the same vertices stay frozen (hence pins chase a jumping target and obstacles push
// deep cloth out at a bounded speed, xpbd_stepper.cpp's CATCH_UP_IN_THICKNESS, which keeps the
// jump ribbon within the budget).
// stats: budget_exceeded (windows) and frozen_vertices (vertices put back after the budget was
// spent, summed). The budget does not apply where the rounding margin exceeds the thickness
// (coordinates beyond about 1e6 thicknesses: cloth that diverged, which the caller must see
// rather than have held back).
//
// Rounding: every test that clears a pair for the CCD keeps a margin of 1e-9 (1 + the largest
// coordinate).
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside; the vertices put
// back are the same for any number of threads (pairs in order).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/detail/self_collision_pairs.hpp"
#include "pliant/cloth/self_collision_candidates.hpp"
#include "pliant/cloth/self_collision_stats.hpp"
#include "pliant/collision/narrow_phase.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

class CCDFailSafe {
public:
    // Pair tests per window: PAIRS_PER_VERTEX per vertex of the cloth, at least MIN_PAIRS. The
    // standard scenes (scenes/*.json, 72 frames) test at most 0.74 (drape), 1.04 (flag), 0.04
    // (twist) and 0.16 (pile) pairs per vertex in one round of a window; a ribbon whose pinned row
    // jumps 1.6 m in a substep tests 66 per vertex in every window for seconds.
    static constexpr std::int64_t PAIRS_PER_VERTEX = 8;
    static constexpr std::int64_t MIN_PAIRS = 10'000;
    static std::int64_t pair_budget(std::size_t num_vertices) {
        return std::max(MIN_PAIRS, PAIRS_PER_VERTEX * static_cast<std::int64_t>(num_vertices));
    }

    // Step 3 over the window time_t0 → time (s, time > time_t0) with the candidates of
    // `candidates` (whose paths it may mark as needing renewal and whose broad phase it runs):
    // positions_t0: the window's start (#V, intersection-free), positions: its end (#V; reverted
    // vertices are set to their start), velocities: at its end (#V; reverted vertices get zero).
    // Works without paths (candidates.has_paths() false: every vertex's motion is searched).
    // InvalidInput on the candidate set's memory guard.
    void enforce(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                 std::span<Vec3d> positions, std::span<Vec3d> velocities, double time_t0,
                 double time, SelfCollisionStats& stats);

    // The fail-safe on a given list of feature pairs instead of the candidate set: the caller
    // guarantees that no pair outside `pairs` (#pairs, vertex-face: the vertex then the face's
    // three; edge-edge: edge a's two then edge b's two; no vertex shared) can touch over the
    // window (detail/ogc_step.hpp: OGC's displacement bounds). The same rounds as enforce(): the
    // conservative CCD on every pair that separation_exceeds() does not clear, the vertices of
    // every hit put back at positions_t0 with zero velocity (in pair order), then only the pairs
    // with a vertex just put back, until no pair touches or nothing moves. No broad phase, no
    // budget (the caller bounds the list). stats: reverted_vertices, ccd_pairs, ccd_hits,
    // enforce_rounds, narrow_ms, response_ms and enforce_ms as enforce() counts them.
    void enforce_pairs(std::span<const detail::FeatureVertices> pairs,
                       std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                       std::span<Vec3d> velocities, SelfCollisionStats& stats);

    // The state later steps read (core/bytes.hpp), so that a run resumed from a checkpoint
    // continues bit for bit; load_state: InvalidInput for a state of another mesh or a
    // truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    using FeatureVertices = detail::FeatureVertices;

    // The vertices in m_escaped_now get boxes around their motion over the window (and around
    // it put back) and are marked escaped (and needing a path); the pairs that involve them are
    // searched (a partial broad phase, or a full one for many) and appended to m_escape_pairs.
    void search_escaped(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                        std::span<const Vec3d> positions, const Vec3d& shift_t0, const Vec3d& shift,
                        double margin, SelfCollisionStats& stats);
    // The CCD on the `budget` pairs of `pairs` (fewer than its size) whose fastest vertex
    // moves farthest; the other pairs are added to its hits. ccd_hits: the hits of the CCD.
    collision::NarrowPhaseResult test_within_budget(const SelfCollisionCandidates& candidates,
                                                    std::span<const Vec3d> positions_t0,
                                                    std::span<const Vec3d> positions,
                                                    const collision::FeaturePairs& pairs,
                                                    std::int64_t budget, std::int64_t& ccd_hits);
    // The CCD rounds.
    void run_rounds(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                    std::span<Vec3d> positions, std::span<Vec3d> velocities, const Vec3d& shift_t0,
                    const Vec3d& shift, double time, double margin, SelfCollisionStats& stats);
    // Clears the per-vertex put-back and changed marks and sets m_window_motion to end − start;
    // returns it.
    std::span<const Vec3d> begin_window(std::span<const Vec3d> start, std::span<const Vec3d> end);
    // Whether the distance at `start` minus the largest relative displacement (motion: per vertex,
    // end − start) of a vertex of one feature and one of the other exceeds threshold (box
    // distance first).
    static bool separation_exceeds(const FeatureVertices& f, std::span<const Vec3d> start,
                                   std::span<const Vec3d> motion, double threshold);

    std::vector<double> m_deviations;     // per vertex, the larger at the window's ends
    std::vector<Vec3d> m_window_motion;   // per vertex, end − start of the window
    std::vector<std::uint8_t> m_escaped;  // per vertex: escaped in the current window
    std::vector<std::int32_t> m_escaped_now;
    collision::FeaturePairs m_escape_pairs;  // pairs that involve an escaped vertex
    collision::FeaturePairs m_tested;        // the pairs within the budget
    std::vector<double> m_pair_motion;       // per pair, its fastest vertex's squared motion
    std::vector<std::int64_t> m_pair_order;
    std::vector<std::uint8_t> m_reverted;
    std::vector<std::uint8_t> m_changed;
    std::vector<std::uint8_t> m_pair_hits;  // enforce_pairs(): per pair, the CCD's hit
    detail::IndexFilter m_index_filter;
};

}  // namespace pliant::cloth
