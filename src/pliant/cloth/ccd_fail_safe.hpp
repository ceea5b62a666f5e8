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
// Rounding: every test that clears a pair for the CCD keeps a margin of 1e-9 (1 + the largest
// coordinate).
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside; the vertices put
// back are the same for any number of threads (pairs in order).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/detail/self_collision_pairs.hpp"
#include "pliant/cloth/self_collision_candidates.hpp"
#include "pliant/cloth/self_collision_stats.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

class CCDFailSafe {
public:
    // Step 3 over the window time_t0 → time (s, time > time_t0) with the candidates of
    // `candidates` (whose paths it may mark as needing renewal and whose broad phase it runs):
    // positions_t0: the window's start (#V, intersection-free), positions: its end (#V; reverted
    // vertices are set to their start), velocities: at its end (#V; reverted vertices get zero).
    // Works without paths (candidates.has_paths() false: every vertex's motion is searched).
    // InvalidInput on the candidate set's memory guard.
    void enforce(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                 std::span<Vec3d> positions, std::span<Vec3d> velocities, double time_t0,
                 double time, SelfCollisionStats& stats);

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
    // The CCD rounds.
    void run_rounds(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                    std::span<Vec3d> positions, std::span<Vec3d> velocities, const Vec3d& shift_t0,
                    const Vec3d& shift, double time, double margin, SelfCollisionStats& stats);
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
    std::vector<std::uint8_t> m_reverted;
    std::vector<std::uint8_t> m_changed;
    detail::IndexFilter m_index_filter;
};

}  // namespace pliant::cloth
