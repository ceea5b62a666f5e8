#include "cloth_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

#include "picking.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::viewer {

ClothSession::ClothSession(cloth::ClothScene scene, std::string scene_name,
                           const ClothSessionOptions& options)
    : m_options(options) {
    if (options.substeps_per_frame < 1 || options.check_every < 1) {
        throw InvalidInput(fmt::format(
            "viewer: substeps per frame ({}) and frames between intersection checks ({}) must "
            "be >= 1",
            options.substeps_per_frame, options.check_every));
    }
    m_sim = std::make_unique<pipeline::ClothSimulation>(
        pipeline::ClothSimulation::from_scene(std::move(scene), std::move(scene_name)));
    m_substep = 1.0 / (m_sim->scene().frames_per_second * m_sim->scene().substeps);
    start_from_reset();
    // Framed as `pliant cloth`'s preview: the cloth at its start (untangled) and the obstacles.
    m_framing_box = pipeline::framing_box(m_positions, setup().shapes);
    m_scene_box = m_framing_box;
    for (const pipeline::ObstacleShape& shape : setup().shapes) {
        for (const Vec3d& p : shape.rest.positions) {
            m_scene_box.extend(p);
        }
    }
}

void ClothSession::reset() {
    if (m_task.is_started()) {
        m_task.wait();  // the frame in flight is dropped
    }
    m_sim->reset();
    start_from_reset();
}

void ClothSession::start_from_reset() {
    m_solver_frame = 0;
    m_solver_stats = {};
    m_grab_vertex = -1;
    m_grab_changed = false;
    count_intersections();
    publish();
}

void ClothSession::set_substeps_per_frame(int substeps) {
    m_options.substeps_per_frame = std::clamp(substeps, 1, 1000);
}

void ClothSession::advance() {
    start_advance();
    finish_advance(true);
}

bool ClothSession::start_advance() {
    if (m_task.is_started()) {
        return false;
    }
    if (m_grab_changed) {
        if (m_grab_vertex >= 0) {
            m_sim->solver().grab(m_grab_vertex, m_grab_target);
        } else {
            m_sim->solver().release_grab();
        }
        m_grab_changed = false;
    }
    const int substeps = m_options.substeps_per_frame;
    m_task.start([this, substeps] { run_frame(substeps); });
    return true;
}

bool ClothSession::finish_advance(bool block) {
    if (!m_task.is_started() || (!block && !m_task.is_done())) {
        return false;
    }
    m_task.wait();
    publish();
    return true;
}

void ClothSession::run_frame(int substeps) {
    m_solver_stats.step = m_sim->solver().step(substeps * m_substep, substeps);
    ++m_solver_frame;
    if (m_solver_frame == 1 || m_solver_frame % m_options.check_every == 0) {
        count_intersections();
    }
}

void ClothSession::count_intersections() {
    const Stopwatch watch;
    m_solver_stats.intersecting_pairs = collision::count_intersecting_pairs(
        m_sim->solver().positions(), m_sim->solver().triangles());
    m_solver_stats.checked_frame = m_solver_frame;
    m_solver_stats.check_ms = watch.elapsed_ms();
}

void ClothSession::publish() {
    m_positions.assign(m_sim->solver().positions().begin(), m_sim->solver().positions().end());
    m_time = m_sim->solver().time();
    m_frame = m_solver_frame;
    m_stats = m_solver_stats;
}

bool ClothSession::begin_grab(const render::Camera& camera, double x, double y) {
    const TriangleHit hit = intersect_triangles(camera.ray(x, y), positions(), triangles());
    const std::int32_t vertex = nearest_corner(hit, triangles());
    if (vertex < 0) {
        return false;
    }
    m_grab_vertex = vertex;
    m_grab_anchor = m_positions[static_cast<std::size_t>(vertex)];
    m_grab_target = m_grab_anchor;
    m_grab_changed = true;
    return true;
}

void ClothSession::drag(const render::Camera& camera, double x, double y) {
    if (m_grab_vertex >= 0) {
        m_grab_target = drag_target(camera, x, y, m_grab_anchor);
        m_grab_changed = true;
    }
}

void ClothSession::end_grab() {
    if (m_grab_vertex >= 0) {
        m_grab_vertex = -1;
        m_grab_changed = true;
    }
}

}  // namespace pliant::viewer
