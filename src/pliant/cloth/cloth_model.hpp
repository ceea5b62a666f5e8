// ClothModel: the cloth's world, apart from the method that advances it in time: the mesh and its
// rest shape, the state (positions, velocities), the masses, pins and their motions, obstacles
// (analytic and triangle-mesh) and their motions, gravity, air and the interactive grab.
//
// A stepper (xpbd_stepper.hpp) owns what its method adds (constraints, colourings, contact
// state) and advances the model through the hooks at the end of the class: per step
// begin_step(dt) ... end_step(); per substep ending at time t, move_pins(t) places the pinned and
// grabbed vertices on their paths, move_obstacles(t) places the obstacles, apply_air(h, t) adds
// the air's impulse, and the stepper moves the free vertices (mutable_positions(),
// mutable_velocities()). Another method (a Vertex Block Descent stepper) uses the same model
// unchanged. ClothSolver (solver.hpp) is a model and an XPBD stepper together.
//
//   ClothModel model(mesh, material, pinned_vertices);
//   model.add_obstacle(SphereObstacle{{0, 0, 0}, 0.5});
//   XPBDStepper stepper(model);
//   for (int frame = 0; frame < 72; ++frame) stepper.step(model, 1.0 / 24.0, 20);
//
// Masses: each vertex gets a third of the rest area of each of its triangles times
// material.areal_density; pinned vertices and vertices with no area get inverse mass 0.
//
// Units: SI (metres, seconds, kilograms). Positions are double. Not thread safe; apply_air
// parallelises internally (bitwise identical for 1 and N threads).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pliant/cloth/air.hpp"
#include "pliant/cloth/material.hpp"
#include "pliant/cloth/mesh_animation.hpp"
#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/obstacles.hpp"
#include "pliant/cloth/seams.hpp"
#include "pliant/cloth/untangle.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

// An analytic obstacle and where its motion has it now and at the previous placement.
struct MovingObstacle {
    Obstacle rest;  // at time 0
    MotionState state;
    Obstacle current;   // rest placed by state.pose
    Obstacle previous;  // rest placed by state.previous_pose
};

// A triangle-mesh obstacle at its rest placement and its rigid motion (queries run in its rest
// frame: state.pose.apply_inverse). A deforming one (animation not null) is this model's own
// copy of the mesh, moved every substep to the animation's positions (MeshObstacle::move_to: its
// swept triangles are what cloth is kept out of), with the rigid motion on top.
struct MovingMeshObstacle {
    std::shared_ptr<const MeshObstacle> mesh;
    MotionState state;
    std::shared_ptr<const MeshAnimation> animation;  // null: rigid
    std::shared_ptr<MeshObstacle> deforming;         // mesh, movable (with animation)
    std::vector<Vec3d> next_positions;               // scratch for move_obstacles (#V)
};

class ClothModel {
public:
    // rest_mesh: the cloth at rest, which is also its initial state (positions in metres).
    // pinned: vertex indices that never move. Throws InvalidInput for out-of-range triangles or
    // pins, non-finite positions or invalid material values (negative density or compliance,
    // friction or damping, a thickness that is not finite and >= 0).
    ClothModel(const geometry::TriangleMeshD& rest_mesh, const ClothMaterial& material,
               std::span<const std::int32_t> pinned = {});

