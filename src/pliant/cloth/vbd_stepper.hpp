// VBDStepper: advances a ClothModel (cloth_model.hpp) by Vertex Block Descent (A. H. Chen,
// M. Macklin, C. Bi, Y. Liu, T.-Y. Kim, "Vertex Block Descent", SIGGRAPH 2024).
//
// Every substep h ending at time t minimises the variational (backward Euler) energy
//   G(x) = Σ_i m_i / (2 h²) |x_i − y_i|² + E(x),  y = x_t + h v_t + h² g  (inertia, §3.1)
// by block coordinate descent over the vertices: for each vertex i, with its neighbours held,
// one Newton step on its 3 unknowns, H_i Δx_i = f_i (§3.2, eq. 8–9), with
//   f_i = −(m_i / h²)(x_i − y_i) − Σ ∂E/∂x_i,   H_i = (m_i / h²) I + Σ ∂²E/∂x_i²
// (each term's Hessian made positive semi-definite). E has, per mesh edge, a spring
// ½ k (|x_i − x_j| − L)², k = 1 / material.stretch_compliance (XPBD's compliance is the inverse of
// this stiffness: the same material), and per hinge (two triangles sharing an edge) ½ k_b C²,
// k_b = 1 / material.bend_compliance, with C the isometric model's normal part on hinges flat at
// rest (isometric_bending.hpp; Gauss-Newton Hessian k_b K_k² n̂ n̂ᵀ) and C = θ − θ_rest on the
// others (dihedral.hpp; Gauss-Newton). Vertices are coloured (vertex_coloring.hpp) so that no two
// of a colour share an edge or hinge; a colour's vertices are updated in parallel, colour after
// colour (Gauss-Seidel), so results are bitwise identical for 1 and N threads. After its Newton
// step a vertex is pushed `thickness` out of the obstacles (a projected block descent step).
// Optional Chebyshev semi-iterative acceleration over the sweeps (§3.5; options.chebyshev_rho).
//
// After the sweeps: mesh obstacles over the whole substep (mesh_contact.hpp, as XPBDStepper: each
// vertex's path swept against the moving triangles, then each cloth edge against the surface's
// edges and each cloth triangle against its vertices, pushes bounded the same way), since the
// sweeps' push sees only where the surface is at the substep's end, and a triangle of a vertex
// these passes moved that still meets an obstacle goes where the substep began, carried with the
// obstacle (obstacle_put_back.hpp; with OGC after OGC's truncation); then the cloth's own
// contacts (self-collision: the same proximity projection, undo of pushes into obstacles and CCD
// fail-safe as XPBDStepper, self_collision.hpp, with a window of one substep), then
// v = (x − x_t) / h; at obstacle contacts the velocity relative to the surface loses its outward
// normal part (inelastic) and Coulomb friction acts on its tangential part, bounded by the
// normal speed the contact took away (obstacles.hpp, apply_friction); then
// v *= max(0, 1 − damping h).
//
// With options.ogc, self-contact is Offset Geometric Contact instead (ogc_contact.hpp): its
// contact energy joins every vertex's Newton step, every move of a vertex (the prediction, each
// Newton step after the obstacles' push, the Chebyshev extrapolation, the seams) is truncated to
// the vertex's bound, and a detection runs before a substep without one and after every sweep
// (or prediction) in which more than ogc.redetect_share of the free vertices hit their bound, or,
// in a substep whose pins left their sets, a ball held any vertex back; when a pin leaves its set
// the prediction's truncation follows a detection with the pins where they moved and the free
// vertices where the substep started (detail/ogc_step.hpp, pins_left_sets). No proximity projection
// and no per-substep fail-safe: the bounds keep the cloth intersection-free. With ogc.audit, the
// CCD fail-safe (ccd_fail_safe.hpp) stays as an audit and a fail-safe over windows that end at
// every detection and at the step's end (its stats: ccd_pairs, ccd_hits, reverted_vertices). Within
// a window every vertex stays in its feasible set, so the straight motion from the window's start
// to its end is free of contact (ogc_contact.hpp) and the CCD should clear it; a vertex it puts
// back at the step's end makes the next substep detect again.
//
// Units: SI. Not thread safe (one stepper per thread); step() parallelises internally.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/detail/ogc_audit_window.hpp"
#include "pliant/cloth/mesh_contact.hpp"
#include "pliant/cloth/obstacle_put_back.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/vertex_coloring.hpp"
#include "pliant/cloth/xpbd_stepper.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

