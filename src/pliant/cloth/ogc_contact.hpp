// OgcContact: the cloth's self-contact for the VBD stepper (vbd_stepper.hpp) by Offset Geometric
// Contact (A. H. Chen, J. Hsu, Z. Liu, M. Macklin, Y. Yang, C. Yuksel, "Offset Geometric
// Contact", SIGGRAPH 2025): a contact energy on the offset geometry in every vertex's Newton step,
// and per-vertex conservative displacement bounds that keep the cloth free of intersections
// without continuous collision detection.
//
//   detection (detect(x), x intersection-free): every non-incident vertex-face and edge-edge
//      pair (collision/self_broad_phase.hpp: LBVH + representative triangles + orphan sets, boxes
//      grown by r_q / 2) whose distance d at x is below the query radius r_q = query_factor · r
//      (triangle pairs, then feature pairs, whose separating-axis lower bound on the distance,
//      detail/pair_bounds.hpp, reaches r_q are dropped before any exact distance).
//      Each kept pair has a separating plane: normal n̂ along the closest points (from the second
//      feature to the first), through their midpoint c; every vertex of the first feature lies at
//      least d / 2 on n̂'s side, every vertex of the second at least d / 2 on the other (the plane
//      that halves the segment of closest points of two convex sets separates them).
//   bounds. Vertex v's feasible set at a frame shift S (below) is the intersection of
//      - the ball of radius b = bound_share · r_q around x_v + S (the paper's b_v = γ_p d_min,v
//        with d_min,v capped at r_q, §4: pairs farther than r_q at detection, each of whose
//        vertices moves at most b < r_q / 2, stay at least (1 − 2 bound_share) r_q > 0 apart);
//      - for every detected pair of v, the half-space of its side of the pair's plane, less
//        PLANE_MARGIN · d / 2 (planar truncation: the paper's refinement that bounds only the
//        motion toward the contact, so a vertex slides along a contact without the isotropic
//        bound's damping). Two features that stay on their sides of one fixed plane do not touch.
//      The set is convex and holds x_v + S. truncate() shortens a vertex's move, from a point of
//      its set, to the farthest point of the set on the move's segment (the paper's truncation of
//      the displacement, with an exact line search on the ball and the planes). Every vertex moves
//      from a point of its set to a point of its set, alone or with others of its colour; and
//      between substeps all vertices move together from their sets at S to their sets at S': every
//      configuration in between lies in the sets at a shift between (the sets are convex), so no
//      two features ever touch: the cloth stays intersection-free for any motion the solver makes.
//   frame shift. Distances do not change when every vertex is translated by the same vector, so
//      the sets are centred at the detection's positions plus a shift S shared by all vertices:
//      set_shift() takes the componentwise median, over every 16th free vertex, of a predicted
//      position less its detection position, when every vertex's prediction (a pinned vertex's:
//      its position) lies in its set at that shift (a falling sheet keeps its detection); else S
//      stays as it was (the vertices' positions are in their sets at S; moving all sets by a shift
//      some vertices do not follow would drag those along). Between substeps every vertex moves
//      from its set at S to its set at S' (the sets are translates of one convex set, so every
//      point between lies in the set at the shift between).
//   contact energy (§3): for a detected pair at distance d < r (current positions),
//      E = ½ k_c (r − d)², quadratic and barrier-free; on vertex i of the pair with weight w_i of
//      the closest point (barycentric or segment parameter, sign by the feature's side) the force
//      is k_c (r − d) w_i n̂ and the Hessian k_c w_i² n̂ n̂ᵀ (Gauss-Newton, positive
//      semi-definite). The partners' positions are read from a snapshot taken at the start of each
//      sweep (snapshot()), so that vertices of one colour solved in parallel read no position
//      another thread writes: results are bitwise identical for 1 and N threads.
//   re-detection: the caller counts the vertices truncate() held back in a sweep and calls
//      detect() again when they exceed redetect_share of the free vertices, and, in a substep
//      whose pins left their sets, when the ball (not a plane: at_ball()) held back any vertex:
//      pins drive the vertices beside them, too few for the share, and without a detection those
//      would stay held back for good while the pins move on. XPBD then truncates the move again
//      from the new detection (XPBDStepper::catch_up), VBD's next sweep moves on from it. A
//      settled sheet keeps one detection for many substeps.
//   wide radius (wide_query_factor w, off by default): while the truncations ask for detections
//      every substep or two (the cloth moves against itself faster than the ball per substep:
//      the drape's impact, where the sphere stops part of the sheet and the rest falls on), the
//      detections use r_w = w r and the ball b_w = (r_w − (1 − 2 bound_share) r_q) / 2: pairs
//      left out still keep (1 − 2 bound_share) r_q apart, and the larger ball lets the sheet
//      move on for several substeps per detection. A wide detection costs more (it keeps the
//      in-plane neighbours one ring out), so the radius returns to r_q after a hold (redetect()).
//
// XPBD (xpbd_stepper.hpp) uses the detection and the bounds with a hard constraint instead of the
// energy: project() pushes every detected pair closer than r apart to r along its normal (XPBD
// with zero compliance, as the proximity projection of self_collision.hpp), pair after pair.
//
// Pinned vertices follow their pins untruncated. A pin that leaves its set breaks the bounds'
// guarantee for its pairs, so the steppers detect again before the substep goes on
// (detail/ogc_step.hpp, pins_left_sets): with every pinned vertex at its new position and every
// free vertex where the substep started, so that the pins are at the centres of their sets and
// the free vertices beside them can follow them by a whole ball. A pin that moves farther than
// the ball in one substep, or whose motion alone brings two features together, is caught only by
// the CCD audit (vbd_stepper.hpp).
//
// Units: metres. Not thread safe except truncate() and add_forces() (const, read only).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "pliant/cloth/detail/sym3.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

