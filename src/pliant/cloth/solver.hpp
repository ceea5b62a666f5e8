// ClothSolver: XPBD cloth with small substeps.
//
// Method: extended position-based dynamics (Macklin, Müller, Chentanez, "XPBD", MIG 2016) run as
// many small substeps with one constraint iteration each (Macklin, Storey, Lu, Terdiman,
// Chentanez, Jeschke, Müller, "Small Steps in Physics Simulation", SCA 2019). Every substep h:
//   1. predict: v += h (g + f_air / m); x_previous = x; x += h v (pinned vertices, inverse mass 0,
//      stay put, or follow their motion: motion.hpp; air: air.hpp);
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
//   4. obstacles (placed where their motion has them at the end of the substep): every vertex is
//      pushed `thickness` away from every obstacle (obstacles.hpp);
//   (with self-collision: after 4, the cloth's own contacts are pushed thickness apart; the CCD
//   fail-safe runs after every 4 substeps on the motion of those 4 substeps, and the candidate
//   pairs are gathered before every 4 or, while contact is sparse, every 8; self_collision.hpp)
//   5. v = (x - x_previous) / h, less the part of an obstacle's push that undid a penetration
//      the vertex began the substep with (cloth given inside an obstacle comes out without being
//      thrown: a sheet 0.3 m behind a plane flew off at 288 m/s); Coulomb friction on the
//      velocities of vertices in contact (relative to the obstacle surface's velocity), bounded
//      by the rest of their normal correction / h
//      (obstacles.hpp: at the velocity level, friction never cancels a constraint's correction,
//      which positional friction does, locking stretched cloth on a rough surface); then v *=
//      max(0, 1 - damping h).
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
// Masses: each vertex gets a third of the rest area of each of its triangles times
// areal_density; pinned vertices and vertices with no area get inverse mass 0.
//
//   ClothSolver solver(mesh, material, pinned_vertices);
//   solver.add_obstacle(SphereObstacle{{0, 0, 0}, 0.5});
//   for (int frame = 0; frame < 72; ++frame) solver.step(1.0 / 24.0, 20);
//
// Units: SI (metres, seconds, kilograms). Positions are double. Not thread safe (one solver per
// thread); step() parallelises internally.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pliant/cloth/air.hpp"
#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/constraint_coloring.hpp"
#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/cloth/material.hpp"
#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/obstacles.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/strain_hierarchy.hpp"
#include "pliant/cloth/stretch_chains.hpp"
#include "pliant/cloth/untangle.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

struct ClothStepStats {
    double ms = 0.0;        // wall-clock time of the step
    double solve_ms = 0.0;  // prediction, stretch, bending, air, obstacles, velocities, friction
    std::int64_t obstacle_contacts = 0;  // vertices in contact with an obstacle in the last substep
    bool has_self_collision = false;     // the fields below are filled
    SelfCollisionStats self;             // self_collision.hpp
};

class ClothSolver {
public:
    // rest_mesh: the cloth at rest, which is also its initial state (positions in metres).
    // pinned: vertex indices that never move. Throws InvalidInput for out-of-range triangles or
    // pins, non-finite positions or invalid material values (negative density or compliance,
    // friction or damping, a thickness that is not finite and >= 0).
    ClothSolver(const geometry::TriangleMeshD& rest_mesh, const ClothMaterial& material,
                std::span<const std::int32_t> pinned = {});

    // An obstacle at its rest placement, moved by `motion` (motion.hpp; time 0 is the solver's
    // start). Moving obstacles carry the cloth along through friction (relative velocity). Boxes
    // stay axis-aligned: a motion that rotates a box is InvalidInput. Invalid shapes (zero plane
    // normal, radius <= 0, min > max) are InvalidInput.
    void add_obstacle(const Obstacle& obstacle, const Motion& motion = {}) {
        m_model.add_obstacle(obstacle, motion);
    }
    // A triangle-mesh obstacle (mesh_obstacle.hpp), given at its rest placement and moved
    // rigidly by `motion` (queries run in its rest frame: no refit per substep). Shared, so that
    // several solvers can use one mesh.
    void add_mesh_obstacle(std::shared_ptr<const MeshObstacle> obstacle,
                           const Motion& motion = {}) {
        m_model.add_mesh_obstacle(std::move(obstacle), motion);
    }
    // Pins `vertices` (InvalidInput when out of range) and moves them rigidly with `motion` from
    // their current positions: every substep they are placed at motion.pose(t)(rest) with the
    // velocity of that path. A vertex in several groups follows the last.
    void add_moving_pins(std::span<const std::int32_t> vertices, const Motion& motion) {
        m_model.add_moving_pins(vertices, motion);
    }
    // m/s², default (0, 0, -9.81)
    void set_gravity(const Vec3d& gravity) { m_model.set_gravity(gravity); }
    // Replaces the velocities (m/s, #V, finite; else InvalidInput), e.g. an initial motion or a
    // kick between steps. Pinned vertices keep following their pins.
    void set_velocities(std::span<const Vec3d> velocities) { m_model.set_velocities(velocities); }
    // Wind and drag (air.hpp); InvalidInput for negative or non-finite values.
    void set_air(const Air& air) { m_model.set_air(air); }
    // Self-collision handling (self_collision.hpp): proximity constraints every substep and the
    // CCD fail-safe at the end of every step, so that no step ends with intersecting triangles
    // when it started without. Off by default.
    void enable_self_collision(bool enabled);

