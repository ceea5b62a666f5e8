// XPBDStepper: advances a ClothModel (cloth_model.hpp) by XPBD with small substeps.
//
// Method: extended position-based dynamics (Macklin, Müller, Chentanez, "XPBD", MIG 2016) run as
// many small substeps with one constraint iteration each (Macklin, Storey, Lu, Terdiman,
// Chentanez, Jeschke, Müller, "Small Steps in Physics Simulation", SCA 2019). Every substep h
// ending at time t:
//   1. predict: v += h (g + f_air / m); x_previous = x; x += h v for the free vertices; pinned and
//      grabbed vertices (inverse mass 0) are placed where their motion has them at t
//      (ClothModel::move_pins; motion.hpp; air: air.hpp);
//   2. stretch: with material.strain_limit, first the coarse strain limits, coarsest level first,
//      carried down to every vertex (strain_hierarchy.hpp); with material.stretch_solver =
//      chains, the chains of edges, each solved as a whole, family after family
//      (stretch_chains.hpp); then C = |x_i - x_j| - L for every mesh edge, compliance α
//      (material.hpp);
//   3. bending, per interior edge (hinge): with material.bending = isometric, on
//      hinges flat at rest the normal part of the isometric model's linear C = Σ K_k x_k
//      (isometric_bending.hpp), on the others C = θ - θ_rest, θ the dihedral angle
//      (dihedral.hpp); for each constraint Δλ = -C / (Σ w_k |∇C_k|² + α / h²), x_k += w_k ∇C_k Δλ
//      (λ starts at 0 every substep: one iteration per substep);
//   3b. seams (seams.hpp), pair after pair;
//   4. obstacles, placed at t (ClothModel::move_obstacles): every vertex is pushed `thickness`
//      away from every obstacle (obstacles.hpp, mesh_obstacle.hpp); with mesh obstacles, then the
//      cloth's edges and triangles swept against the surface's edges and vertices
//      (mesh_contact.hpp); a triangle of a vertex these passes moved that still meets a mesh
//      obstacle goes where the substep began, carried with the obstacle (obstacle_put_back.hpp;
//      with OGC after OGC's truncation, and a triangle that cannot go there goes where these
//      passes left it, with a detection at the substep's end whose audit checks the move:
//      release_stuck_triangles);
//   (with self-collision: after 4, the cloth's own contacts are pushed thickness apart, and a
//   vertex whose push took one of its triangles into an obstacle is put back where 4 left it
//   (obstacle_put_back.hpp, Fallback::reference); the CCD
//   fail-safe runs after every 4 substeps (a window) on the motion of those 4 substeps, and the
//   candidate pairs are gathered before every window or, while contact is sparse, every second
//   one; self_collision.hpp; with mesh obstacles, the triangles of vertices the fail-safe put
//   back that meet an obstacle go where the obstacle's motion over the window carries their
//   start, and the fail-safe checks the window again: enforce_window)
//   5. v = (x - x_previous) / h, less the part of an obstacle's push that undid a penetration
//      the vertex began the substep with (cloth given inside an obstacle comes out without being
//      thrown); Coulomb friction on the velocities of vertices in contact (relative to the
//      obstacle surface's velocity), bounded by the rest of their normal correction / h
//      (obstacles.hpp: at the velocity level, friction never cancels a constraint's correction,
//      which positional friction does, locking stretched cloth on a rough surface); then v *=
//      max(0, 1 - damping h).
// With OGC contact (set_ogc; ogc_contact.hpp: Offset Geometric Contact, Chen et al., SIGGRAPH
// 2025), self-collision is instead: a detection (pairs within the query radius, their separating
// planes, each vertex's conservative bound) before a substep without one; after 1, the frame
// shift from the prediction, a detection first if a pin left its set (with the pins where they
// moved and the free vertices where the substep started, detail::pins_left_sets), and every free
// vertex's move truncated to its bound; after 4, every detected pair closer than the contact
// radius pushed apart to it (OgcContact::project, with the self-friction; with mesh obstacles a
// push that took a triangle into one undone, as on the proximity path), then every free
// vertex's move since the truncated prediction truncated again; in a substep whose pins left
// their sets, after each of the two truncations, detections from the truncated positions that
// let the vertices the balls held back go on toward where the substep took them (catch_up);
// after 5, a detection when the vertices held back in
// the substep's two truncations (a vertex held back in both counts twice) exceed redetect_share of
// the free vertices. Every vertex stays in its feasible set between detections, so the cloth stays
// intersection-free for any motion the substeps make, with no gather and no per-window fail-safe:
// the cost follows how far the cloth moves, not the substep count. With ogc.audit the CCD fail-safe
// (ccd_fail_safe.hpp) runs as an audit and a fail-safe over windows that end at every detection and
// at the step's end (its stats: ccd_pairs, ccd_hits, reverted_vertices); a vertex it puts back at
// the step's end makes the next substep detect first.
//
// Constraints of a kind are projected colour by colour (constraint_coloring.hpp), each colour in
// parallel: Gauss-Seidel across colours, and results bitwise identical for 1 and N threads. The
// projections are the kernels of detail/constraint_kernels.hpp (four constraints at a time with
// AVX2 where the CPU has it, the same bits as their scalar versions).
//
// Convergence: one iteration per substep makes stiff constraints as stiff as the substeps allow,
// so with single edges strain under load falls with the substep count: a 1.2 m sheet of 24 × 24
// quads resting over a sphere with friction keeps every edge within 7 % of its rest length at 40
// substeps per frame (24 frames per second), and stretches more at fewer substeps.
// material.stretch_solver = chains (the default) carries a correction along whole chains of
// edges at once: the same sheet within 1.2 % (tests/cloth/solver_test.cpp); a heavy 1 m strip
// (2 kg/m²) hanging at 12 substeps 12.5 % longer than at rest with single edges, 0.3 % with
// chains (tests/cloth/stretch_chains_test.cpp). material.strain_limit bounds the
// stretch of long paths (the same strip: 3.3 % with a limit of 0.03;
// tests/cloth/strain_hierarchy_test.cpp).
//
// The constraints come from the model's rest shape, topology and material when the stepper is
// built; step() takes that model (the vertex and triangle counts are checked). When the model's
// positions were replaced from outside (ClothModel::num_position_resets), self-collision starts
// over at the next step.
//
// Units: SI (metres, seconds, kilograms). Not thread safe (one stepper per thread); step()
// parallelises internally.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/constraint_coloring.hpp"
#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/cloth/detail/ogc_audit_window.hpp"
#include "pliant/cloth/mesh_contact.hpp"
#include "pliant/cloth/obstacle_put_back.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/strain_hierarchy.hpp"
#include "pliant/cloth/stretch_chains.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