struct OgcOptions {
    // Contact radius r (m); 0: the material's thickness.
    double radius = 0.0;
    // Query radius r_q = query_factor · r, >= 1. With bound_share, pairs not detected stay at
    // least (1 − 2 bound_share) r_q apart: the defaults keep every pair that can come within r
    // under the contact energy.
    double query_factor = 2.0;
    // The ball's radius bound_share · r_q, in (0, 0.5).
    double bound_share = 0.25;
    // A wider query radius while the cloth moves fast against itself: r_w = wide_query_factor · r
    // (0: off; else >= query_factor), its ball b_w = r_w / 2 − (1 − 2 bound_share) r_q / 2, so
    // that pairs not detected keep the same distance (1 − 2 bound_share) r_q. A ball that covers
    // a substep's relative motion lets the sheet move on between detections instead of being
    // held back every substep (the drape's impact); see redetect().
    double wide_query_factor = 0.0;
    // Re-detect when more than this share of the free vertices hit their bound in a sweep, in
    // [0, 1].
    double redetect_share = 0.01;
    // Contact stiffness k_c (N/m); 0: the stretch springs' stiffness (1 / stretch compliance).
    double stiffness = 0.0;
    // Keep the CCD fail-safe as an audit (VBDStepper, vbd_stepper.hpp).
    bool audit = true;
};

class OgcContact {
public:
    // A plane of a vertex's feasible set: dot(normal, x − S) >= offset.
    struct Plane {
        Vec3d normal;
        double offset;
    };
    // A detected pair: VF (vertex, face's three) or EE (edge a's two, edge b's two).
    struct Pair {
        std::int32_t v[4];
        bool is_edge_edge;
        std::int32_t face = -1;  // vertex-face: the face's index (v[1..3] are its corners)
    };

    // The fraction of d / 2 a vertex keeps from its pair's plane.
    static constexpr double PLANE_MARGIN = 0.1;
    // redetect(): the wide radius's trigger and hold, in substeps.
    static constexpr std::int64_t WIDE_TRIGGER_SUBSTEPS = 2;
    static constexpr std::int64_t WIDE_HOLD_SUBSTEPS = 40;

    // triangles: #T, indices into [0, num_vertices); radius r (m, > 0); stiffness k_c (N/m, > 0).
    // InvalidInput for options out of range.
    OgcContact(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
               const OgcOptions& options, double radius, double stiffness);

    // InvalidInput unless radius >= 0, query_factor >= 1, 0 < bound_share < 0.5,
    // 0 <= redetect_share <= 1, stiffness >= 0 and wide_query_factor 0 or >= query_factor (all
    // finite).
    static void check_options(const OgcOptions& options);

    // Detection at x (#V, intersection-free): pairs, planes; the shift restarts at zero. The
    // query radius and ball are the wide ones while the wide hold lasts (redetect()), else the
    // base ones. InvalidInput when the pairs exceed the memory guard (a diverged simulation).
    void detect(std::span<const Vec3d> x);
    // The detection the truncations asked for (more than redetect_share of the free vertices
    // held back). With wide_query_factor, one that comes at most WIDE_TRIGGER_SUBSTEPS substeps
    // after the previous such detection (the base ball is shorter than the motion of a substep
    // or two) starts a hold of WIDE_HOLD_SUBSTEPS substeps in which detections use the wide
    // radius; after the hold the next detection is a base one again. Detections that pins or
    // fail-safes ask for (detect()) do not count: their motion is the pins'. XPBDStepper calls it
    // (VBDStepper rejects wide_query_factor: it detects several times within a substep).
    void redetect(std::span<const Vec3d> x);
    // Once at the start of every substep (the wide hold counts substeps).
    void begin_substep();
    // Whether the current detection used the wide radius; wide detections since construction.
    bool wide() const { return m_wide; }
    std::int64_t wide_detections() const { return m_wide_detections; }
    bool has_detection() const { return m_has_detection; }
    // The next substep must detect first (after a fail-safe moved vertices).
    void invalidate() { m_has_detection = false; }

