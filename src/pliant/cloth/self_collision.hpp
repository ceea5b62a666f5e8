// Self-collision handling for the cloth: proximity constraints that keep the cloth `thickness`
// apart from itself, and a continuous-collision fail-safe that makes every frame end free of
// intersections.
//
// Per window of a few substeps (ClothSolver::step runs a frame as windows of 4 substeps):
//   1. gather, at the window's start: the broad phase (collision/self_broad_phase.hpp: LBVH +
//      R-triangles + orphan sets) swept from the positions x to the prediction x + dt v + ½ g dt²
//      (dt: the window) relative to the cloth's mean motion, boxes grown by half the thickness
//      (so boxes overlap for features within the thickness), then only the pairs whose distance
//      minus relative sweep can fall to twice the thickness: the vertex-face and edge-edge pairs
//      that can come within thickness if the cloth moves about as predicted, each once. Pairs the
//      prediction misses are caught by step 3.
//   2. every substep, project: each gathered pair closer than thickness is pushed apart along
//      its closest-point normal until thickness apart (a one-sided XPBD distance constraint,
//      rigid; Bridson, Fedkiw, Anderson, "Robust Treatment of Collisions, Contact and Friction
//      for Cloth Animation", SIGGRAPH 2002, §7.2 uses the same geometry as repulsions); a pair
//      that passed through each other within the substep is pushed back along the normal it had
//      at the substep's start; then Coulomb friction on the pair's relative tangential motion
//      over the substep. Pairs whose distance at the gather minus their largest relative sweep
//      since then stays at least the thickness are skipped without a proximity test. Sequential
//      over the pairs in their sorted order: deterministic.
//   3. enforce, at the window's end: the gather's broad-phase pairs when every vertex ended inside
//      its gather box (in the gather's translating frame; typical in free fall), else the swept
//      broad phase from the window's start to its end, with boxes swept by the motion relative to
//      the cloth's mean motion (distances do not change
//      in a translating frame, so these are the same pairs, and a falling sheet sweeps nothing);
//      pairs whose start distance minus the largest relative displacement of their vertices stays
//      positive cannot touch and are dropped; the conservative CCD (collision/ccd.hpp) runs on the
//      rest. The vertices of every pair that may touch are put back at their window-start
//      positions with zero velocity, and the check repeats on the changed motion until no pair
//      touches: after the first round a world-space swept broad phase from the start to the
//      positions after that round's reverts (a vertex put back stands still, which is not inside
//      its box relative to the mean motion; later reverts shrink a motion to a point inside its
//      world-space box, so this one broad phase holds every pair until the end), and each round
//      re-tests only the pairs with a vertex put back in that round (the others were cleared on
//      unchanged motion). Every round puts back at least one more vertex or stops, so this ends,
//      at worst with every vertex at its start. Since the window's start is intersection-free, the
//      CCD never misses a contact and reverted vertices do not move, its end is intersection-free
//      too (the fail-safe of Bridson et al. 2002 §7.4 taken to its simplest, rigid form: a vertex
//      that cannot move safely does not move in that window).
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/material.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

// Over one frame (reset_stats() to the next): times in ms and counts, summed over its windows.
struct SelfCollisionStats {
    double gather_ms = 0.0;   // step 1, all calls
    double project_ms = 0.0;  // step 2, all calls
    double enforce_ms = 0.0;  // step 3, all calls
    // The same time by kind of work, over steps 1-3:
    double refit_ms = 0.0;             // LBVH builds and refits (gather and fail-safe broad phases)
    double traverse_ms = 0.0;          // BVH traversal, feature boxes and R-triangle feature tests
    double narrow_ms = 0.0;            // proximity tests of the candidates (step 2), CCD (step 3)
    double response_ms = 0.0;          // pushing contacts apart with friction (2), reverting (3)
    std::int64_t candidate_pairs = 0;  // gathered VF + EE pairs
    std::int64_t contacts = 0;         // pairs pushed apart in the last substep
    std::int64_t ccd_hits = 0;         // pairs the CCD could not clear in the first round, summed
    std::int64_t reverted_vertices = 0;  // vertices put back by the fail-safe, summed over calls
    int enforce_rounds = 0;              // most rounds of one call
};

class SelfCollision {
public:
    SelfCollision(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
                  double thickness);

