// The simulation behind `pliant view cloth`, without any drawing: the pipeline::ClothSimulation
// that `pliant cloth` runs, advanced a few substeps per displayed frame, with
// the exact intersection counter run every few frames and mouse grabbing of cloth vertices.
//
// Time: the scene's substep h = 1 / (fps · substeps) is kept; a frame advances
// substeps_per_frame · h seconds in one ClothSolver::step. With substeps_per_frame equal to the
// scene's substeps a frame is one frame of `pliant cloth` (bitwise the same state: the solver is
// deterministic); with a divisor of it (the default, 4: one self-collision window) the states at
// whole scene frames are the same too, the windows falling on the same substeps.
//
// Frames can run in the background (core/parallel_task.hpp): start_advance() returns at once and
// finish_advance() publishes the new state when the step is done, so a viewer keeps drawing the
// last published state (positions(), time(), stats()) while the next one is computed; advance()
// does both in one call. Grabbing picks on the published state and reaches the solver at the
// next start_advance(), so it never waits for a step in flight; reset() does wait.
//
// Not thread safe: one thread calls every member; the solver parallelises internally.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pliant/cloth/scene.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/parallel_task.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::viewer {

struct ClothSessionOptions {
    int substeps_per_frame = 4;  // ≥ 1
    int check_every = 10;        // frames between exact intersection counts (≥ 1)
};

struct ClothFrameStats {
    cloth::ClothStepStats step;  // the last step's (solve, refit, traverse, narrow, response…)
    // The exact count of intersecting non-adjacent triangle pairs (collision/intersecting_pairs),
    // of the state after frame checked_frame; −1 before the first count.
    std::int64_t intersecting_pairs = -1;
    std::int64_t checked_frame = -1;
    double check_ms = 0.0;
};

class ClothSession {
public:
    // Builds the scene (reads its mesh files): InvalidInput / IoError as `pliant cloth`, and
    // InvalidInput for options out of range.
    ClothSession(cloth::ClothScene scene, std::string scene_name,
                 const ClothSessionOptions& options = {});

    // One frame: substeps_per_frame substeps; the exact count every check_every frames (and
    // after the first frame). advance() = start_advance() + finish_advance(true).
    void advance();
    // Starts the next frame in the background (returns false, doing nothing, while one is in
    // flight); pending grab changes reach the solver first.
    bool start_advance();
    // Publishes the frame in flight when it is done (block: waits for it); returns whether a new
    // state was published. Rethrows what the step threw.
    bool finish_advance(bool block);
    bool is_advancing() const { return m_task.is_started(); }
    // Back to the scene's start, as `pliant cloth` starts (pipeline::prepare_start: cloth that
    // intersects itself is untangled when the scene says so); waits for a frame in flight; the
    // grab is released. The start is found once, when the session is built; resets reuse it
    // (ClothSimulation::reset), so a large tangle is untangled once, not at every reset.
    void reset();
    // Clamped to [1, 1000]; used from the next frame on.
    void set_substeps_per_frame(int substeps);
    int substeps_per_frame() const { return m_options.substeps_per_frame; }

    // Grabbing: begin_grab picks the cloth vertex under pixel (x, y) of the published state (the
    // nearest corner of the nearest triangle the pixel's ray hits) and returns whether one was
    // hit; drag moves it to the cursor in the view plane at the depth it was grabbed at
    // (ClothSolver::grab, applied over the next frame); end_grab lets go.
    bool begin_grab(const render::Camera& camera, double x, double y);
    void drag(const render::Camera& camera, double x, double y);
    void end_grab();
    std::int32_t grabbed_vertex() const { return m_grab_vertex; }

    const cloth::ClothScene& scene() const { return m_sim->scene(); }
    const pipeline::ClothSetup& setup() const { return m_sim->setup(); }
    // What the start needed (intersections, untangling).
    const pipeline::StartState& start() const { return m_sim->start(); }
    // The published state.
    std::span<const Vec3d> positions() const { return m_positions; }
    std::span<const geometry::Triangle> triangles() const { return setup().mesh.triangles; }
    double time() const { return m_time; }          // simulated seconds
    std::int64_t frame() const { return m_frame; }  // frames advanced since the start
    const ClothFrameStats& stats() const { return m_stats; }
    double substep() const { return m_substep; }  // h, seconds
    // The cloth at the start and the bounded obstacles (what the default camera frames).
    const AABBd& framing_box() const { return m_framing_box; }
    // A box around everything drawn, planes included (depth range).
    const AABBd& scene_box() const { return m_scene_box; }

private:
    // The step itself (in the background): solver step, frame count, exact count.
    void run_frame(int substeps);
    void start_from_reset();     // frame 0 of the simulation's start, published
    void count_intersections();  // of the solver's state, into m_solver_stats
    void publish();

    ClothSessionOptions m_options;
    std::unique_ptr<pipeline::ClothSimulation> m_sim;
    BackgroundTask m_task;
    double m_substep = 0.0;
    AABBd m_framing_box, m_scene_box;
    // Written by the frame in flight, published by finish_advance.
    std::int64_t m_solver_frame = 0;
    ClothFrameStats m_solver_stats;
    // The published state.
    std::vector<Vec3d> m_positions;
    double m_time = 0.0;
    std::int64_t m_frame = 0;
    ClothFrameStats m_stats;
    // The grab as the user leaves it; the solver gets it at the next start.
    std::int32_t m_grab_vertex = -1;
    Vec3d m_grab_anchor;  // the grabbed vertex where it was grabbed
    Vec3d m_grab_target;
    bool m_grab_changed = false;
};

}  // namespace pliant::viewer
