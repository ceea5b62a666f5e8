#include "pliant/pipeline/cloth_simulation.hpp"

#include <fmt/format.h>

#include <utility>

#include "pliant/cloth/obstacle_intersections.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::pipeline {

ClothSimulation ClothSimulation::from_scene(cloth::ClothScene scene, std::string scene_name,
                                            const ClothSimulationOptions& options) {
    ClothSetup setup = load_cloth_setup(scene, scene_name, options.max_memory_bytes);
    return {std::move(scene), std::move(scene_name), std::move(setup)};
}

ClothSimulation::ClothSimulation(cloth::ClothScene scene, std::string scene_name, ClothSetup setup)
    : m_scene(std::move(scene)), m_name(std::move(scene_name)), m_setup(std::move(setup)) {
    m_solver = make_solver(m_scene, m_setup);
    // The strain check's rest shape is the cloth as the scene gives it, before untangling.
    m_edge_strain =
        std::make_unique<cloth::EdgeStrain>(m_solver->positions(), m_solver->triangles());
    m_start = prepare_start(m_scene, m_name, *m_solver);
    if (m_start.untangled) {
        m_untangled_start.assign(m_solver->positions().begin(), m_solver->positions().end());
    }
}

cloth::ClothStepStats ClothSimulation::step() {
    const double dt = 1.0 / m_scene.frames_per_second;
    const cloth::ClothStepStats stats = m_solver->step(dt, m_scene.substeps);
    ++m_frame;
    for (const Vec3d& p : m_solver->positions()) {
        if (!within_cube(p, MAX_COORDINATE)) {
            throw InvalidInput(fmt::format(
                "the simulation diverged: a vertex at ({:.3g}, {:.3g}, {:.3g}) m, expected finite "
                "coordinates within {:g} m, with substeps of {:.4g} ms; raise substeps (the "
                "built-in scenes use about 1 ms)",
                p.x, p.y, p.z, MAX_COORDINATE, 1e3 * dt / m_scene.substeps));
        }
    }
    return stats;
}

ClothFrameCheck ClothSimulation::check() const {
    const Stopwatch watch;
    ClothFrameCheck check;
    check.intersecting_pairs =
        collision::count_intersecting_pairs(m_solver->positions(), m_solver->triangles());
    check.obstacle_intersections = cloth::count_obstacle_intersections(m_solver->model());
    check.strain = m_edge_strain->measure(m_solver->positions());
    check.ms = watch.elapsed_ms();
    return check;
}

void ClothSimulation::save_state(ByteWriter& out) const {
    out.put(static_cast<std::int32_t>(m_frame));
    m_solver->save_state(out);
}

void ClothSimulation::load_state(ByteReader& in) {
    const auto frame = in.get<std::int32_t>("simulation.frame");
    if (frame < 0) {
        throw InvalidInput(
            fmt::format("{}: simulation.frame: {}, expected >= 0", in.source(), frame));
    }
    m_solver->load_state(in);
    m_frame = frame;
}

void ClothSimulation::reset() {
    m_solver = make_solver(m_scene, m_setup);
    if (!m_untangled_start.empty()) {
        m_solver->set_positions(m_untangled_start);
    }
    m_frame = 0;
}

}  // namespace pliant::pipeline
