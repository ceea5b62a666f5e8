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
    : m_scene(std::move(scene)), m_scene_name(std::move(scene_name)), m_options(options) {
    if (options.substeps_per_frame < 1 || options.check_every < 1) {
        throw InvalidInput(fmt::format(
            "viewer: substeps per frame ({}) and frames between intersection checks ({}) must "
            "be >= 1",
            options.substeps_per_frame, options.check_every));
    }
    m_setup = cli::load_cloth_setup(m_scene, m_scene_name);
    m_substep = 1.0 / (m_scene.frames_per_second * m_scene.substeps);
    m_framing_box = cli::framing_box(m_setup.mesh.positions, m_setup.shapes);
    m_scene_box = m_framing_box;
    for (const cli::ObstacleShape& shape : m_setup.shapes) {
        for (const Vec3d& p : shape.rest.positions) {
            m_scene_box.extend(p);
        }
    }
    reset();
}

void ClothSession::reset() {
    m_solver = cli::make_solver(m_scene, m_setup);
    m_frame = 0;
    m_stats = {};
    count_intersections();
}

void ClothSession::set_substeps_per_frame(int substeps) {
    m_options.substeps_per_frame = std::clamp(substeps, 1, 1000);
}

void ClothSession::advance() {
    const int n = m_options.substeps_per_frame;
    m_stats.step = m_solver->step(n * m_substep, n);
    ++m_frame;
    if (m_frame == 1 || m_frame % m_options.check_every == 0) {
        count_intersections();
    }
}

void ClothSession::count_intersections() {
    const Stopwatch watch;
    m_stats.intersecting_pairs =
        collision::count_intersecting_pairs(m_solver->positions(), m_solver->triangles());
    m_stats.checked_frame = m_frame;
    m_stats.check_ms = watch.elapsed_ms();
}

bool ClothSession::begin_grab(const render::Camera& camera, double x, double y) {
    const TriangleHit hit = intersect_triangles(camera.ray(x, y), positions(), triangles());
    const std::int32_t vertex = nearest_corner(hit, triangles());
    if (vertex < 0) {
        return false;
    }
    m_grab_anchor = positions()[static_cast<std::size_t>(vertex)];
    m_solver->grab(vertex, m_grab_anchor);
    return true;
}

void ClothSession::drag(const render::Camera& camera, double x, double y) {
    const std::int32_t vertex = m_solver->grabbed_vertex();
    if (vertex >= 0) {
        m_solver->grab(vertex, drag_target(camera, x, y, m_grab_anchor));
    }
}

void ClothSession::end_grab() {
    m_solver->release_grab();
}

}  // namespace pliant::viewer
