// SelfCollisionCandidates: the self-collision's kinetic candidate set (step 1 of
// self_collision.hpp): the pairs of cloth features that can come within `thickness` of each other
// while every vertex stays near a predicted path, kept across windows of substeps.
//
// The candidate pairs persist across windows: each vertex follows a predicted path, and the broad
// phase's boxes hold every point within a slack of those paths, so the candidates stay valid as
// long as every vertex stays within its slack; a vertex that leaves it (or reaches the end of its
// path) gets a new path, and only its pairs are searched again. A falling sheet keeps its paths
// for the whole fall (one broad phase); a draping one renews the paths of its moving parts.
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
// prepare(), at the start of one window, or of two while contact is sparse
// (windows_for_next_gather): the first gathers (every vertex gets a path, a full broad phase);
// later ones give new paths to the vertices that escaped (needs_path), whose path ends within the
// coming window(s) or that are predicted to leave their slack in it (their velocity's difference
// from the path's), drop their candidates and search their pairs again
// (SelfCollisionBroadPhase::update_vertices; a full broad phase for more than a quarter of the
// vertices). The fail-safe (ccd_fail_safe.hpp) searches the pairs of escaped vertices on their
// actual motion through search_motions() and marks them needing a path.
//
// Rounding: every test that clears a pair keeps a margin of 1e-9 (1 + the largest coordinate);
// the broad phase's float boxes are rounded outward.
//
// Memory guard: a broad phase that keeps more than 64 triangle pairs per triangle or finds more
// than 256 feature pairs per triangle (and more than 2^22 pairs in all) throws InvalidInput (the
// simulation diverged, or layers are packed far closer than their thickness); the next call then
// starts over with a full gather.
//
// Units: metres, seconds. Not thread safe; the kernels run in parallel inside, and every result
// is the same for any number of threads (pairs in order, chunks merged in order).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "pliant/cloth/detail/self_collision_pairs.hpp"
#include "pliant/cloth/self_collision_stats.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

class SelfCollisionCandidates {
public:
    using FeatureVertices = detail::FeatureVertices;

    // A candidate pair: its features (VF: vertex, face; EE: the two edges), their vertices (VF:
    // the vertex, then the face's; EE: edge a's, then edge b's), and its distance bound: at time
    // τ, distance − offset − (largest deviation of the first feature's vertices) − (of the
    // second's) − spread · (τ − time).
    struct Candidate {
        std::int32_t feature_a;
        std::int32_t feature_b;
        std::int32_t vertices[4];
        std::int32_t is_edge_edge;
        // The proximity projection's (SelfCollision::project) last measurement of the pair: the
        // call that made it and the distance then, before that call's pushes (m).
        std::int64_t measured_call = -1;
        double distance;  // at `time`
        double offset;    // the deviations at `time`, summed as above
        double spread;    // largest |u_i − u_j|, m/s
        double time;      // s
        double measured_distance;
    };

    // triangles: #T, indices into [0, num_vertices); thickness in metres.
    SelfCollisionCandidates(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
                            double thickness);
    // Not copyable or movable: m_edges points into the broad phase.
    SelfCollisionCandidates(const SelfCollisionCandidates&) = delete;
    SelfCollisionCandidates& operator=(const SelfCollisionCandidates&) = delete;

    // How many of the caller's fail-safe windows the next prepare() should cover: 2 while the
    // candidate pairs are few (fewer than the vertices, or after a dense phase fewer than an
    // eighth of them), which halves the broad phases of a draping sheet; 1 while contact is dense,
    // where a longer window's candidates (every pair that can close the gap over it) would cost
    // more in the projection and the fail-safe than the broad phase saved. Decided on counts only:
    // deterministic.
    int windows_for_next_gather();
    // Step 1 for the window starting at `time` (s) and lasting window_dt (s) (one or several of
    // the fail-safe's windows). positions, velocities: #V, at `time`.
    void prepare(std::span<const Vec3d> positions, std::span<const Vec3d> velocities, double time,
                 double window_dt, SelfCollisionStats& stats);

