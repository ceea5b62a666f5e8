// A cloth scene as a simulation a caller drives frame by frame: what `pliant cloth`, the viewer
// (`pliant view cloth`) and the Python module run, so that all three simulate exactly the same
// thing.
//
//   ClothSimulation sim = ClothSimulation::from_scene(read_cloth_scene("scenes/drape.json"),
//                                                     "scenes/drape.json");
//   for (int f = 1; f <= sim.scene().frames; ++f) {
//       const cloth::ClothStepStats step = sim.step();    // one frame: 1/fps s in `substeps`
//       const ClothFrameCheck check = sim.check();        // exact intersections, edge strain
//       use(sim.positions());                              // #V by 3, m
//   }
//
// from_scene reads the files the scene names, builds the solver (cloth_setup.hpp) and prepares
// the start: cloth that starts inside obstacles or intersecting itself is reported through the
// log (core/log.hpp), and untangled when the scene says "untangle" (prepare_start). Not
// thread-safe: one caller steps it at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "pliant/cloth/edge_strain.hpp"
#include "pliant/cloth/scene.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/pipeline/cloth_setup.hpp"

namespace pliant::pipeline {

struct ClothSimulationOptions {
    // A cloth that needs more memory is refused before it is generated (memory_budget.hpp);
    // 0: the memory available.
    std::uint64_t max_memory_bytes = 0;
};

// The independent checks of a frame: they read only the mesh and the obstacles' placements,
// never the solver's state.
struct ClothFrameCheck {
    std::int64_t intersecting_pairs = 0;  // exact triangle-triangle tests, non-adjacent pairs
    // Where the cloth passes into an obstacle (cloth/obstacle_intersections.hpp): (cloth
    // triangle, mesh obstacle triangle) pairs that intersect, and cloth triangles reaching into
    // an analytic obstacle, with the obstacles where they are now.
    std::int64_t obstacle_intersections = 0;
    cloth::StrainStats strain;  // edge lengths against the start (the rest shape)
    double ms = 0.0;            // wall time of both checks
};

class ClothSimulation {
public:
    // A vertex farther than this from the origin (m; NaN included) means the simulation
    // diverged: scene coordinates are at most MAX_SCENE_COORDINATE, and the checks run on float
    // boxes.
    static constexpr double MAX_COORDINATE = 1e9;

    // Throws InvalidInput / IoError for a scene that cannot be built, naming scene_name.
    static ClothSimulation from_scene(cloth::ClothScene scene, std::string scene_name,
                                      const ClothSimulationOptions& options = {});

    // Advances one frame (1 / fps seconds in the scene's substeps). Throws InvalidInput when the
    // simulation diverged (a vertex beyond MAX_COORDINATE) and what the solver throws (a guard
    // such as self-collision's pair limit); the state is then that of the failed frame.
    cloth::ClothStepStats step();

    // Counts intersecting triangle pairs and the cloth's intersections with the obstacles
    // exactly, and measures edge strain, now.
    ClothFrameCheck check() const;

    // The state that changes as the simulation runs (the frame count and the solver's
    // ClothSolver::save_state), for checkpoints (cloth_run.hpp): a simulation made by
    // from_scene from the same scene that loads it continues bit for bit. load_state:
    // InvalidInput for a state of another cloth or a truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

    // Back to the start as from_scene prepared it (untangled positions, zero velocity), frame 0.
    // The start is not reported again.
    void reset();

    const cloth::ClothScene& scene() const { return m_scene; }
    const std::string& name() const { return m_name; }
    const ClothSetup& setup() const { return m_setup; }
    const StartState& start() const { return m_start; }
    int frame() const { return m_frame; }             // frames stepped since the start
    double time() const { return m_solver->time(); }  // s since the start
    std::span<const Vec3d> positions() const { return m_solver->positions(); }
    std::span<const geometry::Triangle> triangles() const { return m_solver->triangles(); }
    // The solver, for what a frame-by-frame caller does between frames (grab, set_positions,
    // substeps of its own length).
    cloth::ClothSolver& solver() { return *m_solver; }
    const cloth::ClothSolver& solver() const { return *m_solver; }

private:
    ClothSimulation(cloth::ClothScene scene, std::string scene_name, ClothSetup setup);

    cloth::ClothScene m_scene;
    std::string m_name;
    ClothSetup m_setup;
    std::unique_ptr<cloth::ClothSolver> m_solver;
    std::unique_ptr<cloth::EdgeStrain>
        m_edge_strain;  // rest: the solver's start, before untangling
    StartState m_start;
    std::vector<Vec3d> m_untangled_start;  // empty: the start needed no untangling
    int m_frame = 0;
};

}  // namespace pliant::pipeline