    // S from predicted positions (#V): the median shift of the free vertices' (inverse_masses >
    // 0) when every vertex's prediction, the pinned vertices' included, lies in its set at that
    // shift (returns true), else S stays (a shift that some vertices do not follow would drag
    // them along, or leave a pin outside its set).
    bool set_shift(std::span<const Vec3d> predicted, std::span<const double> inverse_masses);
    // Vertex v's move from `from` (in its feasible set) to x, truncated where it leaves the set:
    // x becomes the farthest point of the segment inside the set (from the set's centre when
    // `from` is outside it); returns whether x moved.
    bool truncate(std::size_t v, const Vec3d& from, Vec3d& x) const;
    // Whether x lies in v's feasible set.
    bool feasible(std::size_t v, const Vec3d& x) const;
    // Whether x lies on (or beyond) the sphere of v's ball: where truncate() leaves a vertex the
    // ball held back, rather than one of its planes (to a millionth of the radius).
    bool at_ball(std::size_t v, const Vec3d& x) const;
    // The positions of the vertices in contact pairs (#V) for add_forces(), once per sweep.
    void snapshot(std::span<const Vec3d> x);
    // Adds the contact energy's force (−∂E/∂x_v) and Hessian on vertex v at x_v (its partners at
    // the snapshot), E = ½ k_c (r − d)² per contact closer than r. Every contact counts once,
    // whatever the pairs that see it (the offset geometry's blocks, Chen et al. 2025, §4): a
    // vertex-face pair whose closest point is the face's interior; on an edge, only for the
    // edge's lowest-indexed face; on a corner, only for the corner's lowest-indexed face and
    // when the vertex's index is below the corner's (the pair the other way round speaks for
    // it otherwise); an edge-edge pair only when both closest points are inside their edges
    // (an end's contact is a vertex-face pair's). Stacked cloth whose vertices lie over vertices
    // would otherwise have each contact counted by up to 48 pairs. With friction μ > 0 also the
    // smoothed Coulomb friction of every such pair (Chen et al., "Vertex Block Descent", SIGGRAPH
    // 2024, §3.6, after IPC, Li et al. 2020, §5; λ and n̂ of the current iterate, not lagged from
    // the substep's start): u is the pair's relative tangential
    // displacement since `start` (#V, the substep's start; the closest points' weights on the
    // four vertices' moves, projected on the plane of the normal n̂), λ = k_c (r − d) the normal
    // force, and the force on v is −μ λ w_v f₁(|u|) u / |u| with f₁(y) = 2y/ε − y²/ε² below the
    // slip ε (m, > 0: sticking) and 1 above (sliding), its Hessian μ λ w_v² f₁(|u|)/|u| (I − n̂n̂ᵀ).
    void add_forces(std::size_t v, const Vec3d& x_v, std::span<const Vec3d> start, double friction,
                    double slip, Vec3d& force, detail::Sym3& hessian) const;

    // XPBD's contact constraint: every detected pair closer than r at positions x (#V) is pushed
    // apart to r along its normal, the push split by the closest point's weights and the inverse
    // masses (Δλ = (r − d) / Σ w_k b_k²), then Coulomb friction on the pair's relative tangential
    // motion since `previous` (#V): cancelled when at most static_friction × the push, else
    // shortened by kinetic_friction × the push (self_collision.hpp's rule). The normal is the
    // closest points' unless it points against the detection's (the features crossed the
    // detection's plane: the pair is pushed back along the detection's normal). Pairs closer than
    // r are found in parallel, then pushed sequentially in pair order: bitwise identical for any
    // number of threads. A pair whose distance at the detection less its features' largest
    // deviations from the shifted detection (a feature's distance moves by at most that) is at
    // least r is skipped without a proximity test, and so is one whose distance at the detection
    // less its vertices' largest relative motion since (max |u_i − u_j|, u = x − detected) is at
    // least r; a pair none of whose vertices deviates by its slack (half the least margin d − r
    // of its pairs at the detection) is not even looked at: a substep's cost follows the vertices
    // that moved, not the pairs (a larger query radius keeps every vertex's in-plane neighbours
    // one ring out). The pairs pushed are those a proximity test of every pair finds. Returns the
    // pairs pushed.
    std::int64_t project(std::span<Vec3d> x, std::span<const Vec3d> previous,
                         std::span<const double> inverse_masses, double static_friction,
                         double kinetic_friction);