struct VBDOptions {
    // Block descent sweeps (every vertex once) per substep, >= 1.
    int iterations = 10;
    // Chebyshev acceleration's estimate of the sweeps' spectral radius, in [0, 1): 0 is off.
    double chebyshev_rho = 0.0;
    // Self-contact by Offset Geometric Contact (ogc_contact.hpp) when set, else the XPBD path's
    // proximity projection and per-substep fail-safe.
    std::optional<OgcOptions> ogc;
};

class VBDStepper {
public:
    // The springs and hinges of `model`'s rest shape and the vertex colouring. InvalidInput for
    // invalid options.
    explicit VBDStepper(const ClothModel& model, const VBDOptions& options = {});

    // Self-collision handling as XPBDStepper::enable_self_collision (same limits).
    void enable_self_collision(const ClothModel& model, bool enabled);
    bool has_self_collision() const { return m_self_collision != nullptr; }
    // The OGC contact (options().ogc with self-collision on), or null.
    const OgcContact* ogc() const { return m_ogc.get(); }

    // Advances `model` by dt seconds in `substeps` substeps of options().iterations sweeps each.
    // InvalidInput: dt not finite and > 0, substeps < 1, a model of other vertex or triangle
    // counts.
    ClothStepStats step(ClothModel& model, double dt, int substeps);

    const VBDOptions& options() const { return m_options; }
    std::int32_t num_colors() const { return m_coloring.num_colors(); }
    std::size_t num_springs() const { return m_spring_rest.size() / 2; }
    std::size_t num_hinges() const { return m_hinge_vertices.size(); }

    // The state later steps read (self-collision's and its gather times); a stepper built for the
    // same model that loads it continues bit for bit. load_state: InvalidInput for a state of
    // another mesh or a truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(const ClothModel& model, ByteReader& in);

private:
    struct Hinge {
        std::array<double, 4> k{};  // isometric stencil (1/m), or unused for a dihedral hinge
        double rest_angle = 0.0;    // dihedral hinges (rad)
        bool is_dihedral = false;
    };

    // One substep of length h ending at t_end; returns the vertices in contact with an obstacle.
    std::int64_t substep(ClothModel& model, double h, double t_end, double& solve_ms);
    // The Newton step of vertex v (free) toward the minimum of G with its neighbours held, then
    // the obstacles' push.
    void solve_vertex(const ClothModel& model, std::size_t v, double h, std::span<Vec3d> x) const;
    // solve_vertex, the obstacles' push, and the hinges' b updated by the vertex's move.
    void update_vertex(const ClothModel& model, std::size_t v, double h, std::span<Vec3d> x);
    // Moves x (at `start` when the substep began) out of every obstacle (thickness); returns
    // whether it touches one, with the deepest contact's normal and surface velocity (m/s over h)
    // when normal is not null.
    // Mesh obstacles over the whole substep (mesh_contact.hpp: the swept vertex pass, then the
    // edge pass), after the block descent: its projection sees only where the surface is at the
    // substep's end, so a surface moving faster than the cloth, or a ridge passing between two
    // vertices, would cross it. Fills m_mesh_contacts (friction) and adds to the tallies.
    void resolve_mesh_obstacles(const ClothModel& model, std::span<Vec3d> positions, double h);
    bool push_out_of_obstacles(const ClothModel& model, Vec3d& x, const Vec3d& start, double h,
                               Vec3d* normal, Vec3d* surface_velocity) const;
    void restart_self_collision(const ClothModel& model);
    // OGC: truncates every free vertex's move from `from` to x to its bound (counted in
    // m_sweep_truncated, those the ball held back also in m_sweep_ball_held).
    void truncate_all(std::span<const Vec3d> from, std::span<Vec3d> x,
                      std::span<const double> inverse_masses);
    // OGC: takes the mesh-obstacle passes' corrections (from m_before_mesh_contacts to x) within
    // the bounds, with detections between rounds (MAX_PREDICTION_DETECTIONS at most) while held
    // back vertices still get on; x ends within its bounds. Thickness in m.
    void truncate_mesh_contacts(std::span<Vec3d> x, std::span<const double> inverse_masses,
                                double thickness);
    // OGC: counts vertex v, truncated to x, in m_sweep_truncated (and m_sweep_ball_held when x
    // is on its ball's sphere). Thread safe.
    void count_truncated(std::size_t v, const Vec3d& x);
    // OGC: after a sweep or the prediction, detects again (returns true) when too many vertices
    // hit their bound, or a ball held any back in a substep whose pins left their sets.
    bool redetect_if_needed(std::span<Vec3d> x);
    // OGC: the audit's window ends at x (ogc.audit), then a detection at x.
    void detect(std::span<Vec3d> x);
    // OGC: the CCD fail-safe over the motion from the audit window's start to x (velocities: of the
    // vertices it puts back, set to zero); returns whether it put any back. The next window starts
    // at x.
    bool audit(std::span<Vec3d> x, std::span<Vec3d> velocities);
    // The unit normals n̂ of the isometric hinges at positions x (zero for degenerate ones).
    void update_hinge_normals(std::span<const Vec3d> x);