struct ClothStepStats {
    double ms = 0.0;        // wall-clock time of the step
    double solve_ms = 0.0;  // prediction, stretch, bending, air, obstacles, velocities, friction
    std::int64_t obstacle_contacts = 0;  // vertices in contact with an obstacle in the last substep
    // Vertices a mesh obstacle's swept test (mesh_contact.hpp) caught, summed over the substeps.
    std::int64_t obstacle_swept_contacts = 0;
    // Cloth edges a mesh obstacle's edges met while entering it (mesh_contact.hpp,
    // resolve_mesh_edge_contacts) and that were lifted out, summed over the substeps.
    std::int64_t obstacle_edge_contacts = 0;
    // Cloth triangles a mesh obstacle's vertices met while entering them (mesh_contact.hpp,
    // resolve_mesh_face_contacts) and that were lifted off, summed over the substeps.
    std::int64_t obstacle_face_contacts = 0;
    // Vertices of cloth triangles that the obstacle passes left in an obstacle, put back where
    // they started the substep, carried with the obstacle (obstacle_put_back.hpp), and of
    // triangles the fail-safe put back into one, carried over its window (enforce_window),
    // summed over the substeps.
    std::int64_t obstacle_carried = 0;
    // Vertices put back where they were before the self-contacts because their pushes took a
    // cloth triangle into an obstacle (the proximity contact, and OGC's with mesh obstacles),
    // summed over the substeps.
    std::int64_t obstacle_pushes_undone = 0;
    // Obstacles that jump: the farthest an obstacle's surface moved in one substep (m), the free
    // vertices whose push out of an obstacle was bounded in the last substep (with
    // self-collision, half the thickness per substep beyond the vertex's own motion and the
    // thickness) and the largest push held back in a substep (m).
    double obstacle_max_step = 0.0;
    std::int64_t obstacles_lagging = 0;
    double obstacle_max_lag = 0.0;
    std::int64_t solver_sweeps = 0;   // VBD (vbd_stepper.hpp): sweeps over the vertices; else 0
    bool has_self_collision = false;  // the fields below are filled
    SelfCollisionStats self;          // self_collision.hpp
    // OGC contact (ogc_contact.hpp): detections in the step (those with the wide query radius),
    // vertices held back by their bounds (summed over moves), pairs within the query radius and
    // within the contact radius at the last detection.
    bool has_ogc = false;
    std::int64_t ogc_detections = 0;
    std::int64_t ogc_wide_detections = 0;
    std::int64_t ogc_truncated = 0;
    std::int64_t ogc_pairs = 0;
    std::int64_t ogc_close_pairs = 0;
    double ogc_detect_ms = 0.0;  // the detections' time
    // The CCD audit's windows in the step: on the detection's pairs alone, and by the full
    // fail-safe (detail/ogc_step.hpp, audit_ogc_window).
    std::int64_t ogc_pair_audits = 0;
    std::int64_t ogc_full_audits = 0;
};

