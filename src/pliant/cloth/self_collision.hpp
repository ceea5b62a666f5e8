// Self-collision handling for the cloth: proximity constraints that keep the cloth `thickness`
// apart from itself, and a continuous-collision fail-safe that makes every frame end free of
// intersections.
//
// ClothSolver::step runs a frame as windows of a few substeps. The candidate pairs persist across
// windows (a kinetic candidate set): each vertex follows a predicted path, and the broad phase's
// boxes hold every point within a slack of those paths, so the candidates stay valid as long as
// every vertex stays within its slack; a vertex that leaves it (or reaches the end of its path)
// gets a new path, and only its pairs are searched again. A falling sheet keeps its paths for
// the whole fall (one broad phase); a draping one renews the paths of its moving parts.
//
//   frame. Positions are compared in a frame translating with the cloth: s(τ) is the
//      componentwise median, over every 16th vertex, of the displacement since the last full
//      gather (distances are the same in any translating frame; a falling sheet does not move in
//      this one, and a sheet resting on an obstacle while a part of it swings does not either).
//      Any translation works as long as each check uses one value of s(τ) for all vertices.
//   paths. Vertex v has an anchor a_v (its position in the frame at time τ_v), a velocity u_v
//      (its velocity relative to the frame's) and a slack g_v = 0.2 thickness; its path is
//      a_v + u_v (τ − τ_v) for τ in [τ_v, τ_v + duration] (as long as it moves at most half a
//      thickness, one window to 64 windows); its deviation at τ is
//      e_v = |x_v − s(τ) − a_v − u_v (τ − τ_v)|.
//   boxes. The broad phase (collision/self_broad_phase.hpp: LBVH + R-triangles + orphan sets) runs
//      over the boxes of the paths grown by their slacks, grown by half the thickness more: a
//      pair it does not report stays more than thickness apart while its vertices are within
//      their slacks, and does not touch while they are within slack + half the thickness.
//   candidates. Of the reported pairs, those whose distance can fall below the thickness: a
//      pair's displacement relative to its distance d at time τ_0 is at most
//      |Δ_i − Δ_j| ≤ e_i(τ) + e_i(τ_0) + e_j(τ) + e_j(τ_0) + |u_i − u_j| (τ − τ_0), for i a vertex
//      of one feature and j of the other, so a pair is a candidate when d minus that bound (every
//      e at most its slack, τ up to the paths' end) can fall below the thickness. Each candidate
//      keeps d, τ_0, the deviations at τ_0 and the largest |u_i − u_j|, so its distance bound at
//      any later τ costs a few loads. The broad phase skips triangle pairs whose path boxes, or
//      whose projections on the line through their centroids (a separating axis), less the
//      slacks and the largest relative speed of their vertices over the paths' duration, stay
//      thickness apart (coherent motion: a falling flap's neighbours move together), before any
//      feature test; feature pairs go through the same two lower bounds (detail/pair_bounds.hpp)
//      before their exact distance.
//
// Per window:
//   1. prepare, at the start of one window, or of two while contact is sparse
//      (windows_for_next_gather): the first gathers (every vertex gets a path, a full broad
//      phase); later ones give new paths to the vertices that escaped in the last window, whose
//      path ends within the coming window(s) or that are predicted to leave their slack in it
//      (their velocity's difference from the path's), drop their candidates and search their
//      pairs again (SelfCollisionBroadPhase::update_vertices; a full broad phase for more than a
//      quarter of the vertices).
//   2. every substep, project: each candidate closer than thickness is pushed apart along its
//      closest-point normal until thickness apart (a one-sided XPBD distance constraint, rigid;
//      Bridson, Fedkiw, Anderson, "Robust Treatment of Collisions, Contact and Friction for Cloth
//      Animation", SIGGRAPH 2002, §7.2 uses the same geometry as repulsions); a pair that passed
//      through each other within the substep is pushed back along the normal it had at the
//      substep's start; then Coulomb friction on the pair's relative tangential motion over the
//      substep. Candidates whose distance bound stays at least the thickness over the substep
//      are skipped without a proximity test, and so are those whose lower bounds now (box gap,
//      gap along the centroids' line, or the distance the last substep measured less their
//      relative displacement since) exceed both the thickness and their sweep over the substep.
//      Sequential over the candidates in their order: deterministic.
//   3. enforce, at the window's end: a vertex whose deviation at the window's start or end exceeds
//      its slack + half the thickness has escaped: its motion over the window (in the frame) is
//      its box and its pairs are searched (partial broad phase; for more than a quarter of the
//      vertices, every vertex's motion with boxes grown by the rounding margin only, as thin as
//      the CCD allows). Every other vertex's motion lies within its slack + half the thickness
//      (convex: the deviation along the straight motion, the frame's translation interpolated,
//      is at most the larger of its ends'), so inside its grown box; then every pair that can
//      touch is a candidate whose distance bound over the window is not positive, or a pair of
//      an escaped vertex — in both cases only when its start distance minus its relative sweep
//      over the window is not positive either; the conservative CCD (collision/ccd.hpp) runs on
//      those. The vertices of every pair that may touch are put back at their window-start
//      positions with zero velocity, and the check repeats on the changed motion (only pairs
//      with a vertex just put back; a vertex put back stands still, which in the translating
//      frame is a motion of its own: if that leaves its slack or box, it escapes and its pairs
//      are searched) until no pair touches. Every round puts back at least one more vertex or
//      stops, so this ends, at worst with every vertex at its start. Since the window's start is
//      intersection-free, the CCD never misses a contact and reverted vertices do not move, its
//      end is intersection-free too (the fail-safe of Bridson et al. 2002 §7.4 taken to its
//      simplest, rigid form: a vertex that cannot move safely does not move in that window).
//      Escaped vertices get new paths in the next step 1.
//
// Rounding: every test that clears a pair for the CCD keeps a margin of 1e-9 (1 + the largest
// coordinate); the broad phase's float boxes are rounded outward.
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <type_traits>
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
    double refit_ms = 0.0;             // LBVH builds and refits
    double traverse_ms = 0.0;          // BVH traversal, feature boxes and R-triangle feature tests
    double narrow_ms = 0.0;            // candidate filters, proximity tests (step 2), CCD (step 3)
    double response_ms = 0.0;          // pushing contacts apart with friction (2), reverting (3)
    std::int64_t candidate_pairs = 0;  // candidates at the end of the last call
    std::int64_t contacts = 0;         // pairs pushed apart in the last substep
    std::int64_t ccd_hits = 0;         // pairs the CCD could not clear in the first round, summed
    std::int64_t reverted_vertices = 0;  // vertices put back by the fail-safe, summed over calls
    int enforce_rounds = 0;              // most rounds of one call
    std::int64_t gathers = 0;            // full broad phases
    std::int64_t path_updates = 0;       // partial broad phases (vertices given new paths)
    std::int64_t new_paths = 0;          // vertices given new paths by them, summed
};

