#include "pliant/cloth/solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/cloth/dihedral.hpp"
#include "pliant/cloth/isometric_bending.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t CONSTRAINT_GRAIN = 1024;
constexpr std::int64_t VERTEX_GRAIN = 2048;
constexpr std::int64_t CHAIN_PACKET_GRAIN = 2;
// The self-collision fail-safe checks the motion of every this many substeps (a window); the
// candidate pairs are gathered for one or two windows (SelfCollision::windows_for_next_gather).
constexpr int FAIL_SAFE_WINDOW = 4;
// Self-collision needs a thickness of at most this many median edge lengths: with more, every
// triangle is within reach of hundreds of others (in a flat sheet about 2π (thickness / edge)²),
// and a broad phase costs gigabytes (a 5 cm sheet of 134 × 134 quads under 5 mm: 24 GB).
constexpr double MAX_THICKNESS_IN_EDGES = 4.0;
// A strain limit moves its two vertices by at most this fraction of the thickness per substep
// (per limit: a vertex in several limits can move several times that; strain_hierarchy.hpp).
// Larger moves outran the self-collision's proximity constraints: at half the thickness the
// twist scene had 56 CCD hits in 36 frames, at a tenth none (docs/performance.md).
constexpr double STRAIN_LIMIT_MOVE = 0.1;

// Coordinates below 2^-200 m (6e-61 m: nothing cloth has is that short) become 0: the exact
// predicates of the self-collision and of the intersection count take 0 or magnitudes from
// 2^-300 up (geometry/exact_predicates.hpp; differences of coordinates of 2^-200 or more are
// multiples of 2^-252), and a chain solve spreads corrections that small along its chain (a
// vertex on a grid's symmetry line got x = 1.5e-98 in the pile scene).
void flush_tiny(Vec3d& x) {
    constexpr double TINY = 0x1p-200;
    x.x = std::abs(x.x) < TINY ? 0.0 : x.x;
    x.y = std::abs(x.y) < TINY ? 0.0 : x.y;
    x.z = std::abs(x.z) < TINY ? 0.0 : x.z;
}

void validate_material(const ClothMaterial& m) {
    const auto check = [](double value, const char* name) {
        if (!(value >= 0.0) || !std::isfinite(value)) {
            throw InvalidInput(fmt::format(
                "cloth material: {} must be a finite number >= 0, got {}", name, value));
        }
    };
    check(m.areal_density, "areal_density");
    check(m.stretch_compliance, "stretch_compliance");
    check(m.bend_compliance, "bend_compliance");
    if (!(m.strain_limit >= 0.0)) {
        throw InvalidInput(fmt::format(
            "cloth material: strain_limit must be a number >= 0 (infinity: none), got {}",
            m.strain_limit));
    }
    check(m.damping, "damping");
    check(m.thickness, "thickness");
    check(m.static_friction, "static_friction");
    check(m.kinetic_friction, "kinetic_friction");
    check(m.self_static_friction, "self_static_friction");
    check(m.self_kinetic_friction, "self_kinetic_friction");
}

// The obstacle at its rest placement moved by pose (boxes only translate: add_obstacle checks).
Obstacle placed(const Obstacle& rest, const Pose& pose) {
    if (const auto* plane = std::get_if<PlaneObstacle>(&rest)) {
        return PlaneObstacle{pose.apply(plane->point), pose.rotation.apply(plane->normal)};
    }
    if (const auto* sphere = std::get_if<SphereObstacle>(&rest)) {
        return SphereObstacle{pose.apply(sphere->center), sphere->radius};
    }
    const auto& box = std::get<BoxObstacle>(rest);
    return BoxObstacle{box.min + pose.translate, box.max + pose.translate};
}

}  // namespace