    VBDOptions m_options;
    std::size_t m_num_vertices = 0;
    std::size_t m_num_triangles = 0;
    std::vector<double> m_rest_lengths;  // per mesh edge

    // Per vertex (CSR): its springs as (other vertex, rest length) and its hinges as hinge index
    // · 4 + its place in the hinge.
    std::vector<std::int32_t> m_spring_first;
    std::vector<std::int32_t> m_spring_other;
    std::vector<double> m_spring_rest;
    std::vector<std::int32_t> m_hinge_first;
    std::vector<std::int32_t> m_hinge_refs;
    std::vector<std::array<std::int32_t, 4>> m_hinge_vertices;  // x0, x1, x2, x3 (dihedral.hpp)
    std::vector<Hinge> m_hinges;
    // Per hinge reference, the vertex's isometric weight K_k (0 for a dihedral hinge).
    std::vector<double> m_hinge_ref_k;
    // Per isometric hinge: n̂ at the sweep's start and b = Σ K_k x_k now.
    struct HingeState {
        Vec3d normal;
        Vec3d b;
    };
    std::vector<HingeState> m_hinge_state;
    VertexColoring m_coloring;

    // Per substep.
    std::vector<Vec3d> m_start;     // x_t
    std::vector<Vec3d> m_inertia;   // y
    std::vector<Vec3d> m_previous;  // Chebyshev: the iterate two sweeps back
    std::vector<Vec3d> m_current;   // Chebyshev: the iterate one sweep back

    // Mesh obstacles (resolve_mesh_obstacles): per vertex the substep's contact (depth 0: none),
    // the positions before the pass, the edge pass's buffers, the largest lag of the last
    // substep (m; saved with the state) and this step's tallies.
    std::vector<MeshContact> m_mesh_contacts;
    std::vector<Vec3d> m_before_mesh_contacts;
    std::vector<Vec3d> m_mesh_contact_targets;  // OGC: the passes' corrections
    MeshFeatureContactScratch m_mesh_feature_contacts;
    double m_obstacle_lag = 0.0;
    std::int64_t m_step_swept = 0;
    std::int64_t m_step_edges = 0;
    std::int64_t m_step_faces = 0;
    // Triangles the passes left in a mesh obstacle, and self-contact pushes into an obstacle
    // (the positions before the self-contacts: m_before_self), are put back
    // (obstacle_put_back.hpp); the vertices moved in this step.
    ObstaclePutBack m_put_back;
    std::vector<Vec3d> m_before_self;
    std::int64_t m_step_carried = 0;
    std::int64_t m_step_pushes_undone = 0;
    std::int64_t m_substep_lagging = 0;
    double m_step_max_lag = 0.0;

    std::unique_ptr<SelfCollision> m_self_collision;
    std::unique_ptr<OgcContact> m_ogc;
    // OGC: positions where the audit's window starts (the step's start or the last detection),
    // and scratch velocities for an audit within a substep.
    detail::OgcAuditWindow m_audit;
    std::vector<Vec3d> m_audit_velocities;
    std::int64_t m_num_free = 0;  // OGC: free vertices (inverse mass > 0) in this step
    std::atomic<std::int64_t> m_sweep_truncated{0};  // OGC: vertices held back in this sweep
    std::atomic<std::int64_t> m_sweep_ball_held{0};  // OGC: of them, by their balls
    bool m_pins_left_sets = false;      // OGC: in this substep (detail::pins_left_sets)
    std::int64_t m_step_truncated = 0;  // OGC: summed over this step
    std::int64_t m_num_position_resets = 0;
    double m_gather_start_time = 0.0;
    double m_gather_end_time = -std::numeric_limits<double>::infinity();
};

}  // namespace pliant::cloth