class SelfCollision {
public:
    SelfCollision(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
                  double thickness);

    // How many of the caller's fail-safe windows the next step 1 should cover: 2 while the
    // candidate pairs are few (fewer than the vertices, or after a dense phase fewer than an eighth
    // of them), which halves the broad phases of a draping sheet; 1 while contact is dense, where
    // a longer window's candidates (every pair that can close the gap over it) would cost more
    // in steps 2 and 3 than the broad phase saved. Decided on counts only: deterministic.
    int windows_for_next_gather();
    // Step 1 for the window starting at `time` (s) and lasting window_dt (s) (one or several of
    // the fail-safe's windows: enforce() may run several times within it).
    void prepare(std::span<const Vec3d> positions, std::span<const Vec3d> velocities, double time,
                 double window_dt);
    // Step 2 for the substep of length h ending at `time` (s); returns the pairs pushed apart
    // (also stats().contacts). previous_positions: the positions at the start of the substep, also
    // for friction: the pair's relative tangential motion over the substep is cancelled when it
    // is at most self_static_friction × the normal correction, else shortened by
    // self_kinetic_friction × the correction (Coulomb, positional form: Macklin, Müller,
    // Chentanez, Kim, "Unified Particle Physics for Real-Time Applications", SIGGRAPH 2014, §6.1).
    std::int64_t project(std::span<Vec3d> positions, std::span<const Vec3d> previous_positions,
                         std::span<const double> inverse_masses, const ClothMaterial& material,
                         double time, double h);
    // Step 3 over the window time_t0 → time (s, time > time_t0); positions_t0: its start
    // (intersection-free), positions: its end, velocities: at its end (reverted vertices get
    // zero). Works without step 1 (it then gathers on the window's motion).
    void enforce(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                 std::span<Vec3d> velocities, double time_t0 = 0.0, double time = 1.0);