ClothSolver::ClothSolver(const geometry::TriangleMeshD& rest_mesh, const ClothMaterial& material,
                         std::span<const std::int32_t> pinned)
    : m_material(material),
      m_triangles(rest_mesh.triangles),
      m_positions(rest_mesh.positions),
      m_previous_positions(rest_mesh.positions),
      m_velocities(rest_mesh.positions.size(), Vec3d{0.0, 0.0, 0.0}),
      m_inverse_masses(rest_mesh.positions.size(), 0.0),
      m_contact_depths(rest_mesh.positions.size(), 0.0),
      m_contact_settled(rest_mesh.positions.size(), 0.0),
      m_contact_normals(rest_mesh.positions.size(), Vec3d{0.0, 0.0, 1.0}),
      m_contact_velocities(rest_mesh.positions.size(), Vec3d{0.0, 0.0, 0.0}) {
    validate_material(material);
    geometry::validate_mesh(rest_mesh, "cloth mesh");
    const std::size_t num_vertices = m_positions.size();

    // Masses from the rest area.
    std::vector<double> masses(num_vertices, 0.0);
    for (const geometry::Triangle& t : m_triangles) {
        const Vec3d& a = m_positions[static_cast<std::size_t>(t[0])];
        const Vec3d& b = m_positions[static_cast<std::size_t>(t[1])];
        const Vec3d& c = m_positions[static_cast<std::size_t>(t[2])];
        const double third = material.areal_density * 0.5 * norm(cross(b - a, c - a)) / 3.0;
        for (const std::int32_t v : t) {
            masses[static_cast<std::size_t>(v)] += third;
        }
    }
    for (std::size_t v = 0; v < num_vertices; ++v) {
        m_inverse_masses[v] = masses[v] > 0.0 ? 1.0 / masses[v] : 0.0;
    }
    for (const std::int32_t v : pinned) {
        if (v < 0 || static_cast<std::size_t>(v) >= num_vertices) {
            throw InvalidInput(
                fmt::format("cloth: pinned vertex {} out of range, expected an index in [0, {})", v,
                            num_vertices));
        }
        m_inverse_masses[static_cast<std::size_t>(v)] = 0.0;
    }

    // Constraints from the topology.
    m_topology = geometry::build_topology(m_triangles, num_vertices);
    const geometry::MeshTopology& topology = m_topology;
    for (const geometry::Edge& e : topology.edges) {
        m_stretch_vertices.push_back({e[0], e[1]});
        m_rest_lengths.push_back(norm(m_positions[static_cast<std::size_t>(e[1])] -
                                      m_positions[static_cast<std::size_t>(e[0])]));
    }
    // Hinges (x0, x1, x2, x3) as in dihedral.hpp, x2-x3 the shared edge, with their rest angles
    // (dihedral) or stencils (isometric).
    std::vector<std::array<std::int32_t, 4>> dihedral_hinges;
    std::vector<double> rest_angles;
    std::vector<std::array<std::int32_t, 4>> isometric_hinges;
    std::vector<std::array<double, 4>> stencils;
    for (std::int32_t e = 0; e < static_cast<std::int32_t>(topology.num_edges()); ++e) {
        const std::span<const std::int32_t> faces = topology.triangles_of_edge(e);
        if (faces.size() != 2) {
            continue;  // boundary or non-manifold edge: no bending
        }
        const geometry::Edge& edge = topology.edges[static_cast<std::size_t>(e)];
        // Orient the shared edge as triangle A traverses it: A = (x0, x2, x3).
        const geometry::Triangle& a = m_triangles[static_cast<std::size_t>(faces[0])];
        const geometry::Triangle& b = m_triangles[static_cast<std::size_t>(faces[1])];
        std::int32_t x2 = edge[0];
        std::int32_t x3 = edge[1];
        for (int k = 0; k < 3; ++k) {
            if (a[static_cast<std::size_t>(k)] == edge[1] &&
                a[static_cast<std::size_t>((k + 1) % 3)] == edge[0]) {
                std::swap(x2, x3);
            }
        }
        const auto opposite = [&](const geometry::Triangle& t) {
            for (const std::int32_t v : t) {
                if (v != edge[0] && v != edge[1]) {
                    return v;
                }
            }
            return t[0];
        };
        const std::array<std::int32_t, 4> vertices{opposite(a), opposite(b), x2, x3};
        if (vertices[0] == vertices[1]) {
            continue;  // two triangles on the same three vertices
        }
        const auto at = [&](std::int32_t v) {
            return m_positions[static_cast<std::size_t>(v)];
        };
        if (material.bending == BendingModel::isometric) {
            if (const auto stencil = isometric_bending_stencil(at(vertices[0]), at(vertices[1]),
                                                               at(vertices[2]), at(vertices[3]))) {
                isometric_hinges.push_back(vertices);
                stencils.push_back(*stencil);
                continue;
            }
        }
        dihedral_hinges.push_back(vertices);
        rest_angles.push_back(dihedral_angle_value(at(vertices[0]), at(vertices[1]),
                                                   at(vertices[2]), at(vertices[3])));
    }
    m_stretch =
        color_edges(m_stretch_vertices, m_rest_lengths, static_cast<std::int64_t>(num_vertices));
    // The kernels' columns, in colour order.
    m_dihedral = color_hinges(dihedral_hinges, static_cast<std::int64_t>(num_vertices));
    for (const std::int32_t i : m_dihedral.colors.order) {
        m_dihedral_rest.push_back(rest_angles[static_cast<std::size_t>(i)]);
    }
    m_isometric = color_hinges(isometric_hinges, static_cast<std::int64_t>(num_vertices));
    for (const std::int32_t i : m_isometric.colors.order) {
        for (std::size_t k = 0; k < 4; ++k) {
            m_isometric_k[k].push_back(stencils[static_cast<std::size_t>(i)][k]);
        }
    }
    m_packed.resize(num_vertices);
    if (material.stretch_solver == StretchSolver::chains) {
        // In colour order, so that an edge's index in the chains is its column in m_stretch.
        std::vector<std::array<std::int32_t, 2>> colored(m_stretch.p.size());
        for (std::size_t i = 0; i < colored.size(); ++i) {
            colored[i] = {m_stretch.p[i], m_stretch.q[i]};
        }
        m_chains = StretchChains(colored, m_stretch.rest, m_positions);
        m_chain_scratch.resize(static_cast<std::size_t>(m_chains.scratch_size()));
        m_stretch_lambda.assign(colored.size(), 0.0);
        m_packed.push_back({0.0, 0.0, 0.0, 0.0});  // the padding vertex
    }
    if (std::isfinite(material.strain_limit)) {
        m_strain_hierarchy = StrainHierarchy(static_cast<std::int64_t>(num_vertices),
                                             topology.edges, m_rest_lengths);
    }
}

