#include "pliant/cloth/cloth_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pliant/cloth/detail/air_kernels.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t VERTEX_GRAIN = 2048;

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

// The orthonormal frame of a triangle (rows: the unit first edge, the unit normal's cross with
// it, the unit normal), or the identity for a degenerate triangle.
Rotation triangle_frame(const std::array<Vec3d, 3>& c) {
    const Vec3d e = c[1] - c[0];
    const Vec3d n = cross(e, c[2] - c[0]);
    const double e_length = norm(e);
    const double n_length = norm(n);
    Rotation frame;
    if (e_length > 0.0 && n_length > 0.0) {
        frame.row[0] = e * (1.0 / e_length);
        frame.row[2] = n * (1.0 / n_length);
        frame.row[1] = cross(frame.row[2], frame.row[0]);
    }
    return frame;
}

// d in a triangle's frame, and back: a point attached to the triangle turns with it.
Vec3d to_triangle_frame(const std::array<Vec3d, 3>& c, const Vec3d& d) {
    return triangle_frame(c).apply(d);
}
Vec3d from_triangle_frame(const std::array<Vec3d, 3>& c, const Vec3d& local) {
    return triangle_frame(c).apply_inverse(local);
}

// How far an analytic obstacle's surface moved between two placements of one shape (m): a
// sphere's centre, a plane along its normal, a box's corner.
double obstacle_move(const Obstacle& before, const Obstacle& after) {
    if (const auto* plane = std::get_if<PlaneObstacle>(&after)) {
        const auto& was = std::get<PlaneObstacle>(before);
        return std::abs(dot(plane->point - was.point, plane->normal)) / norm(plane->normal);
    }
    if (const auto* sphere = std::get_if<SphereObstacle>(&after)) {
        return norm(sphere->center - std::get<SphereObstacle>(before).center);
    }
    return norm(std::get<BoxObstacle>(after).min - std::get<BoxObstacle>(before).min);
}

}  // namespace

ClothModel::ClothModel(const geometry::TriangleMeshD& rest_mesh, const ClothMaterial& material,
                       std::span<const std::int32_t> pinned)
    : m_material(material),
      m_triangles(rest_mesh.triangles),
      m_rest_positions(rest_mesh.positions),
      m_positions(rest_mesh.positions),
      m_velocities(rest_mesh.positions.size(), Vec3d{0.0, 0.0, 0.0}),
      m_inverse_masses(rest_mesh.positions.size(), 0.0) {
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
    m_topology = geometry::build_topology(m_triangles, num_vertices);
}

