// ClothSolver: a cloth simulation as one object: a ClothModel (cloth_model.hpp: the mesh, its
// state, masses, pins, obstacles, air, gravity, grab) advanced by an XPBDStepper
// (xpbd_stepper.hpp: XPBD with small substeps, constraints, self-collision). Every function
// forwards to one of the two; model() and stepper() give them to callers that drive the parts
// themselves (another stepper, a viewer).
//
//   ClothSolver solver(mesh, material, pinned_vertices);
//   solver.add_obstacle(SphereObstacle{{0, 0, 0}, 0.5});
//   for (int frame = 0; frame < 72; ++frame) solver.step(1.0 / 24.0, 20);
//
// Masses: each vertex gets a third of the rest area of each of its triangles times
// areal_density; pinned vertices and vertices with no area get inverse mass 0.
//
// Units: SI (metres, seconds, kilograms). Positions are double. Not thread safe (one solver per
// thread); step() parallelises internally.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <utility>

#include "pliant/cloth/air.hpp"
#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/material.hpp"
#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/obstacles.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/untangle.hpp"
#include "pliant/cloth/vbd_stepper.hpp"
#include "pliant/cloth/xpbd_stepper.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

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
    // A deforming mesh obstacle following `animation`, with `motion` on top
    // (ClothModel::add_animated_mesh_obstacle); returns its index for add_attached_pins.
    std::size_t add_animated_mesh_obstacle(const MeshObstacle& obstacle,
                                           std::shared_ptr<const MeshAnimation> animation,
                                           const Motion& motion = {}) {
        return m_model.add_animated_mesh_obstacle(obstacle, std::move(animation), motion);
    }
    // Pins `vertices` to the surface of mesh obstacle `mesh_obstacle` (the order of
    // add_mesh_obstacle and add_animated_mesh_obstacle calls): they follow it as it moves and
    // deforms (ClothModel::add_attached_pins).
    void add_attached_pins(std::span<const std::int32_t> vertices, std::size_t mesh_obstacle,
                           double max_distance = std::numeric_limits<double>::infinity()) {
        m_model.add_attached_pins(vertices, mesh_obstacle, max_distance);
    }
    // Pins `vertices` (InvalidInput when out of range) and moves them rigidly with `motion` from
    // their current positions: every substep they are placed at motion.pose(t)(rest) with the
    // velocity of that path. A vertex in several groups follows the last.
    void add_moving_pins(std::span<const std::int32_t> vertices, const Motion& motion) {
        m_model.add_moving_pins(vertices, motion);
    }
    // Sews a[k] to b[k] over `seconds` (ClothModel::add_seam, seams.hpp).
    void add_seam(std::span<const std::int32_t> a, std::span<const std::int32_t> b,
                  double seconds) {
        m_model.add_seam(a, b, seconds);
    }
    // m/s², default (0, 0, -9.81)
    void set_gravity(const Vec3d& gravity) { m_model.set_gravity(gravity); }
    // Replaces the velocities (m/s, #V, finite; else InvalidInput), e.g. an initial motion or a
    // kick between steps. Pinned vertices keep following their pins.
    void set_velocities(std::span<const Vec3d> velocities) { m_model.set_velocities(velocities); }
    // Wind and drag (air.hpp); InvalidInput for negative or non-finite values.
    void set_air(const Air& air) { m_model.set_air(air); }
    // Self-collision handling (self_collision.hpp): proximity constraints every substep and the
    // CCD fail-safe at the end of every window of substeps, so that no step ends with
    // intersecting triangles when it started without. Off by default. InvalidInput when the
    // thickness exceeds 4 median edge lengths.
    void enable_self_collision(bool enabled) {
        m_stepper.enable_self_collision(m_model, enabled);
        if (m_vbd) {
            m_vbd->enable_self_collision(m_model, enabled);
        }
    }
    // Steps with Vertex Block Descent (vbd_stepper.hpp) from now on instead of XPBD, with
    // self-collision as the XPBD stepper has it. InvalidInput for invalid options.
    void use_vbd(const VBDOptions& options) {
        m_vbd = std::make_unique<VBDStepper>(m_model, options);
        m_vbd->enable_self_collision(m_model, m_stepper.has_self_collision());
    }
    // Self-contact of the XPBD stepper by Offset Geometric Contact (ogc_contact.hpp,
    // XPBDStepper::set_ogc) instead of the proximity constraints, or the proximity path again
    // (nullopt). InvalidInput for invalid options.
    void use_xpbd_ogc(const std::optional<OgcOptions>& options) {
        m_stepper.set_ogc(m_model, options);
    }
    // The VBD stepper (use_vbd), or null when XPBD steps.
    const VBDStepper* vbd() const { return m_vbd.get(); }

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
    ClothStepStats step(double dt, int substeps) {
        return m_vbd ? m_vbd->step(m_model, dt, substeps) : m_stepper.step(m_model, dt, substeps);
    }

    double time() const { return m_model.time(); }  // s since the start
    std::span<const Vec3d> positions() const { return m_model.positions(); }
    std::span<const Vec3d> velocities() const { return m_model.velocities(); }
    std::span<const double> inverse_masses() const { return m_model.inverse_masses(); }
    std::span<const geometry::Triangle> triangles() const { return m_model.triangles(); }
    const ClothMaterial& material() const { return m_model.material(); }
    std::size_t num_stretch_constraints() const { return m_stepper.num_stretch_constraints(); }
    // Chains the stretch constraints are solved in (0 unless material.stretch_solver = chains;
    // stretch_chains.hpp).
    std::size_t num_stretch_chains() const { return m_stepper.num_stretch_chains(); }
    // Coarse strain limits (0 unless material.strain_limit is finite; strain_hierarchy.hpp).
    std::size_t num_strain_limits() const { return m_stepper.num_strain_limits(); }
    // Bending constraints: dihedral plus isometric (material.bending).
    std::size_t num_bending_constraints() const { return m_stepper.num_bending_constraints(); }
    std::size_t num_isometric_bending_constraints() const {
        return m_stepper.num_isometric_bending_constraints();
    }

    // The state that changes as the solver runs (ClothModel::save_state, XPBDStepper::save_state):
    // a solver built from the same mesh, material, obstacles and options that loads it continues
    // bit for bit. load_state: InvalidInput for a state of another cloth or a truncated one.
    void save_state(ByteWriter& out) const {
        m_model.save_state(out);
        if (m_vbd) {
            m_vbd->save_state(out);
        } else {
            m_stepper.save_state(out);
        }
    }
    void load_state(ByteReader& in) {
        m_model.load_state(in);
        if (m_vbd) {
            m_vbd->load_state(m_model, in);
        } else {
            m_stepper.load_state(m_model, in);
        }
    }

    // The parts. The stepper was built for this model: step it with model() only.
    ClothModel& model() { return m_model; }
    const ClothModel& model() const { return m_model; }
    XPBDStepper& stepper() { return m_stepper; }
    const XPBDStepper& stepper() const { return m_stepper; }

private:
    ClothModel m_model;
    XPBDStepper m_stepper;
    std::unique_ptr<VBDStepper> m_vbd;  // steps instead of m_stepper when set
};

}  // namespace pliant::cloth