void ClothSolver::enable_self_collision(bool enabled) {
    if (!enabled) {
        m_self_collision.reset();
    } else if (!m_self_collision) {
        if (!m_rest_lengths.empty()) {
            std::vector<double> lengths = m_rest_lengths;
            const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
            std::nth_element(lengths.begin(), middle, lengths.end());
            if (m_material.thickness > MAX_THICKNESS_IN_EDGES * *middle) {
                throw InvalidInput(fmt::format(
                    "cloth: self-collision: material.thickness ({} m) is {:.1f} times the "
                    "median edge length ({:.3g} m), expected at most {}: every triangle would be "
                    "within reach of hundreds of others; use a smaller thickness or a coarser "
                    "mesh, or turn self_collision off",
                    m_material.thickness, m_material.thickness / *middle, *middle,
                    MAX_THICKNESS_IN_EDGES));
            }
        }
        m_self_collision =
            std::make_unique<SelfCollision>(m_triangles, m_positions.size(), m_material.thickness);
        m_gather_end_time = -std::numeric_limits<double>::infinity();
    }
}

UntangleResult ClothSolver::untangle(const UntangleOptions& options) {
    UntangleOptions with_obstacles = options;
    if (!with_obstacles.obstacle_distance && !(m_obstacles.empty() && m_mesh_obstacles.empty())) {
        // Where the obstacles are now (before the first step: where their motion has them at
        // time 0).
        with_obstacles.obstacle_distance = [this](const Vec3d& x) {
            return nearest_obstacle(x).distance;
        };
    }
    const UntangleResult result =
        cloth::untangle(m_positions, m_triangles, m_inverse_masses, with_obstacles);
    if (result.iterations > 0) {
        restart_self_collision();
    }
    return result;
}

SurfaceDistance ClothSolver::nearest_obstacle(const Vec3d& x) const {
    SurfaceDistance nearest{std::numeric_limits<double>::infinity(), {0.0, 0.0, 0.0}};
    for (const MovingObstacle& obstacle : m_obstacles) {
        const SurfaceDistance s = surface_distance(obstacle.current, x);
        if (s.distance < nearest.distance) {
            nearest = s;
        }
    }
    for (const MovingMesh& mesh : m_mesh_obstacles) {
        const Pose& pose = mesh.state.pose;
        const std::optional<SurfaceDistance> s =
            mesh.mesh->surface_distance(pose.apply_inverse(x), norm(mesh.mesh->bounds().extent()));
        if (s && s->distance < nearest.distance) {
            nearest = {s->distance, pose.rotation.apply(s->normal)};
        }
    }
    return nearest;
}