    // Step 1. dt: the time the candidates must cover (s); gravity (m/s²). candidate_pairs
    // describes the last call; gather_ms sums the frame's calls.
    void gather(std::span<const Vec3d> positions, std::span<const Vec3d> velocities, double dt,
                const Vec3d& gravity);
    // Step 2; returns the pairs pushed apart (also stats().contacts). previous_positions: the
    // positions at the start of the substep, for friction: the pair's relative tangential
    // motion over the substep is cancelled when it is at most self_static_friction × the normal
    // correction, else shortened by self_kinetic_friction × the correction (Coulomb, positional
    // form: Macklin, Müller, Chentanez, Kim, "Unified Particle Physics for Real-Time
    // Applications", SIGGRAPH 2014, §6.1).
    std::int64_t project(std::span<Vec3d> positions, std::span<const Vec3d> previous_positions,
                         std::span<const double> inverse_masses, const ClothMaterial& material);
    // Step 3; positions_t0: the start of the motion to check (intersection-free).
    void enforce(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                 std::span<Vec3d> velocities);

    const SelfCollisionStats& stats() const { return m_stats; }
    void reset_stats() { m_stats = {}; }

private:
    void add_broad_phase_times(const collision::BroadPhaseStats& broad);
    // True when the last gather started at positions_t0 and every vertex's position now, in the
    // gather's translating frame, lies in its gather box shrunk by `margin`: then the gather's
    // broad-phase pairs include every pair that can touch over positions_t0 → positions.
    bool gather_boxes_hold(std::span<const Vec3d> positions_t0, std::span<const Vec3d> positions,
                           double margin) const;
    // Pairs are indexed VF first, then EE: i < #VF is vertex_face[i], else edge_edge[i − #VF].
    // True when pair i has a vertex v with marked[v] != 0.
    bool touches(const collision::FeaturePairs& pairs, std::int64_t i,
                 std::span<const std::uint8_t> marked) const;
    // The distance between pair i's features at x.
    double pair_distance(const collision::FeaturePairs& pairs, std::int64_t i,
                         std::span<const Vec3d> x) const;
    // Whether a lower bound on pair i's distance over the linear motion start → end exceeds
    // threshold: the distance at the start minus the largest relative displacement of a vertex
    // of one feature and a vertex of the other. Decides most pairs by the features' box distance
    // first; when it computes the exact start distance, it also stores it in *distance.
    bool separation_exceeds(const collision::FeaturePairs& pairs, std::int64_t i,
                            std::span<const Vec3d> start, std::span<const Vec3d> end,
                            double threshold, double* distance = nullptr) const;
    // The pairs for which keep(i) holds, in order (their indices stay in m_indices).
    template <typename Keep>
    collision::FeaturePairs filter_pairs(const collision::FeaturePairs& pairs, Keep&& keep);
    // The i in [0, n) with keep(i), ascending (valid until the next call).
    template <typename Keep>
    const std::vector<std::int64_t>& indices_where(std::int64_t n, Keep&& keep);

    std::vector<geometry::Triangle> m_triangles;
    double m_thickness;
    collision::SelfCollisionBroadPhase<double> m_gather_phase;
    collision::SelfCollisionBroadPhase<double> m_swept_phase;   // fail-safe, round 0
    collision::SelfCollisionBroadPhase<double> m_revert_phase;  // fail-safe, later rounds
    std::vector<Vec3d> m_predicted;
    std::vector<Vec3d> m_relative_end;       // a step's end minus the mean displacement
    Vec3d m_gather_shift{0.0, 0.0, 0.0};     // the gather's mean displacement
    std::vector<Vec3d> m_gather_end;         // the gather's prediction minus m_gather_shift
    collision::FeaturePairs m_candidates;    // gathered pairs that may come within thickness
    std::vector<double> m_swept_distances;   // per gathered broad-phase pair (kept ones set)
    std::vector<double> m_gather_distances;  // per candidate, its distance at the gather
    std::vector<Vec3d> m_gather_positions;   // the positions at the gather
    std::vector<double> m_pair_sweeps;       // per candidate, its largest relative sweep since
    ChunkedBuffer<std::int64_t> m_index_chunks;
    std::vector<std::int64_t> m_indices;
    SelfCollisionStats m_stats;
};

}  // namespace pliant::cloth