    // Whether the vertices have paths (a prepare() ran since the start or the last error).
    bool has_paths() const { return m_has_gather; }
    // Without paths: the frame starts at x, every vertex needs a path, no candidates (the
    // fail-safe then searches every vertex's motion).
    void start_without_paths(std::span<const Vec3d> x);
    std::span<Candidate> candidates() { return m_candidates; }
    std::span<const Candidate> candidates() const { return m_candidates; }

    // The frame's translation at x (#V): the componentwise median over sample vertices of their
    // displacement since the last gather (a falling sheet's motion; zero for a sheet that rests
    // while a part of it swings).
    Vec3d shift_of(std::span<const Vec3d> x) const;
    // Vertex v's deviation from its path at time τ (s) and position x, the frame at `shift`.
    double deviation(const Vec3d& x, const Vec3d& shift, double time, std::size_t v) const {
        return norm(x - shift - m_anchors[v] - m_path_velocities[v] * (time - m_anchor_times[v]));
    }
    // Whether v's path covers time τ and its deviation there is at most its slack + half the
    // thickness less margin: then v is inside its grown box, and pairs whose grown boxes do not
    // overlap cannot touch.
    bool within_path(const Vec3d& x, const Vec3d& shift, double time, std::size_t v,
                     double margin) const;
    // Whether v escaped since its path was set (search_motions).
    bool needs_path(std::size_t v) const { return m_needs_path[v] != 0; }
    // Whether p (in the frame) is inside v's box as the broad phase grew it (by its inflation),
    // less margin.
    bool box_holds(std::size_t v, const Vec3d& p, double margin) const;

    // Whether searching the motions of `count` vertices should be a full broad phase: with no
    // broad phase yet, or for more than a quarter of the vertices.
    bool full_search_pays(std::size_t count) const;
    // The vertices in `vertices` (all of them when full) get the boxes of their motion over a
    // window, from positions_t0 − shift_t0 to positions − shift (frame coordinates), and need new
    // paths; the broad phase runs on the changed boxes (full: every box, grown by `margin` only,
    // as thin as the CCD allows; else a partial update around `vertices`). Returns the broad
    // phase's pairs, valid until the next search or prepare(); the caller keeps those that
    // involve the vertices. InvalidInput on the memory guard.
    const collision::FeaturePairs& search_motions(std::span<const std::int32_t> vertices, bool full,
                                                  std::span<const Vec3d> positions_t0,
                                                  std::span<const Vec3d> positions,
                                                  const Vec3d& shift_t0, const Vec3d& shift,
                                                  double margin, SelfCollisionStats& stats);

    // Pair i of `pairs` (VF first, then EE: i < #VF is vertex_face[i], else edge_edge[i − #VF]).
    FeatureVertices feature_vertices(const collision::FeaturePairs& pairs, std::int64_t i) const {
        FeatureVertices f{};
        const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
        if (i < num_vf) {
            const collision::VertexFacePair& pair = pairs.vertex_face[static_cast<std::size_t>(i)];
            const geometry::Triangle& t = m_triangles[static_cast<std::size_t>(pair.face)];
            f.v[0] = pair.vertex;
            f.v[1] = t[0];
            f.v[2] = t[1];
            f.v[3] = t[2];
            f.num_first = 1;
        } else {
            const collision::EdgeEdgePair& pair =
                pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
            const geometry::Edge& a = (*m_edges)[static_cast<std::size_t>(pair.edge_a)];
            const geometry::Edge& b = (*m_edges)[static_cast<std::size_t>(pair.edge_b)];
            f.v[0] = a[0];
            f.v[1] = a[1];
            f.v[2] = b[0];
            f.v[3] = b[1];
            f.num_first = 2;
        }
        return f;
    }
    static FeatureVertices feature_vertices(const Candidate& c) {
        return {{c.vertices[0], c.vertices[1], c.vertices[2], c.vertices[3]},
                c.is_edge_edge != 0 ? 2u : 1u};
    }
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

    std::span<const geometry::Triangle> triangles() const { return m_triangles; }
    std::span<const geometry::Edge> edges() const { return *m_edges; }
    std::size_t num_vertices() const { return m_num_vertices; }
    double thickness() const { return m_thickness; }
    // The rounding margin of the last path search (1e-9 (1 + largest coordinate)), m.
    double filter_margin() const { return m_filter_margin; }