ClothSolver::Penetration ClothSolver::obstacle_penetration() const {
    Penetration penetration;
    if (m_obstacles.empty() && m_mesh_obstacles.empty()) {
        return penetration;
    }
    for (std::size_t v = 0; v < m_positions.size(); ++v) {
        if (m_inverse_masses[v] > 0.0) {
            const double distance = nearest_obstacle(m_positions[v]).distance;
            if (distance < 0.0) {
                ++penetration.vertices;
                penetration.deepest = std::max(penetration.deepest, -distance);
            }
        }
    }
    return penetration;
}

void ClothSolver::set_positions(std::span<const Vec3d> positions) {
    if (positions.size() != m_positions.size()) {
        throw InvalidInput(fmt::format("cloth: positions.size() ({}) != the vertex count ({})",
                                       positions.size(), m_positions.size()));
    }
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (!is_finite(positions[i])) {
            throw InvalidInput(fmt::format("cloth: position of vertex {} is not finite", i));
        }
        if (m_inverse_masses[i] == 0.0 && !(positions[i] == m_positions[i])) {
            const Vec3d& at = m_positions[i];
            throw InvalidInput(fmt::format(
                "cloth: vertex {} does not move (pinned, grabbed or without area) from ({}, {}, "
                "{}), got ({}, {}, {})",
                i, at.x, at.y, at.z, positions[i].x, positions[i].y, positions[i].z));
        }
    }
    m_positions.assign(positions.begin(), positions.end());
    restart_self_collision();
}

void ClothSolver::restart_self_collision() {
    if (m_self_collision) {
        m_self_collision.reset();
        enable_self_collision(true);
    }
}

void ClothSolver::add_obstacle(const Obstacle& obstacle, const Motion& motion) {
    if (const auto* plane = std::get_if<PlaneObstacle>(&obstacle)) {
        if (!(squared_norm(plane->normal) > 0.0) || !is_finite(plane->normal) ||
            !is_finite(plane->point)) {
            throw InvalidInput("cloth: a plane obstacle needs a finite point and a nonzero normal");
        }
    }
    if (const auto* sphere = std::get_if<SphereObstacle>(&obstacle)) {
        if (!(sphere->radius > 0.0) || !std::isfinite(sphere->radius) ||
            !is_finite(sphere->center)) {
            throw InvalidInput(fmt::format(
                "cloth: a sphere obstacle needs a finite centre and radius > 0, got radius {}",
                sphere->radius));
        }
    }
    if (const auto* box = std::get_if<BoxObstacle>(&obstacle)) {
        if (!(box->min.x <= box->max.x && box->min.y <= box->max.y && box->min.z <= box->max.z) ||
            !is_finite(box->min) || !is_finite(box->max)) {
            throw InvalidInput("cloth: a box obstacle needs finite min <= max on every axis");
        }
        if (motion.rotates()) {
            throw InvalidInput(
                "cloth: a box obstacle stays axis-aligned, expected a motion without rotation");
        }
    }
    if (!motion.is_valid()) {
        throw InvalidInput(
            "cloth: obstacle motion: expected finite keyframes at strictly increasing times");
    }
    MotionState state(motion, m_time);
    const Obstacle now = placed(obstacle, state.pose);
    m_obstacles.push_back(MovingObstacle{obstacle, std::move(state), now, now});
}

void ClothSolver::add_mesh_obstacle(std::shared_ptr<const MeshObstacle> obstacle,
                                    const Motion& motion) {
    if (!obstacle) {
        throw InvalidInput("cloth: a mesh obstacle needs a mesh");
    }
    if (!motion.is_valid()) {
        throw InvalidInput(
            "cloth: obstacle motion: expected finite keyframes at strictly increasing times");
    }
    m_mesh_obstacles.push_back({std::move(obstacle), MotionState(motion, m_time)});
}

void ClothSolver::add_moving_pins(std::span<const std::int32_t> vertices, const Motion& motion) {
    if (!motion.is_valid()) {
        throw InvalidInput(
            "cloth: pin motion: expected finite keyframes at strictly increasing times");
    }
    MovingPins pins;
    pins.motion = motion;
    const Pose start = motion.pose(m_time);
    for (const std::int32_t v : vertices) {
        if (v < 0 || static_cast<std::size_t>(v) >= m_positions.size()) {
            throw InvalidInput(
                fmt::format("cloth: pinned vertex {} out of range, expected an index in [0, {})", v,
                            m_positions.size()));
        }
        m_inverse_masses[static_cast<std::size_t>(v)] = 0.0;
        pins.vertices.push_back(v);
        // The rest placement that the motion's current pose maps to the vertex's position.
        pins.rest_positions.push_back(
            start.apply_inverse(m_positions[static_cast<std::size_t>(v)]));
    }
    m_moving_pins.push_back(std::move(pins));
}