    // Inelastic contact: for every detected pair closer than r at positions x (#V), the part of
    // the velocities' relative normal motion that separates the pair is removed (an impulse split
    // by the closest point's weights and the inverse masses), pair after pair in their order.
    // Velocities only: the bounds are untouched. Returns the pairs changed.
    std::int64_t remove_separating_velocity(std::span<const Vec3d> x, std::span<Vec3d> velocities,
                                            std::span<const double> inverse_masses) const;

    double radius() const { return m_radius; }
    double query_radius() const { return m_query_radius; }
    double ball_radius() const { return m_ball_radius; }
    const OgcOptions& options() const { return m_options; }
    std::size_t num_pairs() const { return m_pairs.size(); }
    // Pairs closer than r at the last detection.
    std::int64_t close_pairs() const { return m_close_pairs; }
    std::span<const Pair> pairs() const { return m_pairs; }
    // The positions of the last detection (#V; empty before one) and the frame shift S.
    std::span<const Vec3d> detected_positions() const { return m_detected; }
    const Vec3d& shift() const { return m_shift; }
    // Per vertex (#V, empty before a detection): half the least margin d − r of its pairs at the
    // detection less 1e-14 d (+∞ without pairs): while each vertex of a pair deviates less than
    // its slack from its shifted detection position, the pair stays at least r apart.
    std::span<const double> slacks() const { return m_slack; }
    // Detections since construction.
    std::int64_t detections() const { return m_detections; }
    // Wall-clock time of the detections since construction (ms).
    double detect_ms() const { return m_detect_ms; }

    // The state later steps read: the detection's positions (the pairs and planes are derived
    // from them) and the frame shift; load_state: InvalidInput for another mesh or a truncated
    // state.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    // Whether a pair closer than r speaks for its contact in the energy (add_forces), given its
    // PairGeometry region.
    bool counts_once(const Pair& pair, int region) const;

    OgcOptions m_options;
    std::size_t m_num_vertices;
    double m_radius;
    double m_query_radius;  // of the current detection
    double m_ball_radius;   // of the current detection
    double m_base_query_radius;
    double m_base_ball_radius;
    double m_wide_query_radius;  // the base ones without wide_query_factor
    double m_wide_ball_radius;
    bool m_wide = false;  // the current detection is a wide one
    std::int64_t m_wide_detections = 0;
    std::int64_t m_since_redetect = std::numeric_limits<std::int64_t>::max() / 2;  // substeps
    std::int64_t m_wide_hold = 0;  // substeps left in the wide hold
    double m_stiffness;
    collision::SelfCollisionBroadPhase<double> m_broad_phase;
    std::vector<geometry::Triangle> m_triangles;
    // Per face, the features it speaks for in the contact energy (add_forces: every contact
    // once): bit k its edge k (corners k, k + 1), bit 3 + k its corner k, set when it is that
    // feature's lowest-indexed triangle.
    std::vector<std::uint8_t> m_owned_features;

    bool m_has_detection = false;
    std::int64_t m_detections = 0;
    double m_detect_ms = 0.0;
    std::int64_t m_close_pairs = 0;
    std::vector<Vec3d> m_detected;  // #V, positions at the detection
    Vec3d m_shift{0.0, 0.0, 0.0};
    std::vector<Pair> m_pairs;
    std::vector<Vec3d> m_pair_normals;     // per pair, its normal at the detection
    std::vector<double> m_pair_distances;  // per pair, its distance at the detection
    std::vector<double> m_deviations;      // project(): |x_v − (detected_v + S)| per vertex
    std::vector<std::uint8_t> m_close;     // project(): per pair tested, closer than r
    std::vector<std::uint64_t> m_marks;    // project(): a bit per pair, zero between calls
    std::vector<double> m_slack;           // per vertex: its pairs are tested from this deviation
    std::vector<std::int32_t> m_tested;    // project(): the pairs tested, ascending
    // Per vertex (CSR): the planes its ball can reach (of its pairs', in pair order), and its
    // pairs as pair index · 4 + its place in the pair.
    std::vector<std::int32_t> m_plane_first;
    std::vector<Plane> m_planes;
    std::vector<std::int32_t> m_pair_first;
    std::vector<std::int32_t> m_pair_refs;
    std::vector<std::int32_t> m_contact_vertices;  // vertices in some pair, ascending
    std::vector<Vec3d> m_snapshot;                 // #V, valid at m_contact_vertices
    // Scratch for detection.
    std::vector<double> m_distances;
    std::vector<std::array<Vec3d, 3>> m_geometry;  // per broad-phase pair: points and normal
};

}  // namespace pliant::cloth