    const SelfCollisionStats& stats() const { return m_stats; }
    void reset_stats() { m_stats = {}; }

private:
    // A candidate pair: its features (VF: vertex, face; EE: the two edges), their vertices (VF:
    // the vertex, then the face's; EE: edge a's, then edge b's), and its distance bound: at time
    // τ, distance − offset − (largest deviation of the first feature's vertices) − (of the
    // second's) − spread · (τ − time).
    struct Candidate {
        std::int32_t feature_a;
        std::int32_t feature_b;
        std::int32_t vertices[4];
        std::int32_t is_edge_edge;
        std::int64_t measured_call = -1;  // the project() call that measured measured_distance
        double distance;                  // at `time`
        double offset;                    // the deviations at `time`, summed as above
        double spread;                    // largest |u_i − u_j|, m/s
        double time;                      // s
        double measured_distance;         // at that call's positions before its pushes, m
    };
    // The vertices of a pair's two features: v[0 .. num_first) the first, v[num_first .. 4) the
    // second.
    struct FeatureVertices {
        std::int32_t v[4];
        std::size_t num_first;
    };
    // Pairs are indexed VF first, then EE: i < #VF is vertex_face[i], else edge_edge[i − #VF].
    FeatureVertices feature_vertices(const collision::FeaturePairs& pairs, std::int64_t i) const;
    static FeatureVertices feature_vertices(const Candidate& c) {
        return {{c.vertices[0], c.vertices[1], c.vertices[2], c.vertices[3]},
                c.is_edge_edge != 0 ? 2u : 1u};
    }

    // Throws InvalidInput when the last broad phase hit its pair limit or found more feature
    // pairs than MAX_FEATURE_PAIRS_PER_TRIANGLE per triangle (found: its pairs); the next
    // prepare() or enforce() then starts over with a full gather.
    void check_pair_limit(const collision::FeaturePairs& found);
    // The frame's translation at x: the componentwise median over sample vertices of their
    // displacement since the last gather (a falling sheet's motion; zero for a sheet that rests
    // while a part of it swings).
    Vec3d shift_of(std::span<const Vec3d> x) const;
    // Componentwise median of x[v] (minus the sample's position at the last gather when
    // from_origin) over the sample vertices.
    Vec3d median_of(std::span<const Vec3d> x, bool from_origin) const;
    // The sample vertices and their positions at x become the frame's origin.
    void reset_frame(std::span<const Vec3d> x);
    // Vertex v's deviation from its path at time τ (s) and position x, the frame at `shift`.
    double deviation(const Vec3d& x, const Vec3d& shift, double time, std::size_t v) const {
        return norm(x - shift - m_anchors[v] - m_path_velocities[v] * (time - m_anchor_times[v]));
    }
    // Whether v's path covers time τ and its deviation there is at most its slack less margin.
    bool within_path(const Vec3d& x, const Vec3d& shift, double time, std::size_t v,
                     double margin) const;
    // A candidate's distance bound at time τ given per-vertex deviations (a span, or a callable
    // from vertex index to deviation).
    template <typename Deviations>
    static double bound(const Candidate& c, const Deviations& deviations, double time) {
        return c.distance - c.offset - feature_sum(feature_vertices(c), deviations) -
               c.spread * (time - c.time);
    }
    // Largest per_vertex value over the first feature plus the largest over the second
    // (per_vertex: a span, or a callable from vertex index to value).
    template <typename PerVertex>
    static double feature_sum(const FeatureVertices& f, const PerVertex& per_vertex) {
        const auto at = [&](int k) {
            const auto v = static_cast<std::size_t>(f.v[k]);
            if constexpr (std::is_invocable_v<const PerVertex&, std::size_t>) {
                return static_cast<double>(per_vertex(v));
            } else {
                return static_cast<double>(per_vertex[v]);
            }
        };
        if (f.num_first == 1) {
            return at(0) + std::max({at(1), at(2), at(3)});
        }
        return std::max(at(0), at(1)) + std::max(at(2), at(3));
    }

    // Every vertex gets a path anchored at x (time τ, frame reset so that s(τ) = 0) with
    // velocity u[v]; full broad phase; the candidates are rebuilt.
    void gather(std::span<const Vec3d> x, std::span<const Vec3d> u, double time, double window_dt);
    // The vertices in m_new_path_vertices (ascending) get paths anchored at x (time τ, frame
    // translation `shift`) with velocities u[v]; their pairs are searched again and replace their
    // old candidates (for more than a quarter of the vertices, found by a full broad phase).
    void renew_paths(std::span<const Vec3d> x, const Vec3d& shift, std::span<const Vec3d> u,
                     double time);
    // Sets vertex v's path and box.
    void set_path(std::size_t v, const Vec3d& anchor, const Vec3d& velocity, double time);
    // Appends the pairs of `pairs` (a broad phase's, boxes at x / time τ / frame `shift`) that
    // can come within thickness as candidates; with `involving` non-empty, only pairs with a
    // vertex v where involving[v] != 0.
    void add_candidates(const collision::FeaturePairs& pairs, std::span<const Vec3d> x,
                        const Vec3d& shift, double time, std::span<const std::uint8_t> involving);
    // The vertices in m_escaped_now get boxes around their motion over the window (and around
    // it put back) and are marked escaped (and needing a path); the pairs that involve them are
    // searched (a partial broad phase, or a full one for many) and appended to m_escape_pairs.
    void search_escaped(std::span<const Vec3d> positions_t0, std::span<const Vec3d> positions,
                        const Vec3d& shift_t0, const Vec3d& shift, double margin);
    // Per triangle, its vertices' path positions at `time` and the box of their path velocities
    // (m_triangle_motions).
    void compute_triangle_motions(double time);
    // The broad phase's triangle-pair filter: false when no feature of triangles a and b can come
    // within thickness while their vertices follow their paths within their slacks.
    bool may_come_close(std::int32_t a, std::int32_t b) const;
    // The CCD rounds of step 3.
    void run_fail_safe(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                       std::span<Vec3d> velocities, const Vec3d& shift_t0, const Vec3d& shift,
                       double time, double margin);