    // The state later steps read (core/bytes.hpp), so that a run resumed from a checkpoint
    // continues bit for bit; load_state: InvalidInput for a state of another mesh or a
    // truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    // Throws InvalidInput when the last broad phase hit its pair limit or found more feature
    // pairs than MAX_FEATURE_PAIRS_PER_TRIANGLE per triangle (found: its pairs); the next
    // prepare() or search then starts over with a full gather.
    void check_pair_limit(const collision::FeaturePairs& found);
    // Componentwise median of x[v] (minus the sample's position at the last gather when
    // from_origin) over the sample vertices.
    Vec3d median_of(std::span<const Vec3d> x, bool from_origin) const;
    // The sample vertices and their positions at x become the frame's origin.
    void reset_frame(std::span<const Vec3d> x);
    // Every vertex gets a path anchored at x (time τ, frame reset so that s(τ) = 0) with
    // velocity u[v]; full broad phase; the candidates are rebuilt.
    void gather(std::span<const Vec3d> x, std::span<const Vec3d> u, double time, double window_dt,
                SelfCollisionStats& stats);
    // The vertices in m_new_path_vertices (ascending) get paths anchored at x (time τ, frame
    // translation `shift`) with velocities u[v]; their pairs are searched again and replace their
    // old candidates (for more than a quarter of the vertices, found by a full broad phase).
    void renew_paths(std::span<const Vec3d> x, const Vec3d& shift, std::span<const Vec3d> u,
                     double time, SelfCollisionStats& stats);
    // Sets vertex v's path and box.
    void set_path(std::size_t v, const Vec3d& anchor, const Vec3d& velocity, double time);
    // Appends the pairs of `pairs` (a broad phase's, boxes at x / time τ / frame `shift`) that
    // can come within thickness as candidates; with `involving` non-empty, only pairs with a
    // vertex v where involving[v] != 0.
    void add_candidates(const collision::FeaturePairs& pairs, std::span<const Vec3d> x,
                        const Vec3d& shift, double time, std::span<const std::uint8_t> involving);
    // Per triangle, its vertices' path positions at `time` and the box of their path velocities
    // (m_triangle_motions).
    void compute_triangle_motions(double time);
    // The broad phase's triangle-pair filter: false when no feature of triangles a and b can come
    // within thickness while their vertices follow their paths within their slacks.
    bool may_come_close(std::int32_t a, std::int32_t b) const;
    void add_broad_phase_times(SelfCollisionStats& stats) const;

    std::vector<geometry::Triangle> m_triangles;
    std::size_t m_num_vertices;
    double m_thickness;
    collision::SelfCollisionBroadPhase<double> m_broad_phase;
    const std::vector<geometry::Edge>* m_edges;  // m_broad_phase's topology

    bool m_has_gather = false;
    bool m_dense_contact = false;      // windows_for_next_gather's state
    bool m_broad_phase_ready = false;  // a full update ran
    double m_inflation = 0.0;          // of the broad phase's boxes (m)
    double m_window_dt = 0.0;          // s
    // The frame: every FRAME_SAMPLE_STRIDE-th vertex is a sample.
    static constexpr std::size_t FRAME_SAMPLE_STRIDE = 16;
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
    std::vector<std::uint8_t> m_needs_path;  // per vertex: escaped since its path was set
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

    // Scratch.
    std::vector<Candidate> m_scratch_candidates;
    ChunkedBuffer<Candidate> m_candidate_chunks;
    // Per vertex, what add_candidates reads of it (one cache line).
    struct FilterVertex {
        Vec3d x;           // position, m
        double deviation;  // from its path, m
        Vec3d velocity;    // its path's, m/s
        double remaining;  // time left on its path, s (negative when it has ended)
    };
    std::vector<FilterVertex> m_filter_vertices;
    std::vector<Vec3d> m_new_velocities;
    std::vector<std::int32_t> m_new_path_vertices;
    std::vector<std::uint8_t> m_marks;
    detail::IndexFilter m_index_filter;
};

}  // namespace pliant::cloth