class XPBDStepper {
public:
    // The constraints of `model`'s rest shape (stretch per edge, bending per interior edge,
    // chains and strain limits as model.material() asks). InvalidInput when the chains need more
    // than 64 families (stretch_chains.hpp) or the colouring more than 64 colours.
    explicit XPBDStepper(const ClothModel& model);

    // Self-collision handling (self_collision.hpp) for `model`: proximity constraints every
    // substep and the CCD fail-safe at the end of every window, so that no step ends with
    // intersecting triangles when it started without. Off by default. InvalidInput when the
    // thickness exceeds 4 median edge lengths (every triangle within reach of hundreds).
    void enable_self_collision(const ClothModel& model, bool enabled);
    bool has_self_collision() const { return m_self_collision != nullptr; }
    // Self-contact by Offset Geometric Contact instead of the proximity constraints and gathers
    // (the header's "With OGC contact") while self-collision is on; nullopt: the proximity path.
    // InvalidInput for invalid options (OgcContact::check_options). Self-collision starts over.
    void set_ogc(const ClothModel& model, const std::optional<OgcOptions>& options);
    // The OGC contact (set_ogc with self-collision on), or null.
    const OgcContact* ogc() const { return m_ogc.get(); }

    // Advances `model` (the one the stepper was built from) by dt seconds in `substeps` equal
    // substeps. InvalidInput: dt not finite and > 0, substeps < 1, a model of other vertex or
    // triangle counts.
    ClothStepStats step(ClothModel& model, double dt, int substeps);

    std::size_t num_stretch_constraints() const { return m_stretch_vertices.size(); }
    // Chains the stretch constraints are solved in (0 unless material.stretch_solver = chains;
    // stretch_chains.hpp).
    std::size_t num_stretch_chains() const {
        return static_cast<std::size_t>(m_chains.num_chains());
    }
    // Coarse strain limits (0 unless material.strain_limit is finite; strain_hierarchy.hpp).
    std::size_t num_strain_limits() const { return m_strain_hierarchy.num_limits(); }
    // Bending constraints: dihedral plus isometric (material.bending).
    std::size_t num_bending_constraints() const { return m_dihedral.size() + m_isometric.size(); }
    std::size_t num_isometric_bending_constraints() const { return m_isometric.size(); }