void ClothSolver::set_velocities(std::span<const Vec3d> velocities) {
    if (velocities.size() != m_velocities.size()) {
        throw InvalidInput(fmt::format("cloth: velocities.size() ({}) != the vertex count ({})",
                                       velocities.size(), m_velocities.size()));
    }
    for (const Vec3d& v : velocities) {
        if (!is_finite(v)) {
            throw InvalidInput("cloth: velocities must be finite");
        }
    }
    m_velocities.assign(velocities.begin(), velocities.end());
}

void ClothSolver::grab(std::int32_t vertex, const Vec3d& target) {
    if (vertex < 0 || static_cast<std::size_t>(vertex) >= m_positions.size()) {
        throw InvalidInput(
            fmt::format("cloth: grabbed vertex {} out of range, expected an index in [0, {})",
                        vertex, m_positions.size()));
    }
    if (!is_finite(target)) {
        throw InvalidInput(fmt::format("cloth: grab target ({}, {}, {}) is not finite", target.x,
                                       target.y, target.z));
    }
    if (m_grab && m_grab->vertex != vertex) {
        release_grab();
    }
    if (!m_grab) {
        const auto v = static_cast<std::size_t>(vertex);
        m_grab = Grab{vertex, m_positions[v], target, m_inverse_masses[v]};
        m_inverse_masses[v] = 0.0;
    }
    m_grab->target = target;
}

void ClothSolver::release_grab() {
    if (m_grab) {
        m_inverse_masses[static_cast<std::size_t>(m_grab->vertex)] = m_grab->inverse_mass;
        m_grab.reset();
    }
}

void ClothSolver::set_air(const Air& air) {
    if (!(air.density >= 0.0) || !std::isfinite(air.density) || !(air.drag_coefficient >= 0.0) ||
        !std::isfinite(air.drag_coefficient) || !is_finite(air.wind) ||
        !(air.gust_amplitude >= 0.0) || !std::isfinite(air.gust_amplitude) ||
        !(air.gust_period > 0.0) || !std::isfinite(air.gust_period) ||
        !(air.gust_wavelength > 0.0) || !std::isfinite(air.gust_wavelength)) {
        throw InvalidInput(
            "cloth: air: expected finite density, drag_coefficient and gust_amplitude >= 0, "
            "gust_period and gust_wavelength > 0 and a finite wind");
    }
    m_air = air;
    m_triangle_forces.assign(air.is_active() ? m_triangles.size() : 0, Vec3d{});
}

ClothStepStats ClothSolver::step(double dt, int substeps) {
    if (!(dt > 0.0) || !std::isfinite(dt) || substeps < 1) {
        throw InvalidInput(fmt::format(
            "cloth step: expected dt > 0 (finite) and substeps >= 1, got dt {} and substeps {}", dt,
            substeps));
    }
    Stopwatch watch;
    const double h = dt / substeps;
    ClothStepStats stats;
    const double start_time = m_time;
    if (m_self_collision) {
        m_self_collision->reset_stats();
    }
    // With self-collision the step runs in windows of FAIL_SAFE_WINDOW substeps, each ending with
    // the fail-safe over the window's motion; candidates are gathered at the start of a window for
    // it and, while contact is sparse, the next one too. A window's start-to-end line is close to
    // the path its substeps took (a frame's is not: cloth that folds around something within a
    // frame crosses it on the straight line between the frame's ends), and a vertex put back loses
    // only that window's motion.
    m_step_start = start_time;
    m_step_dt = dt;
    if (m_grab) {
        m_grab->start = m_positions[static_cast<std::size_t>(m_grab->vertex)];
    }
    for (int s = 0; s < substeps; ++s) {
        if (m_self_collision && s % FAIL_SAFE_WINDOW == 0) {
            // A new gather unless the last one's span covers this window (times compared to a
            // millionth of a substep: steps sum their times differently).
            const double window_start = start_time + s * h;
            const double window_end = start_time + std::min(s + FAIL_SAFE_WINDOW, substeps) * h;
            const double slop = 1e-6 * h;
            if (window_start < m_gather_start_time - slop ||
                window_end > m_gather_end_time + slop) {
                const int windows = m_self_collision->windows_for_next_gather();
                const double span = windows * FAIL_SAFE_WINDOW * h;
                m_self_collision->prepare(m_positions, m_velocities, window_start, span);
                m_gather_start_time = window_start;
                m_gather_end_time = window_start + span;
            }
            m_window_start = m_positions;
            m_window_start_time = window_start;
        }
        stats.obstacle_contacts = substep(h, start_time + (s + 1) * h, stats.solve_ms);
        if (m_self_collision &&
            (s % FAIL_SAFE_WINDOW == FAIL_SAFE_WINDOW - 1 || s == substeps - 1)) {
            m_self_collision->enforce(m_window_start, m_positions, m_velocities,
                                      m_window_start_time, start_time + (s + 1) * h);
        }
    }
    m_time = start_time + dt;
    if (m_self_collision) {
        stats.has_self_collision = true;
        stats.self = m_self_collision->stats();
    }
    stats.ms = watch.elapsed_ms();
    return stats;
}

