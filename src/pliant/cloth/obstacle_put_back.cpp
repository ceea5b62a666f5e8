#include "pliant/cloth/obstacle_put_back.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <optional>

#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/obstacle_intersections.hpp"
#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t TRIANGLE_GRAIN = 256;

// Where each obstacle was when a carry starts: its pose, and a deforming mesh's vertices with
// the radius within which a point's nearest surface point is looked up (its largest vertex move
// since, plus the thickness).
struct CarryStart {
    const Pose* pose;
    std::span<const Vec3d> positions;  // a deforming mesh's vertices then (else empty)
    double radius;
};

// Where the motion of obstacle `met` (obstacle_met_by's index) since `from` carries the point
// `start`.
Vec3d carried(const ClothModel& model, std::int32_t met, const CarryStart& from,
              const Vec3d& start) {
    const std::span<const MovingMeshObstacle> meshes = model.mesh_obstacles();
    const auto k = static_cast<std::size_t>(met);
    if (k >= meshes.size()) {
        const MotionState& state = model.obstacles()[k - meshes.size()].state;
        return state.pose.apply(from.pose->apply_inverse(start));
    }
    const MovingMeshObstacle& obstacle = meshes[k];
    Vec3d x = from.pose->apply_inverse(start);
    if (obstacle.animation && !from.positions.empty()) {
        const MeshObstacle& mesh = *obstacle.mesh;
        if (const std::optional<MeshObstacle::SurfacePoint> point =
                mesh.surface_point(x, from.radius)) {
            const geometry::Triangle& tri =
                mesh.mesh().triangles[static_cast<std::size_t>(point->triangle)];
            const std::span<const Vec3d> now = mesh.mesh().positions;
            const Vec3d& b = point->barycentric;
            const auto moved = [&](std::size_t j) {
                const auto v = static_cast<std::size_t>(tri[j]);
                return now[v] - from.positions[v];
            };
            x += moved(0) * b.x + moved(1) * b.y + moved(2) * b.z;
        }
    }
    return obstacle.state.pose.apply(x);
}

// Per obstacle (obstacle_met_by's indices), where a carry starts: the previous placement, or
// `since`.
void carry_starts(const ClothModel& model, const ObstaclePlacements* since,
                  std::vector<CarryStart>& out) {
    const std::span<const MovingMeshObstacle> meshes = model.mesh_obstacles();
    const std::span<const MovingObstacle> analytic = model.obstacles();
    const double thickness = model.material().thickness;
    if (since != nullptr) {
        PLIANT_CHECK_EQ(since->mesh_poses.size(), meshes.size());
        PLIANT_CHECK_EQ(since->poses.size(), analytic.size());
    }
    out.clear();
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const MovingMeshObstacle& obstacle = meshes[k];
        if (since == nullptr) {
            out.push_back({&obstacle.state.previous_pose, obstacle.mesh->previous_positions(),
                           obstacle.mesh->max_vertex_step() + thickness});
            continue;
        }
        const std::span<const Vec3d> then(since->mesh_positions[k]);
        double step = 0.0;
        if (obstacle.animation && then.size() == obstacle.mesh->mesh().positions.size()) {
            const std::span<const Vec3d> now = obstacle.mesh->mesh().positions;
            for (std::size_t v = 0; v < then.size(); ++v) {
                step = std::max(step, norm(now[v] - then[v]));
            }
        }
        out.push_back({&since->mesh_poses[k], then, step + thickness});
    }
    for (std::size_t k = 0; k < analytic.size(); ++k) {
        out.push_back(
            {since != nullptr ? &since->poses[k] : &analytic[k].state.previous_pose, {}, 0.0});
    }
}

// Whether x is inside a closed mesh obstacle (behind its surface; meets_triangle sees only a
// triangle through the surface, not one wholly inside).
bool inside_a_closed_mesh(const ClothModel& model, const Vec3d& x) {
    for (const MovingMeshObstacle& mesh : model.mesh_obstacles()) {
        if (mesh.mesh->is_closed()) {
            const std::optional<SurfaceDistance> surface = mesh.mesh->surface_distance(
                mesh.state.pose.apply_inverse(x), std::numeric_limits<double>::infinity());
            if (surface && surface->distance < 0.0) {
                return true;
            }
        }
    }
    return false;
}

}  // namespace

void ObstaclePlacements::capture(const ClothModel& model) {
    const std::span<const MovingMeshObstacle> meshes = model.mesh_obstacles();
    mesh_poses.resize(meshes.size());
    mesh_positions.resize(meshes.size());
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        mesh_poses[k] = meshes[k].state.pose;
        if (meshes[k].animation) {
            const std::span<const Vec3d> now = meshes[k].mesh->mesh().positions;
            mesh_positions[k].assign(now.begin(), now.end());
        } else {
            mesh_positions[k].clear();
        }
    }
    poses.clear();
    for (const MovingObstacle& obstacle : model.obstacles()) {
        poses.push_back(obstacle.state.pose);
    }
}