    // An obstacle at its rest placement, moved by `motion` (motion.hpp; time 0 is the model's
    // start), placed where the motion has it at time(). Boxes stay axis-aligned: a motion that
    // rotates a box is InvalidInput. Invalid shapes (zero plane normal, radius <= 0, min > max)
    // and invalid motions are InvalidInput.
    void add_obstacle(const Obstacle& obstacle, const Motion& motion = {});
    // A triangle-mesh obstacle (mesh_obstacle.hpp), given at its rest placement and moved
    // rigidly by `motion`. Shared, so that several models can use one mesh.
    void add_mesh_obstacle(std::shared_ptr<const MeshObstacle> obstacle, const Motion& motion = {});
    // A deforming triangle-mesh obstacle: a copy of `obstacle` (its topology) whose vertices
    // follow `animation` (mesh_animation.hpp; time 0 is the model's start), placed at time() now
    // and moved by move_obstacles every substep, with the rigid `motion` on top. InvalidInput:
    // no animation, an animation of another vertex count, an invalid motion. Returns the index
    // among mesh_obstacles().
    std::size_t add_animated_mesh_obstacle(const MeshObstacle& obstacle,
                                           std::shared_ptr<const MeshAnimation> animation,
                                           const Motion& motion = {});
    // Pins `vertices` (InvalidInput when out of range) and moves them rigidly with `motion` from
    // their current positions: move_pins(t) places them at motion.pose(t)(rest). A vertex in
    // several groups follows the last (it leaves the earlier groups).
    void add_moving_pins(std::span<const std::int32_t> vertices, const Motion& motion);
    // Pins `vertices` to the surface of mesh obstacle `mesh_obstacle` (an index into
    // mesh_obstacles()): each is bound to the closest point of the surface where the obstacle is
    // now (a triangle and barycentric weights) and its offset from it in the triangle's frame,
    // and move_pins(t) places it there as the obstacle moves, turns and deforms (the obstacle's
    // animation and motion at t; where it is now, exactly). A vertex farther than max_distance (m)
    // from the surface is InvalidInput (naming it and its distance), as are vertices out of range
    // and an obstacle index out of range. Like add_moving_pins, a vertex follows its last group.
    void add_attached_pins(std::span<const std::int32_t> vertices, std::size_t mesh_obstacle,
                           double max_distance = std::numeric_limits<double>::infinity());
    void set_gravity(const Vec3d& gravity) { m_gravity = gravity; }  // m/s², default (0, 0, -9.81)
    // Sews a[k] to b[k] (seams.hpp): pulled together over `seconds` from time 0, from their
    // current distance down to the material's thickness, then held there. InvalidInput as
    // Seams::add says.
    void add_seam(std::span<const std::int32_t> a, std::span<const std::int32_t> b,
                  double seconds) {
        m_seams.add(a, b, seconds, m_material.thickness, m_positions);
    }
    const Seams& seams() const { return m_seams; }
    // Wind and drag (air.hpp); InvalidInput for negative or non-finite values.
    void set_air(const Air& air);
    // Replaces the velocities (m/s, #V, finite; else InvalidInput).
    void set_velocities(std::span<const Vec3d> velocities);
    // Moves the cloth to `positions` (#V, finite). Pinned vertices (inverse mass 0) must be given
    // where they are. Velocities are kept. InvalidInput: a size that does not match, a non-finite
    // position, a pinned vertex moved. Counts in num_position_resets().
    void set_positions(std::span<const Vec3d> positions);
    // Moves the cloth out of its own intersections (untangle.hpp; pinned vertices stay). Without
    // options.obstacle_distance, region moves keep out of the obstacles where they are now
    // (nearest_obstacle). Counts in num_position_resets() when it moved the cloth.
    UntangleResult untangle(const UntangleOptions& options = {});

    // Interactive dragging: `vertex` becomes kinematic (inverse mass 0) and, over the next step
    // (begin_step(dt) to end_step()), moves on the straight line from where it is to `target`
    // (metres): move_pins(t) places it at the fraction min(1, (t - step start) / dt) of that
    // line. It stays at the target in later steps until the target moves. Calling again with the
    // same vertex moves the target; with another vertex releases the first. The grab overrides a
    // pin's motion while it lasts. InvalidInput: vertex out of range, target not finite.
    void grab(std::int32_t vertex, const Vec3d& target);
    // Ends the grab (no-op without one): the vertex gets its inverse mass back and keeps its
    // velocity (a pinned vertex stays pinned where it was left; a moving pin resumes its motion).
    void release_grab();
    // The grabbed vertex, or -1.
    std::int32_t grabbed_vertex() const { return m_grab ? m_grab->vertex : -1; }

    // The free vertices inside an obstacle (signed distance < 0 to an analytic obstacle, or to a
    // mesh obstacle within its box's diagonal of its surface) where the obstacles are now, and
    // how deep the deepest is (m; 0 when none).
    struct Penetration {
        std::int64_t vertices = 0;
        double deepest = 0.0;
    };
    Penetration obstacle_penetration() const;
    // The obstacle surface nearest to x where the obstacles are now (a mesh obstacle within its
    // box's diagonal: an open mesh is "inside" behind its triangles' planes, which would
    // otherwise reach across all of space); distance +inf without one.
    SurfaceDistance nearest_obstacle(const Vec3d& x) const;
    bool has_obstacles() const { return !(m_obstacles.empty() && m_mesh_obstacles.empty()); }

    double time() const { return m_time; }  // s since the start
    std::size_t num_vertices() const { return m_positions.size(); }
    std::span<const Vec3d> positions() const { return m_positions; }
    std::span<const Vec3d> velocities() const { return m_velocities; }
    std::span<const double> inverse_masses() const { return m_inverse_masses; }
    std::span<const Vec3d> rest_positions() const { return m_rest_positions; }
    std::span<const geometry::Triangle> triangles() const { return m_triangles; }
    const geometry::MeshTopology& topology() const { return m_topology; }
    const ClothMaterial& material() const { return m_material; }
    const Vec3d& gravity() const { return m_gravity; }
    const Air& air() const { return m_air; }
    std::span<const MovingObstacle> obstacles() const { return m_obstacles; }
    std::span<const MovingMeshObstacle> mesh_obstacles() const { return m_mesh_obstacles; }
    // How many times the positions were replaced from outside a step (set_positions, untangle):
    // a stepper whose caches describe positions (self-collision paths) starts them over when
    // this changes.
    std::int64_t num_position_resets() const { return m_num_position_resets; }