std::int64_t ClothSolver::substep(double h, double t_end, double& solve_ms) {
    Stopwatch watch;
    const auto n = static_cast<std::int64_t>(m_positions.size());
    if (m_air.is_active()) {
        apply_air(h, t_end - h);
    }
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_previous_positions[v] = m_positions[v];
            if (m_inverse_masses[v] > 0.0) {
                m_velocities[v] += m_gravity * h;
                m_positions[v] += m_velocities[v] * h;
            }
        },
        VERTEX_GRAIN);
    for (const MovingPins& pins : m_moving_pins) {
        const Pose pose = pins.motion.pose(t_end);
        parallel_for(static_cast<std::int64_t>(pins.vertices.size()), [&](std::int64_t k) {
            m_positions[static_cast<std::size_t>(pins.vertices[static_cast<std::size_t>(k)])] =
                pose.apply(pins.rest_positions[static_cast<std::size_t>(k)]);
        });
    }
    if (m_grab) {
        const double f = std::min(1.0, (t_end - m_step_start) / m_step_dt);
        m_positions[static_cast<std::size_t>(m_grab->vertex)] =
            m_grab->start + (m_grab->target - m_grab->start) * f;
    }
    project_constraints(h);
    move_obstacles(t_end);
    const std::int64_t contacts = resolve_obstacles(h);
    solve_ms += watch.elapsed_ms();
    // Self-contacts last: the substep ends with the cloth apart from itself (an obstacle's push
    // may have pressed one layer into the next); a vertex pushed back into an obstacle is
    // pushed out again next substep, while layers that pass through each other stay entangled.
    if (m_self_collision) {
        m_self_collision->project(m_positions, m_previous_positions, m_inverse_masses, m_material,
                                  t_end, h);
    }
    watch.restart();
    const double keep = std::max(0.0, 1.0 - m_material.damping * h);
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            flush_tiny(m_positions[v]);
            Vec3d velocity = (m_positions[v] - m_previous_positions[v]) * (1.0 / h);
            if (m_contact_depths[v] > 0.0) {
                // A penetration the substep began with is undone without becoming velocity
                // (cloth given inside an obstacle comes out, it is not thrown out); friction acts
                // on the velocity relative to the obstacle's surface, bounded by the rest.
                const double settled = m_contact_settled[v];
                velocity -= m_contact_normals[v] * (settled / h);
                velocity = m_contact_velocities[v] +
                           apply_friction(velocity - m_contact_velocities[v], m_contact_normals[v],
                                          (m_contact_depths[v] - settled) / h,
                                          m_material.static_friction, m_material.kinetic_friction);
            }
            m_velocities[v] = velocity * keep;
        },
        VERTEX_GRAIN);
    solve_ms += watch.elapsed_ms();
    return contacts;
}