    // Moves the cloth out of its own intersections (untangle.hpp; pinned vertices stay): for
    // input that intersects itself, before the first step (the fail-safe keeps cloth
    // intersection-free only once it is). Velocities are kept; self-collision starts over.
    // Without options.obstacle_distance, region moves keep out of the solver's obstacles where
    // they are now (a mesh obstacle within its box's diagonal of its surface).
    UntangleResult untangle(const UntangleOptions& options = {}) {
        return m_model.untangle(options);
    }
    // The free vertices inside an obstacle (signed distance < 0 to an analytic obstacle, or to a
    // mesh obstacle within its box's diagonal of its surface) where the obstacles are now, and
    // how deep the deepest is (m; 0 when none). Cloth given inside an obstacle is pushed out onto
    // its surface in the first substep (without being thrown, but stretched as the surface has it).
    using Penetration = ClothModel::Penetration;
    Penetration obstacle_penetration() const { return m_model.obstacle_penetration(); }
    // Moves the cloth to `positions` (#V, finite), e.g. a start untangled before and kept, so
    // that it need not be untangled again: afterwards the solver is in the state untangle()
    // leaves when it ends there. Pinned vertices (inverse mass 0) must be given where they are.
    // Velocities are kept; self-collision starts over. InvalidInput: a size that does not match,
    // a non-finite position, a pinned vertex moved.
    void set_positions(std::span<const Vec3d> positions) { m_model.set_positions(positions); }

    // Interactive dragging: `vertex` becomes kinematic (inverse mass 0) and, over the substeps of
    // the next step, moves on the straight line from where it is to `target` (metres) with that
    // path's velocity; it stays at the target in later steps until the target moves. Calling
    // again with the same vertex moves the target; with another vertex releases the first. The
    // grab overrides a pin's motion while it lasts, and the self-collision fail-safe may still
    // put the vertex back like any other (the cloth stays intersection-free). InvalidInput:
    // vertex out of range, target not finite.
    void grab(std::int32_t vertex, const Vec3d& target) { m_model.grab(vertex, target); }
    // Ends the grab (no-op without one): the vertex gets its inverse mass back and keeps its
    // velocity (a pinned vertex stays pinned where it was left; a moving pin resumes its motion).
    void release_grab() { m_model.release_grab(); }
    // The grabbed vertex, or -1.
    std::int32_t grabbed_vertex() const { return m_model.grabbed_vertex(); }

    // Advances the cloth by dt seconds in `substeps` equal substeps (dt > 0, substeps >= 1; else
    // InvalidInput).
    ClothStepStats step(double dt, int substeps);

    double time() const { return m_model.time(); }  // s since the start
    std::span<const Vec3d> positions() const { return m_model.positions(); }
    std::span<const Vec3d> velocities() const { return m_model.velocities(); }
    std::span<const double> inverse_masses() const { return m_model.inverse_masses(); }
    std::span<const geometry::Triangle> triangles() const { return m_model.triangles(); }
    const ClothMaterial& material() const { return m_model.material(); }
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

private:
    // One substep ending at time t_end; returns the vertices in contact with an obstacle and
    // adds the solver's own time (not self-collision's) to solve_ms.
    std::int64_t substep(double h, double t_end, double& solve_ms);
    // Strain limits, stretch, then bending (dihedral, then isometric), colour by colour
    // (detail/constraint_kernels.hpp).
    void project_constraints(double h);
    // Self-collision's paths and candidates describe positions that are gone: it starts over
    // (when it is on).
    void restart_self_collision();
    // Pushes every free vertex out of the obstacles, recording the deepest correction per vertex
    // and the obstacle surface's velocity there for friction; returns the vertices in contact.
    std::int64_t resolve_obstacles(double h);

    ClothModel m_model;
    std::int64_t m_num_position_resets = 0;  // the model's when self-collision last started
    std::vector<Vec3d> m_previous_positions;
    std::unique_ptr<SelfCollision> m_self_collision;
    std::vector<Vec3d> m_window_start;  // positions at the start of a self-collision window
    double m_window_start_time = 0.0;   // s
    // The span [start, end] (s) the last self-collision gather covers; it outlives a step, so
    // that steps of one window each gather at the same substeps as longer steps.
    double m_gather_start_time = 0.0;
    double m_gather_end_time = -std::numeric_limits<double>::infinity();  // none yet
    std::vector<double> m_contact_depths;  // this substep's obstacle correction per vertex (m)
    // The part of it that undid a penetration the vertex started the substep with (m): moved
    // out, but not turned into velocity.
    std::vector<double> m_contact_settled;
    std::vector<Vec3d> m_contact_normals;
    std::vector<Vec3d> m_contact_velocities;  // the obstacle surface's velocity at the contact

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
    // Positions and inverse masses, per substep, and (with stretch chains) the chains' padding
    // vertex last.
    std::vector<detail::PackedVertex> m_packed;
    StretchChains m_chains;  // material.stretch_solver = chains
    std::vector<double> m_chain_scratch;
    std::vector<double> m_stretch_lambda;  // per stretch constraint, in colour order (with chains)
    StrainHierarchy m_strain_hierarchy;    // coarse strain limits (material.strain_limit)
};

}  // namespace pliant::cloth
