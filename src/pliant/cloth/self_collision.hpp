// Self-collision handling for the cloth: proximity constraints that keep the cloth `thickness`
// apart from itself, and a continuous-collision fail-safe that makes every frame end free of
// intersections.
//
// XPBDStepper::step (xpbd_stepper.hpp) runs a frame as windows of a few substeps. SelfCollision
// is three parts in that order:
//   1. prepare, at the start of one window, or of two while contact is sparse
//      (windows_for_next_gather): the kinetic candidate set (self_collision_candidates.hpp:
//      per-vertex paths in a frame translating with the cloth, a broad phase over the paths'
//      boxes, the feature pairs whose distance can fall below the thickness while every vertex
//      stays near its path) is gathered or its escaped vertices get new paths;
//   2. every substep, project (here): each candidate closer than thickness is pushed apart along
//      its closest-point normal until thickness apart (a one-sided XPBD distance constraint,
//      rigid; Bridson, Fedkiw, Anderson, "Robust Treatment of Collisions, Contact and Friction
//      for Cloth Animation", SIGGRAPH 2002, §7.2 uses the same geometry as repulsions); a pair
//      that passed through each other within the substep is pushed back along the normal it had
//      at the substep's start; then Coulomb friction on the pair's relative tangential motion
//      over the substep. Candidates whose distance bound stays at least the thickness over the
//      substep are skipped without a proximity test, and so are those whose lower bounds now (box
//      gap, gap along the centroids' line, or the distance the last substep measured less their
//      relative displacement since) exceed both the thickness and their sweep over the substep.
//      Sequential over the candidates in their order: deterministic;
//   3. enforce, at the window's end: the CCD fail-safe (ccd_fail_safe.hpp) puts back the
//      vertices whose motion over the window may make the cloth pass through itself, so that a
//      window that starts intersection-free ends intersection-free.
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside, and results are
// bitwise identical for any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/ccd_fail_safe.hpp"
#include "pliant/cloth/detail/self_collision_pairs.hpp"
#include "pliant/cloth/material.hpp"
#include "pliant/cloth/self_collision_candidates.hpp"
#include "pliant/cloth/self_collision_stats.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

class SelfCollision {
public:
    // triangles: #T, indices into [0, num_vertices); thickness: the distance the cloth keeps from
    // itself (m).
    SelfCollision(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
                  double thickness);

    // How many of the caller's fail-safe windows the next step 1 should cover (1 or 2;
    // SelfCollisionCandidates::windows_for_next_gather).
    int windows_for_next_gather() { return m_candidates.windows_for_next_gather(); }
    // Step 1 for the window starting at `time` (s) and lasting window_dt (s) (one or several of
    // the fail-safe's windows: enforce() may run several times within it).
    void prepare(std::span<const Vec3d> positions, std::span<const Vec3d> velocities, double time,
                 double window_dt) {
        m_candidates.prepare(positions, velocities, time, window_dt, m_stats);
    }
    // Step 2 for the substep of length h ending at `time` (s); returns the pairs pushed apart
    // (also stats().contacts). previous_positions: the positions at the start of the substep, also
    // for friction: the pair's relative tangential motion over the substep is cancelled when it
    // is at most self_static_friction × the normal correction, else shortened by
    // self_kinetic_friction × the correction (Coulomb, positional form: Macklin, Müller,
    // Chentanez, Kim, "Unified Particle Physics for Real-Time Applications", SIGGRAPH 2014, §6.1).
    // Does nothing before a step 1.
    std::int64_t project(std::span<Vec3d> positions, std::span<const Vec3d> previous_positions,
                         std::span<const double> inverse_masses, const ClothMaterial& material,
                         double time, double h);
    // Step 3 over the window time_t0 → time (s, time > time_t0); positions_t0: its start
    // (intersection-free), positions: its end, velocities: at its end (reverted vertices get
    // zero). Works without step 1 (it then searches every vertex's motion over the window).
    void enforce(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                 std::span<Vec3d> velocities, double time_t0 = 0.0, double time = 1.0) {
        m_fail_safe.enforce(m_candidates, positions_t0, positions, velocities, time_t0, time,
                            m_stats);
    }

    // Step 3 on a given pair list (CCDFailSafe::enforce_pairs): the caller guarantees that no
    // pair outside `pairs` can touch over the window positions_t0 → positions.
    void enforce_pairs(std::span<const detail::FeatureVertices> pairs,
                       std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                       std::span<Vec3d> velocities) {
        m_fail_safe.enforce_pairs(pairs, positions_t0, positions, velocities, m_stats);
    }

    const SelfCollisionStats& stats() const { return m_stats; }
    void reset_stats() { m_stats = {}; }
    const SelfCollisionCandidates& candidates() const { return m_candidates; }

    // The state later steps read (core/bytes.hpp), so that a run resumed from a checkpoint
    // continues bit for bit; load_state: InvalidInput for a state of another mesh or a
    // truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    using Candidate = SelfCollisionCandidates::Candidate;

    SelfCollisionCandidates m_candidates;
    CCDFailSafe m_fail_safe;
    SelfCollisionStats m_stats;
    // The proximity projection's state: its calls so far, the positions at the last call before
    // its pushes (call m_project_calls − 1; empty before the first), deviations per vertex over
    // the substep, and scratch.
    std::int64_t m_project_calls = 0;
    std::vector<Vec3d> m_measured_positions;
    std::vector<double> m_deviations;
    detail::IndexFilter m_index_filter;
};

}  // namespace pliant::cloth