void ClothModel::add_obstacle(const Obstacle& obstacle, const Motion& motion) {
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

void ClothModel::add_mesh_obstacle(std::shared_ptr<const MeshObstacle> obstacle,
                                   const Motion& motion) {
    if (!obstacle) {
        throw InvalidInput("cloth: a mesh obstacle needs a mesh");
    }
    if (!motion.is_valid()) {
        throw InvalidInput(
            "cloth: obstacle motion: expected finite keyframes at strictly increasing times");
    }
    m_mesh_obstacles.push_back({std::move(obstacle), MotionState(motion, m_time), {}, {}, {}});
}

std::size_t ClothModel::add_animated_mesh_obstacle(const MeshObstacle& obstacle,
                                                   std::shared_ptr<const MeshAnimation> animation,
                                                   const Motion& motion) {
    if (!animation) {
        throw InvalidInput("cloth: an animated mesh obstacle needs an animation");
    }
    if (animation->num_vertices() != obstacle.mesh().positions.size()) {
        throw InvalidInput(fmt::format(
            "cloth: animated mesh obstacle: the animation has {} vertices per frame, the mesh {}",
            animation->num_vertices(), obstacle.mesh().positions.size()));
    }
    if (!motion.is_valid()) {
        throw InvalidInput(
            "cloth: obstacle motion: expected finite keyframes at strictly increasing times");
    }
    auto deforming = std::make_shared<MeshObstacle>(obstacle);
    std::vector<Vec3d> now(animation->num_vertices());
    animation->positions_at(m_time, now);
    deforming->set_positions(now);
    m_mesh_obstacles.push_back(
        {deforming, MotionState(motion, m_time), std::move(animation), deforming, std::move(now)});
    return m_mesh_obstacles.size() - 1;
}

void ClothModel::add_moving_pins(std::span<const std::int32_t> vertices, const Motion& motion) {
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
    add_pin_group(std::move(pins));
}

void ClothModel::add_pin_group(MovingPins pins) {
    // A vertex follows its last group: it leaves the earlier ones.
    std::vector<bool> in_group(m_positions.size(), false);
    for (const std::int32_t v : pins.vertices) {
        in_group[static_cast<std::size_t>(v)] = true;
    }
    for (MovingPins& earlier : m_moving_pins) {
        const bool attached = earlier.mesh_obstacle >= 0;
        std::size_t kept = 0;
        for (std::size_t k = 0; k < earlier.vertices.size(); ++k) {
            if (!in_group[static_cast<std::size_t>(earlier.vertices[k])]) {
                earlier.vertices[kept] = earlier.vertices[k];
                earlier.rest_positions[kept] = earlier.rest_positions[k];
                if (attached) {
                    earlier.triangles[kept] = earlier.triangles[k];
                    earlier.barycentric[kept] = earlier.barycentric[k];
                    earlier.offsets[kept] = earlier.offsets[k];
                }
                ++kept;
            }
        }
        earlier.vertices.resize(kept);
        earlier.rest_positions.resize(kept);
        if (attached) {
            earlier.triangles.resize(kept);
            earlier.barycentric.resize(kept);
            earlier.offsets.resize(kept);
        }
    }
    m_moving_pins.push_back(std::move(pins));
}

void ClothModel::add_attached_pins(std::span<const std::int32_t> vertices,
                                   std::size_t mesh_obstacle, double max_distance) {
    if (mesh_obstacle >= m_mesh_obstacles.size()) {
        throw InvalidInput(fmt::format(
            "cloth: attached pins: mesh obstacle {} out of range, expected an index below {}",
            mesh_obstacle, m_mesh_obstacles.size()));
    }
    const MovingMeshObstacle& body = m_mesh_obstacles[mesh_obstacle];
    MovingPins pins;
    pins.mesh_obstacle = static_cast<std::int64_t>(mesh_obstacle);
    const double reach = norm(body.mesh->bounds().extent()) + max_distance;
    for (const std::int32_t v : vertices) {
        if (v < 0 || static_cast<std::size_t>(v) >= m_positions.size()) {
            throw InvalidInput(
                fmt::format("cloth: pinned vertex {} out of range, expected an index in [0, {})", v,
                            m_positions.size()));
        }
        const Vec3d& x = m_positions[static_cast<std::size_t>(v)];
        const Vec3d x_rest = body.state.pose.apply_inverse(x);
        const std::optional<MeshObstacle::SurfacePoint> point =
            body.mesh->surface_point(x_rest, std::isfinite(reach) ? reach : 1e300);
        if (!point || !(std::abs(point->surface.distance) <= max_distance)) {
            throw InvalidInput(fmt::format(
                "cloth: attached pins: vertex {} at ({}, {}, {}) is {} m from mesh obstacle {}'s "
                "surface, expected at most {} m",
                v, x.x, x.y, x.z, point ? std::abs(point->surface.distance) : reach, mesh_obstacle,
                max_distance));
        }
        const geometry::Triangle& tri =
            body.mesh->mesh().triangles[static_cast<std::size_t>(point->triangle)];
        const std::span<const Vec3d> corners = body.mesh->mesh().positions;
        const std::array<Vec3d, 3> c{corners[static_cast<std::size_t>(tri[0])],
                                     corners[static_cast<std::size_t>(tri[1])],
                                     corners[static_cast<std::size_t>(tri[2])]};
        const Vec3d on_surface =
            c[0] * point->barycentric.x + c[1] * point->barycentric.y + c[2] * point->barycentric.z;
        pins.vertices.push_back(v);
        pins.rest_positions.push_back(x_rest);
        pins.triangles.push_back(point->triangle);
        pins.barycentric.push_back(point->barycentric);
        pins.offsets.push_back(to_triangle_frame(c, x_rest - on_surface));
        m_inverse_masses[static_cast<std::size_t>(v)] = 0.0;
    }
    add_pin_group(std::move(pins));
}

Vec3d ClothModel::pin_target(const MovingPins& pins, const Pose& pose, std::size_t k,
                             double t) const {
    if (pins.mesh_obstacle < 0) {
        return pose.apply(pins.rest_positions[k]);
    }
    const MovingMeshObstacle& body = m_mesh_obstacles[static_cast<std::size_t>(pins.mesh_obstacle)];
    const geometry::Triangle& tri =
        body.mesh->mesh().triangles[static_cast<std::size_t>(pins.triangles[k])];
    std::array<Vec3d, 3> corners;
    for (std::size_t c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(tri[c]);
        corners[c] =
            body.animation ? body.animation->position_at(v, t) : body.mesh->mesh().positions[v];
    }
    const Vec3d& b = pins.barycentric[k];
    const Vec3d x = corners[0] * b.x + corners[1] * b.y + corners[2] * b.z +
                    from_triangle_frame(corners, pins.offsets[k]);
    return body.state.motion.pose(t).apply(x);
}

void ClothModel::set_air(const Air& air) {
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

void ClothModel::set_velocities(std::span<const Vec3d> velocities) {
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

void ClothModel::set_positions(std::span<const Vec3d> positions) {
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
    ++m_num_position_resets;
}

UntangleResult ClothModel::untangle(const UntangleOptions& options) {
    UntangleOptions with_obstacles = options;
    if (!with_obstacles.obstacle_distance && has_obstacles()) {
        // Where the obstacles are now (before the first step: where their motion has them at
        // time 0).
        with_obstacles.obstacle_distance = [this](const Vec3d& x) {
            return nearest_obstacle(x).distance;
        };
    }
    const UntangleResult result =
        cloth::untangle(m_positions, m_triangles, m_inverse_masses, with_obstacles);
    if (result.iterations > 0) {
        ++m_num_position_resets;
    }
    return result;
}

void ClothModel::grab(std::int32_t vertex, const Vec3d& target) {
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

void ClothModel::release_grab() {
    if (m_grab) {
        m_inverse_masses[static_cast<std::size_t>(m_grab->vertex)] = m_grab->inverse_mass;
        m_grab.reset();
    }
}

SurfaceDistance ClothModel::nearest_obstacle(const Vec3d& x) const {
    SurfaceDistance nearest{std::numeric_limits<double>::infinity(), {0.0, 0.0, 0.0}};
    for (const MovingObstacle& obstacle : m_obstacles) {
        const SurfaceDistance s = surface_distance(obstacle.current, x);
        if (s.distance < nearest.distance) {
            nearest = s;
        }
    }
    for (const MovingMeshObstacle& mesh : m_mesh_obstacles) {
        const Pose& pose = mesh.state.pose;
        const std::optional<SurfaceDistance> s =
            mesh.mesh->surface_distance(pose.apply_inverse(x), norm(mesh.mesh->bounds().extent()));
        if (s && s->distance < nearest.distance) {
            nearest = {s->distance, pose.rotation.apply(s->normal)};
        }
    }
    return nearest;
}

ClothModel::Penetration ClothModel::obstacle_penetration() const {
    Penetration penetration;
    if (!has_obstacles()) {
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

void ClothModel::begin_step(double dt) {
    m_step_start = m_time;
    m_step_dt = dt;
    if (m_grab) {
        m_grab->start = m_positions[static_cast<std::size_t>(m_grab->vertex)];
    }
}

void ClothModel::move_pins(double t, double max_step) {
    for (const MovingPins& pins : m_moving_pins) {
        const Pose pose = pins.motion.pose(t);
        parallel_for(static_cast<std::int64_t>(pins.vertices.size()), [&](std::int64_t k) {
            Vec3d& x =
                m_positions[static_cast<std::size_t>(pins.vertices[static_cast<std::size_t>(k)])];
            const Vec3d target = pin_target(pins, pose, static_cast<std::size_t>(k), t);
            const Vec3d to_target = target - x;
            const double distance = norm(to_target);
            // Within max_step (up to rounding: a relative 1e-9), the target itself, so that a
            // chase ends on it rather than a rounding error short of it.
            x = distance > max_step * (1.0 + 1e-9) ? x + to_target * (max_step / distance) : target;
        });
    }
    if (m_grab) {
        const double f = std::min(1.0, (t - m_step_start) / m_step_dt);
        m_positions[static_cast<std::size_t>(m_grab->vertex)] =
            m_grab->start + (m_grab->target - m_grab->start) * f;
    }
}

ClothModel::PinLag ClothModel::pin_lag() const {
    PinLag lag;
    for (const MovingPins& pins : m_moving_pins) {
        const Pose pose = pins.motion.pose(m_time);
        for (std::size_t k = 0; k < pins.vertices.size(); ++k) {
            if (m_grab && m_grab->vertex == pins.vertices[k]) {
                continue;
            }
            const double distance = norm(pin_target(pins, pose, k, m_time) -
                                         m_positions[static_cast<std::size_t>(pins.vertices[k])]);
            if (distance > 0.0) {
                ++lag.vertices;
                lag.max = std::max(lag.max, distance);
            }
        }
    }
    return lag;
}

void ClothModel::move_obstacles(double t) {
    double step = 0.0;
    for (MovingObstacle& obstacle : m_obstacles) {
        if (!obstacle.state.motion.is_static()) {
            obstacle.state.advance(t);
            obstacle.previous = obstacle.current;
            obstacle.current = placed(obstacle.rest, obstacle.state.pose);
            step = std::max(step, obstacle_move(obstacle.previous, obstacle.current));
        }
    }
    for (MovingMeshObstacle& mesh : m_mesh_obstacles) {
        mesh.state.advance(t);
        if (mesh.animation) {
            mesh.animation->positions_at(t, mesh.next_positions);
            mesh.deforming->move_to(mesh.next_positions);
        }
        if (mesh.animation || !mesh.state.motion.is_static()) {
            const std::span<const Vec3d> now = mesh.mesh->mesh().positions;
            const std::span<const Vec3d> before = mesh.mesh->previous_positions();
            const MotionState& s = mesh.state;
            step = std::max(
                step, parallel_reduce(
                          static_cast<std::int64_t>(now.size()), 0.0,
                          [&](std::int64_t begin, std::int64_t end) {
                              double largest = 0.0;
                              for (std::int64_t v = begin; v < end; ++v) {
                                  const auto i = static_cast<std::size_t>(v);
                                  largest =
                                      std::max(largest, norm(s.pose.apply(now[i]) -
                                                             s.previous_pose.apply(before[i])));
                              }
                              return largest;
                          },
                          [](double a, double b) { return std::max(a, b); }, VERTEX_GRAIN));
        }
    }
    m_obstacle_step = step;
}

void ClothModel::apply_air(double h, double t) {
    if (!m_air.is_active()) {
        return;
    }
    // Per triangle (detail/air_kernels.hpp), then per vertex over its incident triangles in
    // ascending order: no concurrent writes, the same sums for any number of threads.
    const detail::AirTerms terms = detail::air_terms(m_air, m_material.areal_density, h, t);
    parallel_for_chunks(static_cast<std::int64_t>(m_triangles.size()), VERTEX_GRAIN,
                        [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                            detail::triangle_air_forces(m_positions.data(), m_velocities.data(),
                                                        m_triangles.data(), begin, end, terms,
                                                        m_triangle_forces.data());
                        });
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

void ClothModel::save_state(ByteWriter& out) const {
    out.put_vector(m_positions);
    out.put_vector(m_velocities);
    out.put_vector(m_inverse_masses);
    out.put(m_time);
    out.put(m_step_start);
    out.put(m_step_dt);
    out.put(m_num_position_resets);
    out.put_vector(m_triangle_forces);
    out.put(m_grab.has_value());
    if (m_grab) {
        out.put(*m_grab);
    }
    out.put(static_cast<std::uint64_t>(m_obstacles.size()));
    for (const MovingObstacle& o : m_obstacles) {
        out.put(o.state.pose);
        out.put(o.state.previous_pose);
        out.put(o.current);
        out.put(o.previous);
    }
    out.put(static_cast<std::uint64_t>(m_mesh_obstacles.size()));
    for (const MovingMeshObstacle& o : m_mesh_obstacles) {
        out.put(o.state.pose);
        out.put(o.state.previous_pose);
        if (o.animation) {  // where the deforming mesh is, and was at the last substep's start
            const std::span<const Vec3d> previous = o.mesh->previous_positions();
            out.put_vector(std::vector<Vec3d>(previous.begin(), previous.end()));
            out.put_vector(o.mesh->mesh().positions);
        }
    }
}

void ClothModel::load_state(ByteReader& in) {
    const auto n = static_cast<std::int64_t>(m_positions.size());
    in.get_vector("model.positions", m_positions, n);
    in.get_vector("model.velocities", m_velocities, n);
    in.get_vector("model.inverse_masses", m_inverse_masses, n);
    m_time = in.get<double>("model.time");
    m_step_start = in.get<double>("model.step_start");
    m_step_dt = in.get<double>("model.step_dt");
    m_num_position_resets = in.get<std::int64_t>("model.num_position_resets");
    in.get_vector("model.triangle_forces", m_triangle_forces,
                  static_cast<std::int64_t>(m_triangle_forces.size()));
    m_grab.reset();
    if (in.get_bool("model.has_grab")) {
        m_grab = in.get<Grab>("model.grab");
        if (m_grab->vertex < 0 || m_grab->vertex >= n) {
            throw InvalidInput(
                fmt::format("{}: model.grab: vertex {} of {}", in.source(), m_grab->vertex, n));
        }
    }
    const auto num_obstacles = in.get<std::uint64_t>("model.num_obstacles");
    if (num_obstacles != m_obstacles.size()) {
        throw InvalidInput(fmt::format("{}: model: {} obstacles in the state, {} in the scene",
                                       in.source(), num_obstacles, m_obstacles.size()));
    }
    for (MovingObstacle& o : m_obstacles) {
        o.state.pose = in.get<Pose>("model.obstacle.pose");
        o.state.previous_pose = in.get<Pose>("model.obstacle.previous_pose");
        const auto current = in.get<Obstacle>("model.obstacle.current");
        const auto previous = in.get<Obstacle>("model.obstacle.previous");
        if (current.index() != o.rest.index() || previous.index() != o.rest.index()) {
            throw InvalidInput(
                fmt::format("{}: model: an obstacle of another shape in the state", in.source()));
        }
        o.current = current;
        o.previous = previous;
    }
    const auto num_mesh_obstacles = in.get<std::uint64_t>("model.num_mesh_obstacles");
    if (num_mesh_obstacles != m_mesh_obstacles.size()) {
        throw InvalidInput(fmt::format("{}: model: {} mesh obstacles in the state, {} in the scene",
                                       in.source(), num_mesh_obstacles, m_mesh_obstacles.size()));
    }
    for (MovingMeshObstacle& o : m_mesh_obstacles) {
        o.state.pose = in.get<Pose>("model.mesh_obstacle.pose");
        o.state.previous_pose = in.get<Pose>("model.mesh_obstacle.previous_pose");
        if (o.animation) {
            const auto n_mesh = static_cast<std::int64_t>(o.next_positions.size());
            std::vector<Vec3d> previous;
            std::vector<Vec3d> current;
            in.get_vector("model.mesh_obstacle.previous_positions", previous, n_mesh);
            in.get_vector("model.mesh_obstacle.positions", current, n_mesh);
            o.deforming->set_positions(previous);
            o.deforming->move_to(current);
        }
    }
}

}  // namespace pliant::cloth