void ClothSolver::apply_air(double h, double t) {
    // Per triangle, then per vertex over its incident triangles in ascending order: no
    // concurrent writes, the same sums for any number of threads.
    parallel_for(
        static_cast<std::int64_t>(m_triangles.size()),
        [&](std::int64_t i) {
            const geometry::Triangle& tri = m_triangles[static_cast<std::size_t>(i)];
            const Vec3d& a = m_positions[static_cast<std::size_t>(tri[0])];
            const Vec3d& b = m_positions[static_cast<std::size_t>(tri[1])];
            const Vec3d& c = m_positions[static_cast<std::size_t>(tri[2])];
            const Vec3d area_normal = cross(b - a, c - a) * 0.5;  // |.| = area
            const double area = norm(area_normal);
            Vec3d force{0.0, 0.0, 0.0};
            if (area > 0.0) {
                const Vec3d velocity = (m_velocities[static_cast<std::size_t>(tri[0])] +
                                        m_velocities[static_cast<std::size_t>(tri[1])] +
                                        m_velocities[static_cast<std::size_t>(tri[2])]) *
                                       (1.0 / 3.0);
                const Vec3d centre = (a + b + c) * (1.0 / 3.0);
                const Vec3d normal = area_normal * (1.0 / area);
                const double u_n = dot(velocity - m_air.wind_at(centre, t), normal);
                // Drag can at most stop the relative motion within the substep: the impulse is
                // capped at the triangle's momentum normal to it (explicit quadratic drag would
                // overshoot and blow up once h ρ C_d |u·n| / areal_density > 2).
                const double drag = 0.5 * m_air.density * m_air.drag_coefficient * area * u_n * u_n;
                const double stopping = m_material.areal_density * area * std::abs(u_n) / h;
                force = normal * (-std::copysign(std::min(drag, stopping), u_n));
            }
            m_triangle_forces[static_cast<std::size_t>(i)] = force;
        },
        VERTEX_GRAIN);
    parallel_for(
        static_cast<std::int64_t>(m_positions.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            if (!(m_inverse_masses[v] > 0.0)) {
                return;
            }
            Vec3d force{0.0, 0.0, 0.0};
            for (const std::int32_t triangle :
                 m_topology.triangles_of_vertex(static_cast<std::int32_t>(i))) {
                force += m_triangle_forces[static_cast<std::size_t>(triangle)];
            }
            m_velocities[v] += force * (m_inverse_masses[v] * h / 3.0);
        },
        VERTEX_GRAIN);
}

void ClothSolver::move_obstacles(double t) {
    for (MovingObstacle& obstacle : m_obstacles) {
        if (!obstacle.state.motion.is_static()) {
            obstacle.state.advance(t);
            obstacle.previous = obstacle.current;
            obstacle.current = placed(obstacle.rest, obstacle.state.pose);
        }
    }
    for (MovingMesh& mesh : m_mesh_obstacles) {
        mesh.state.advance(t);
    }
}

void ClothSolver::project_constraints(double h) {
    // Positions and inverse masses packed for the kernels (detail/constraint_kernels.hpp), then
    // the strain limits (with material.strain_limit; strain_hierarchy.hpp), stretch and bending
    // colour by colour, each colour in parallel over fixed chunks.
    const auto n = static_cast<std::int64_t>(m_positions.size());
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_packed[v] = {m_positions[v].x, m_positions[v].y, m_positions[v].z,
                           m_inverse_masses[v]};
        },
        VERTEX_GRAIN);
    detail::PackedVertex* x = m_packed.data();
    if (std::isfinite(m_material.strain_limit)) {
        m_strain_hierarchy.project(x, m_material.strain_limit,
                                   m_material.thickness > 0.0
                                       ? STRAIN_LIMIT_MOVE * m_material.thickness
                                       : std::numeric_limits<double>::infinity());
    }
    const double stretch_alpha = m_material.stretch_compliance / (h * h);
    // Chains first (their Δλ per edge, in colour order, to m_stretch_lambda), then the sweep
    // over single edges as XPBD's next iteration from those λ.
    const detail::ChainSolve chain_solve{stretch_alpha, CHAIN_REGULARIZATION,
                                         CHAIN_STRAIN_REGULARIZATION};
    for (std::int32_t f = 0; f < m_chains.num_families(); ++f) {
        const std::int32_t first = m_chains.first_packet(f);
        parallel_for_chunks(m_chains.first_packet(f + 1) - first, CHAIN_PACKET_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                for (std::int64_t i = begin; i < end; ++i) {
                                    const auto p = first + static_cast<std::int32_t>(i);
                                    detail::project_chain_packet(
                                        x, m_chains.packet(p), chain_solve, m_stretch_lambda.data(),
                                        m_chain_scratch.data() + m_chains.scratch_offset(p));
                                }
                            });
    }
    const bool chains = m_chains.num_families() > 0;
    for (std::int32_t c = 0; c < m_stretch.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_stretch.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::StretchColumns columns{
            m_stretch.p.data() + offset, m_stretch.q.data() + offset,
            m_stretch.rest.data() + offset, chains ? m_stretch_lambda.data() + offset : nullptr};
        parallel_for_chunks(static_cast<std::int64_t>(m_stretch.colors.color(c).size()),
                            CONSTRAINT_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                detail::project_stretch(x, columns, begin, end, stretch_alpha);
                            });
    }
    const double bend_alpha = m_material.bend_compliance / (h * h);
    for (std::int32_t c = 0; c < m_dihedral.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_dihedral.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::BendingColumns columns{
            m_dihedral.v[0].data() + offset, m_dihedral.v[1].data() + offset,
            m_dihedral.v[2].data() + offset, m_dihedral.v[3].data() + offset,
            m_dihedral_rest.data() + offset};
        parallel_for_chunks(static_cast<std::int64_t>(m_dihedral.colors.color(c).size()),
                            CONSTRAINT_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                detail::project_bending(x, columns, begin, end, bend_alpha);
                            });
    }
    for (std::int32_t c = 0; c < m_isometric.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_isometric.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::IsometricBendingColumns columns{
            m_isometric.v[0].data() + offset, m_isometric.v[1].data() + offset,
            m_isometric.v[2].data() + offset, m_isometric.v[3].data() + offset,
            m_isometric_k[0].data() + offset, m_isometric_k[1].data() + offset,
            m_isometric_k[2].data() + offset, m_isometric_k[3].data() + offset};
        parallel_for_chunks(
            static_cast<std::int64_t>(m_isometric.colors.color(c).size()), CONSTRAINT_GRAIN,
            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                detail::project_isometric_bending(x, columns, begin, end, bend_alpha);
            });
    }
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_positions[v] = {m_packed[v].x, m_packed[v].y, m_packed[v].z};
        },
        VERTEX_GRAIN);
}