    // The state later steps read, between steps (core/bytes.hpp): the per-substep buffers,
    // self-collision's whole state (candidates, paths, broad phase, fail-safe) and its window
    // and gather times; not the constraints the constructor derives from the model. A stepper
    // built for the same model that loads it continues bit for bit. load_state: InvalidInput for
    // a state of another mesh or a truncated one (the stepper is then unusable).
    void save_state(ByteWriter& out) const;
    void load_state(const ClothModel& model, ByteReader& in);

private:
    // Obstacle contacts of a substep (sums and maxima: the same for any number of threads).
    struct ObstacleTally {
        std::int64_t contacts = 0;  // vertices in contact
        std::int64_t swept = 0;     // vertices a mesh obstacle's swept test caught
        std::int64_t edges = 0;     // cloth edges a mesh obstacle's edges met (edge pass)
        std::int64_t faces = 0;     // cloth triangles a mesh obstacle's vertices met (face pass)
        std::int64_t carried = 0;   // vertices put back, carried with an obstacle
        std::int64_t lagging = 0;   // vertices whose push was bounded
        double max_lag = 0.0;       // m
    };
    // One substep of length h ending at time t_end; returns its obstacle contacts and adds the
    // stepper's own time (not self-collision's) to solve_ms.
    ObstacleTally substep(ClothModel& model, double h, double t_end, double& solve_ms);
    // Strain limits, stretch, then bending (dihedral, then isometric), colour by colour
    // (detail/constraint_kernels.hpp).
    void project_constraints(ClothModel& model, double h);
    // Pushes every free vertex out of the obstacles, recording the deepest correction per vertex
    // and the obstacle surface's velocity there for friction; returns the vertices in contact.
    ObstacleTally resolve_obstacles(ClothModel& model, double h);
    // The triangles seeded in m_put_back that meet an obstacle go back to the substep's start,
    // carried with the obstacle (obstacle_put_back.hpp); their vertices' obstacle contacts are
    // dropped (they move with the surface). Returns the vertices moved.
    std::int64_t put_back_into_obstacle_motion(ClothModel& model);
    // The self-collision fail-safe over the window that ends at t_end (s). With mesh obstacles,
    // the triangles of the vertices it put back that meet an obstacle (which moved on over the
    // window) go where the obstacles' motion since the window's start carries them, and the
    // fail-safe checks that motion again, so the window still ends with the cloth apart from
    // itself; what it puts back once more stays. Returns the vertices carried.
    std::int64_t enforce_window(ClothModel& model, double t_end);
    // OGC with ogc.audit: the triangles the put-back left in an obstacle (their fallback meets it
    // too: OGC's truncation took back the passes' correction, and the carried start of a
    // deforming body's surface is inside it as well) have their free vertices put where the
    // passes left them (m_before_self), clear of the obstacles. That move leaves the vertices'
    // bounds, so the caller detects at the substep's end, whose audit (the CCD) puts back any
    // vertex whose move could make the cloth pass through itself. Returns the vertices moved.
    std::int64_t release_stuck_triangles(ClothModel& model);
    // Self-collision's paths and candidates describe positions that are gone: it starts over
    // (when it is on).
    void restart_self_collision(const ClothModel& model);
    // OGC: whether `truncated` vertices held back call for a new detection.
    bool needs_detection(std::int64_t truncated) const;
    // OGC: the audit's window ends at x (ogc.audit; velocities of the vertices it puts back are
    // set to zero), then a detection at x: OgcContact::redetect() when held_back (the detection
    // the truncations asked for), else OgcContact::detect().
    void detect(std::span<Vec3d> x, std::span<Vec3d> velocities, bool held_back = false);
    // OGC, in a substep whose pins left their sets (they drive the cloth faster than the
    // detections follow): the vertices their balls held back at x are caught up: a detection at x
    // (intersection-free), then every free vertex's move from there toward m_ogc_wanted
    // truncated again, until no ball holds one back or detail::MAX_CATCH_UP_DETECTIONS
    // detections were made.
    void catch_up(std::span<Vec3d> x, std::span<Vec3d> velocities,
                  std::span<const double> inverse_masses);
    // OGC: the CCD fail-safe over the motion from the audit window's start to x; returns whether it
    // put any vertex back. The next window starts at x.
    bool audit(std::span<Vec3d> x, std::span<Vec3d> velocities);