void ObstaclePutBack::seed(std::span<const Vec3d> positions, std::span<const Vec3d> changed_from) {
    m_seeded.resize(positions.size(), 0);
    for (std::size_t v = 0; v < positions.size(); ++v) {
        if (!(positions[v] == changed_from[v])) {
            m_seeded[v] = 1;
        }
    }
}

std::int64_t ObstaclePutBack::run(ClothModel& model, std::span<const Vec3d> reference,
                                  Fallback fallback, double max_carry,
                                  const ObstaclePlacements* since) {
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const std::span<const geometry::Triangle> triangles = model.triangles();
    const geometry::MeshTopology& topology = model.topology();
    m_triangle_marks.resize(triangles.size(), 0);
    m_vertex_moved.resize(positions.size(), 0);
    m_moved.clear();
    m_marked.clear();
    m_seeds.clear();
    m_stuck.clear();
    const auto add_triangles_of = [&](std::int32_t v) {
        for (const std::int32_t t : topology.triangles_of_vertex(v)) {
            const auto k = static_cast<std::size_t>(t);
            if (m_triangle_marks[k] == 0) {
                m_triangle_marks[k] = 1;
                m_seeds.push_back(t);
            }
        }
    };
    m_seeded.resize(positions.size(), 0);
    for (std::size_t v = 0; v < positions.size(); ++v) {
        if (m_seeded[v] != 0) {
            m_seeded[v] = 0;
            add_triangles_of(static_cast<std::int32_t>(v));
        }
    }
    std::vector<CarryStart> carry_from;  // per obstacle, with Fallback::carried
    if (fallback == Fallback::carried && !m_seeds.empty()) {
        carry_starts(model, since, carry_from);
    }
    std::array<Vec3d, 3> corners{};
    for (std::int32_t round = 1; !m_seeds.empty(); ++round) {
        std::sort(m_seeds.begin(), m_seeds.end());
        m_met.assign(m_seeds.size(), -1);
        parallel_for(
            static_cast<std::int64_t>(m_seeds.size()),
            [&](std::int64_t i) {
                const auto k = static_cast<std::size_t>(i);
                const geometry::Triangle& tri = triangles[static_cast<std::size_t>(m_seeds[k])];
                m_met[k] = obstacle_met_by(model, positions[static_cast<std::size_t>(tri[0])],
                                           positions[static_cast<std::size_t>(tri[1])],
                                           positions[static_cast<std::size_t>(tri[2])]);
            },
            TRIANGLE_GRAIN);
        for (const std::int32_t t : m_seeds) {
            m_triangle_marks[static_cast<std::size_t>(t)] = 0;
        }
        const std::size_t round_start = m_moved.size();
        for (std::size_t i = 0; i < m_seeds.size(); ++i) {
            if (m_met[i] < 0) {
                continue;
            }
            const geometry::Triangle& tri = triangles[static_cast<std::size_t>(m_seeds[i])];
            const auto at = [&](std::size_t j) -> const Vec3d& {
                return positions[static_cast<std::size_t>(tri[j])];
            };
            // A triangle whose vertex an earlier one of this round moved may be clear now (the
            // moves of earlier rounds are in m_met already).
            const bool touched = m_vertex_moved[static_cast<std::size_t>(tri[0])] == round ||
                                 m_vertex_moved[static_cast<std::size_t>(tri[1])] == round ||
                                 m_vertex_moved[static_cast<std::size_t>(tri[2])] == round;
            if (touched && !triangle_meets_obstacles(model, at(0), at(1), at(2))) {
                continue;
            }
            // The triangle at its fallback: free vertices not yet moved go there, the rest stay.
            std::array<bool, 3> moves{};
            bool usable = true;
            for (std::size_t j = 0; j < 3; ++j) {
                const auto v = static_cast<std::size_t>(tri[j]);
                moves[j] = inverse_masses[v] > 0.0 && m_vertex_moved[v] == 0;
                corners[j] =
                    !moves[j] ? positions[v]
                    : fallback == Fallback::carried
                        ? carried(model, m_met[i], carry_from[static_cast<std::size_t>(m_met[i])],
                                  reference[v])
                        : reference[v];
                if (moves[j]) {
                    usable = usable && norm(corners[j] - reference[v]) <= max_carry &&
                             !inside_a_closed_mesh(model, corners[j]);
                }
            }
            if (!usable || triangle_meets_obstacles(model, corners[0], corners[1], corners[2])) {
                m_stuck.push_back(m_seeds[i]);
                continue;
            }
            for (std::size_t j = 0; j < 3; ++j) {
                if (moves[j]) {
                    const auto v = static_cast<std::size_t>(tri[j]);
                    m_vertex_moved[v] = round;
                    m_marked.push_back(tri[j]);
                    if (!(positions[v] == corners[j])) {
                        positions[v] = corners[j];
                        m_moved.push_back(tri[j]);
                    }
                }
            }
        }
        m_seeds.clear();
        for (std::size_t i = round_start; i < m_moved.size(); ++i) {
            add_triangles_of(m_moved[i]);
        }
    }
    for (const std::int32_t v : m_marked) {
        m_vertex_moved[static_cast<std::size_t>(v)] = 0;
    }
    return static_cast<std::int64_t>(m_moved.size());
}

}  // namespace pliant::cloth