std::int64_t ClothSolver::resolve_obstacles(double h) {
    if (m_obstacles.empty() && m_mesh_obstacles.empty()) {
        return 0;
    }
    return parallel_reduce(
        static_cast<std::int64_t>(m_positions.size()), std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t contacts = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                m_contact_depths[v] = 0.0;
                m_contact_settled[v] = 0.0;
                if (!(m_inverse_masses[v] > 0.0)) {
                    continue;
                }
                const Vec3d& start = m_previous_positions[v];
                const double thickness = m_material.thickness;
                for (const MovingObstacle& obstacle : m_obstacles) {
                    const ContactCorrection contact =
                        push_out(obstacle.current, m_positions[v], thickness);
                    if (contact.depth > m_contact_depths[v]) {
                        m_contact_depths[v] = contact.depth;
                        m_contact_normals[v] = contact.normal;
                        // The surface point under x moved from where the previous pose had it.
                        m_contact_velocities[v] =
                            obstacle.state.surface_displacement(m_positions[v]) * (1.0 / h);
                        // How deep the vertex already was when the substep began.
                        const double was_in =
                            thickness - surface_distance(obstacle.previous, start).distance;
                        m_contact_settled[v] = std::clamp(was_in, 0.0, contact.depth);
                    }
                }
                for (const MovingMesh& mesh : m_mesh_obstacles) {
                    // In the mesh's rest frame. A vertex can be as deep as its own motion plus
                    // the surface's over the substep, plus the thickness.
                    Vec3d& x = m_positions[v];
                    const Vec3d swept_by_surface = mesh.state.surface_displacement(x);
                    const double max_depth =
                        norm(x - start) + norm(swept_by_surface) + 2.0 * thickness;
                    const Pose& pose = mesh.state.pose;
                    Vec3d x_rest = pose.apply_inverse(x);
                    const ContactCorrection contact =
                        push_out(*mesh.mesh, x_rest, thickness, max_depth);
                    if (contact.depth > 0.0) {
                        x = pose.apply(x_rest);
                    }
                    if (contact.depth > m_contact_depths[v]) {
                        m_contact_depths[v] = contact.depth;
                        m_contact_normals[v] = pose.rotation.apply(contact.normal);
                        m_contact_velocities[v] = swept_by_surface * (1.0 / h);
                        const std::optional<SurfaceDistance> before = mesh.mesh->surface_distance(
                            mesh.state.previous_pose.apply_inverse(start), max_depth);
                        m_contact_settled[v] =
                            before ? std::clamp(thickness - before->distance, 0.0, contact.depth)
                                   : 0.0;
                    }
                }
                contacts += m_contact_depths[v] > 0.0 ? 1 : 0;
            }
            return contacts;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, VERTEX_GRAIN);
}

}  // namespace pliant::cloth