    std::size_t m_num_vertices = 0;
    std::size_t m_num_triangles = 0;

    // Constraints.
    std::vector<std::array<std::int32_t, 2>> m_stretch_vertices;
    std::vector<double> m_rest_lengths;
    ColoredEdges m_stretch;  // the stretch constraints as the kernels' columns, in colour order
    // The bending constraints as the kernels' columns, in colour order: the dihedral ones with
    // their rest angles, the isometric ones (material.bending; isometric_bending.hpp) with their
    // stencils.
    ColoredHinges m_dihedral;
    std::vector<double> m_dihedral_rest;
    ColoredHinges m_isometric;
    std::array<std::vector<double>, 4> m_isometric_k;
    StretchChains m_chains;  // material.stretch_solver = chains
    std::vector<double> m_chain_scratch;
    std::vector<double> m_stretch_lambda;  // per stretch constraint, in colour order (with chains)
    StrainHierarchy m_strain_hierarchy;    // coarse strain limits (material.strain_limit)

    // Per substep.
    // Positions and inverse masses for the kernels, and (with stretch chains) the chains' padding
    // vertex last.
    std::vector<detail::PackedVertex> m_packed;
    std::vector<Vec3d> m_previous_positions;  // at the substep's start
    std::vector<double> m_contact_depths;     // this substep's obstacle correction per vertex (m)
    // The part of it that undid a penetration the vertex started the substep with (m): moved
    // out, but not turned into velocity.
    std::vector<double> m_contact_settled;
    std::vector<Vec3d> m_contact_normals;
    std::vector<Vec3d> m_contact_velocities;       // the obstacle surface's velocity at the contact
    MeshFeatureContactScratch m_feature_contacts;  // mesh obstacles' edge and face passes
    std::vector<Vec3d> m_before_contacts;          // positions before the passes (with meshes)
    // Triangles the passes left in an obstacle, and self-contact pushes into one (the positions
    // before the self-contacts: m_before_self), are put back (obstacle_put_back.hpp).
    std::vector<Vec3d> m_before_self;
    ObstaclePutBack m_put_back;
    std::int64_t m_step_pushes_undone = 0;
    // The largest push an obstacle held back in the last substep (m): how far behind a mesh
    // obstacle's surface a vertex can be at the next (mesh_contact.hpp, extra_depth).
    double m_obstacle_lag = 0.0;

    // Self-collision and its windows.
    std::unique_ptr<SelfCollision> m_self_collision;
    std::int64_t m_num_position_resets = 0;  // the model's when self-collision last started
    std::vector<Vec3d> m_window_start;       // positions at the start of a fail-safe window
    double m_window_start_time = 0.0;        // s
    // With mesh obstacles: where the obstacles were at the window's start, and the positions
    // before the fail-safe (enforce_window).
    ObstaclePlacements m_window_obstacles;
    std::vector<Vec3d> m_before_fail_safe;
    // The span [start, end] (s) the last self-collision gather covers; it outlives a step, so
    // that steps of one window each gather at the same substeps as longer steps.
    double m_gather_start_time = 0.0;
    double m_gather_end_time = -std::numeric_limits<double>::infinity();  // none yet

    // OGC contact (set_ogc): its options, the contact (with self-collision on), where the audit's
    // window starts (the step's start or the last detection), the truncated prediction of the
    // substep, the free vertices and the vertices held back in this step.
    std::optional<OgcOptions> m_ogc_options;
    std::unique_ptr<OgcContact> m_ogc;
    detail::OgcAuditWindow m_audit;
    std::vector<Vec3d> m_ogc_from;
    std::vector<Vec3d> m_ogc_wanted;  // a truncation's target (catch_up)
    bool m_pins_left_sets = false;    // in this substep (detail::pins_left_sets)
    std::int64_t m_num_free = 0;
    std::int64_t m_step_truncated = 0;
    std::int64_t m_substep_truncated = 0;
};

}  // namespace pliant::cloth