    // The distance between pair i's features at x.
    static double features_distance(const FeatureVertices& f, std::span<const Vec3d> x);
    // Whether the distance at `start` minus the largest relative displacement (motion: per vertex,
    // end − start) of a vertex of one feature and one of the other exceeds threshold (box
    // distance first).
    static bool separation_exceeds(const FeatureVertices& f, std::span<const Vec3d> start,
                                   std::span<const Vec3d> motion, double threshold);
    // The i in [0, n) with keep(i), ascending (valid until the next call).
    template <typename Keep>
    const std::vector<std::int64_t>& indices_where(std::int64_t n, Keep&& keep);
    void add_broad_phase_times(const collision::BroadPhaseStats& broad);

    std::vector<geometry::Triangle> m_triangles;
    std::size_t m_num_vertices;
    double m_thickness;
    collision::SelfCollisionBroadPhase<double> m_broad_phase;
    const std::vector<geometry::Edge>* m_edges;  // m_broad_phase's topology

    bool m_has_gather = false;
    bool m_dense_contact = false;                           // windows_for_next_gather's state
    bool m_broad_phase_ready = false;                       // a full update ran
    double m_inflation = 0.0;                               // of the broad phase's boxes (m)
    double m_window_dt = 0.0;                               // s
    static constexpr std::size_t FRAME_SAMPLE_STRIDE = 16;  // every 16th vertex is a sample
    std::vector<std::int32_t> m_frame_samples;
    std::vector<Vec3d> m_frame_origin;  // the samples' positions at the last gather
    mutable std::vector<double> m_median_scratch;
    // Paths, per vertex (see the header comment).
    std::vector<Vec3d> m_anchors;
    std::vector<Vec3d> m_path_velocities;
    std::vector<double> m_anchor_times;  // s
    std::vector<double> m_path_ends;     // s
    std::vector<double> m_slacks;        // m
    std::vector<Vec3d> m_box_lo;         // the path's box grown by the slack, in the frame
    std::vector<Vec3d> m_box_hi;
    struct TriangleMotion {
        Vec3d p[3];        // its vertices' path positions at the time of the last
                           // compute_triangle_motions
        Vec3d u_lo, u_hi;  // path velocities
        double slack;      // largest slack, m
        double duration;   // time to the last path end, s
    };
    std::vector<TriangleMotion> m_triangle_motions;
    double m_filter_margin = 0.0;
    std::vector<Candidate> m_candidates;
    std::int64_t m_project_calls = 0;  // project() calls so far
    // The positions at the last project() call before its pushes (call m_project_calls − 1;
    // empty before the first).
    std::vector<Vec3d> m_measured_positions;
    std::vector<Candidate> m_scratch_candidates;
    ChunkedBuffer<Candidate> m_candidate_chunks;

    std::vector<double> m_deviations;  // per vertex, over a substep or a window
    // Per vertex, what add_candidates reads of it (one cache line).
    struct FilterVertex {
        Vec3d x;           // position, m
        double deviation;  // from its path, m
        Vec3d velocity;    // its path's, m/s
        double remaining;  // time left on its path, s (negative when it has ended)
    };
    std::vector<FilterVertex> m_filter_vertices;
    std::vector<Vec3d> m_window_motion;  // per vertex, end − start of the window
    std::vector<Vec3d> m_new_velocities;
    std::vector<std::int32_t> m_new_path_vertices;
    std::vector<std::uint8_t> m_marks;       // per vertex, scratch
    std::vector<std::uint8_t> m_needs_path;  // per vertex: escaped since its path was set
    std::vector<std::uint8_t> m_escaped;     // per vertex: escaped in the current window
    std::vector<std::int32_t> m_escaped_now;
    collision::FeaturePairs m_escape_pairs;  // pairs that involve an escaped vertex
    std::vector<std::uint8_t> m_reverted;
    std::vector<std::uint8_t> m_changed;
    ChunkedBuffer<std::int64_t> m_index_chunks;
    std::vector<std::int64_t> m_indices;
    SelfCollisionStats m_stats;
};

}  // namespace pliant::cloth