    // Stepper hooks (see the header). begin_step: a step of dt seconds (> 0) starts at time();
    // the grabbed vertex's path starts where it is. end_step: time() becomes the step's end.
    void begin_step(double dt);
    void end_step() { m_time = m_step_start + m_step_dt; }
    // Places the moving pins (their motion at time t, s) and then the grabbed vertex (on its
    // path, see grab()). Positions only: a stepper derives velocities from the motion.
    // max_step (m, > 0): a pinned vertex moves at most that far per call, on the straight line
    // from where it is toward its target, so a pin whose keyframes jump chases its target at
    // that bounded speed and reaches it over several calls (its lag, pin_lag(), lives in the
    // positions: nothing else to keep). A target within max_step (up to a relative 1e-9) is
    // taken exactly, so pins slower than that are placed as without the bound. The grabbed
    // vertex is not bounded.
    void move_pins(double t, double max_step = std::numeric_limits<double>::infinity());
    // Pinned vertices (of moving pin groups, not grabbed) that are not at their motion's target
    // at time(), and the largest such distance (m).
    struct PinLag {
        std::int64_t vertices = 0;
        double max = 0.0;  // m
    };
    PinLag pin_lag() const;
    // Places the obstacles at time t (s); the previous placements are kept for the obstacles'
    // surface velocities (MotionState::surface_displacement, MeshObstacle::previous_positions).
    void move_obstacles(double t);
    // The farthest any obstacle's surface moved at the last move_obstacles (m): a sphere's
    // centre, a plane along its normal, a box's corner, a mesh's vertices (rigid motion and
    // deformation together). 0 before the first.
    double obstacle_step() const { return m_obstacle_step; }
    // Adds h · (air force at time t / mass) to the free vertices' velocities (air.hpp; h the
    // substep in s, which caps the drag); nothing without air (air().is_active()). Per triangle,
    // then per vertex over its incident triangles in ascending order: the same sums for any number
    // of threads.
    void apply_air(double h, double t);
    // The state a stepper moves (#V each). Pinned and grabbed vertices (inverse mass 0) are
    // moved only by move_pins.
    std::span<Vec3d> mutable_positions() { return m_positions; }
    std::span<Vec3d> mutable_velocities() { return m_velocities; }

    // The state that changes as the model runs (core/bytes.hpp): positions, velocities, inverse
    // masses, time, the step in progress, the grab, the air's forces and where the obstacles
    // are; not what the constructor and the add_/set_ calls set up (mesh, material, pins,
    // motions, gravity, air), which a model built the same way has. load_state: InvalidInput for
    // a state of another mesh or other obstacles, or a truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    struct MovingPins {
        std::vector<std::int32_t> vertices;
        std::vector<Vec3d> rest_positions;
        Motion motion;
        // Attached to a mesh obstacle's surface (add_attached_pins): that obstacle's index, and
        // per vertex its triangle, barycentric weights and offset from that surface point in the
        // triangle's frame (first edge, normal × edge, normal; rest_positions unused); -1: moved
        // by motion.
        std::int64_t mesh_obstacle = -1;
        std::vector<std::int32_t> triangles;
        std::vector<Vec3d> barycentric;
        std::vector<Vec3d> offsets;
    };
    // Where pin k of `pins` belongs at time t.
    Vec3d pin_target(const MovingPins& pins, const Pose& pose, std::size_t k, double t) const;
    // Makes `pins` the last group: its vertices leave the earlier groups.
    void add_pin_group(MovingPins pins);
    struct Grab {
        std::int32_t vertex = -1;
        Vec3d start;                // where the current step's path starts
        Vec3d target;               // where it ends
        double inverse_mass = 0.0;  // the vertex's own, restored on release
    };

    ClothMaterial m_material;
    std::vector<geometry::Triangle> m_triangles;
    geometry::MeshTopology m_topology;
    std::vector<Vec3d> m_rest_positions;
    std::vector<Vec3d> m_positions;
    std::vector<Vec3d> m_velocities;
    std::vector<double> m_inverse_masses;
    double m_time = 0.0;        // s
    double m_step_start = 0.0;  // time and length of the step in progress (grab paths), s
    double m_step_dt = 1.0;
    std::int64_t m_num_position_resets = 0;
    Vec3d m_gravity{0.0, 0.0, -9.81};
    Air m_air;
    std::vector<Vec3d> m_triangle_forces;  // air, per triangle (N)
    std::vector<MovingPins> m_moving_pins;
    std::optional<Grab> m_grab;
    std::vector<MovingObstacle> m_obstacles;
    std::vector<MovingMeshObstacle> m_mesh_obstacles;
    double m_obstacle_step = 0.0;  // m, see obstacle_step()
    Seams m_seams;
};

}  // namespace pliant::cloth
