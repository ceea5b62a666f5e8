#include "pliant/cloth/mesh_contact.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "pliant/core/parallel.hpp"

namespace pliant::cloth {
namespace {

Vec3d barycentric_point(std::span<const Vec3d> positions, const geometry::Triangle& tri,
                        const Vec3d& b) {
    return positions[static_cast<std::size_t>(tri[0])] * b.x +
           positions[static_cast<std::size_t>(tri[1])] * b.y +
           positions[static_cast<std::size_t>(tri[2])] * b.z;
}

}  // namespace

MeshContact resolve_mesh_contact(const MovingMeshObstacle& obstacle, Vec3d& x, const Vec3d& start,
                                 double thickness, double h, double max_settle, double max_push,
                                 double extra_depth) {
    MeshContact contact;
    const MeshObstacle& mesh = *obstacle.mesh;
    const Pose& pose = obstacle.state.pose;
    const Pose& previous_pose = obstacle.state.previous_pose;
    const std::span<const Vec3d> now = mesh.mesh().positions;
    const std::span<const Vec3d> before = mesh.previous_positions();
    const Vec3d x_rest0 = pose.apply_inverse(x);
    const Vec3d start_rest = previous_pose.apply_inverse(start);
    Vec3d x_rest = x_rest0;
    std::int32_t triangle = -1;
    Vec3d barycentric{};
    Vec3d normal{};

    // Step 1: swept contact.
    if (const std::optional<MeshObstacle::SweptHit> hit = mesh.sweep(start_rest, x_rest)) {
        const Vec3d n = mesh.face_normals()[static_cast<std::size_t>(hit->triangle)];
        if (squared_norm(n) > 0.0) {
            const geometry::Triangle& tri =
                mesh.mesh().triangles[static_cast<std::size_t>(hit->triangle)];
            x_rest = barycentric_point(now, tri, hit->barycentric) + n * thickness;
            triangle = hit->triangle;
            barycentric = hit->barycentric;
            normal = n;
            contact.swept = true;
        }
    }

    // Step 2: push out of the surface at the substep's end.
    const Vec3d rigid_move = obstacle.state.surface_displacement(x);
    const double max_depth = norm(x_rest0 - start_rest) + norm(rigid_move) +
                             mesh.max_vertex_step() + 2.0 * thickness + extra_depth;
    if (const std::optional<MeshObstacle::SurfacePoint> point =
            mesh.surface_point(x_rest, std::max(thickness, max_depth))) {
        const double depth = thickness - point->surface.distance;
        if (depth > 0.0 && point->surface.distance >= -max_depth) {
            x_rest += point->surface.normal * depth;
            triangle = point->triangle;
            barycentric = point->barycentric;
            normal = point->surface.normal;
        }
    }
    if (triangle < 0) {
        return contact;
    }

    // Step 3: bounds on the correction.
    const Vec3d correction = x_rest - x_rest0;
    const double length = norm(correction);
    if (!(length > 0.0)) {
        return contact;
    }
    const geometry::Triangle& tri = mesh.mesh().triangles[static_cast<std::size_t>(triangle)];
    const Vec3d p_start = barycentric_point(before, tri, barycentric);
    const double was_in = thickness - dot(start_rest - p_start, normal);
    double settled = std::clamp(was_in, 0.0, length);
    const double excess_settle = settled > max_settle ? settled - max_settle : 0.0;
    settled -= excess_settle;
    const double allowed = norm(x_rest0 - start_rest) + thickness + max_push;
    const double excess_push = std::max(0.0, length - excess_settle - settled - allowed);
    const double excess = excess_settle + excess_push;
    if (excess > 0.0) {
        x_rest -= correction * (excess / length);
    }
    x = pose.apply(x_rest);
    contact.depth = length - excess;
    contact.settled = settled;
    contact.normal = pose.rotation.apply(normal);
    contact.lag = excess_push;
    const Vec3d p_end = barycentric_point(now, tri, barycentric);
    contact.surface_velocity = (pose.apply(p_end) - previous_pose.apply(p_start)) * (1.0 / h);
    return contact;
}

namespace {

constexpr std::int64_t FEATURE_GRAIN = 256;

// Step 2 of the edge and face passes: each feature's corrections (of its N corners, in
// scratch.corrections) averaged per free vertex, summed in feature order; returns the features
// with a correction.
template <std::size_t N>
std::int64_t apply_averaged(std::span<Vec3d> positions, std::span<const double> inverse_masses,
                            std::span<const std::array<std::int32_t, N>> features,
                            MeshFeatureContactScratch& scratch) {
    scratch.sums.assign(positions.size(), Vec3d{});
    scratch.counts.assign(positions.size(), 0);
    std::int64_t corrected = 0;
    for (std::size_t k = 0; k < features.size(); ++k) {
        if (scratch.has_correction[k] == 0) {
            continue;
        }
        ++corrected;
        for (std::size_t corner = 0; corner < N; ++corner) {
            const auto v = static_cast<std::size_t>(features[k][corner]);
            if (inverse_masses[v] > 0.0) {
                scratch.sums[v] += scratch.corrections[k][corner];
                ++scratch.counts[v];
            }
        }
    }
    if (corrected == 0) {
        return 0;
    }
    parallel_for(
        static_cast<std::int64_t>(positions.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            if (scratch.counts[v] > 0) {
                positions[v] += scratch.sums[v] * (1.0 / scratch.counts[v]);
            }
        },
        FEATURE_GRAIN);
    return corrected;
}

}  // namespace

std::int64_t resolve_mesh_edge_contacts(const MovingMeshObstacle& obstacle,
                                        std::span<Vec3d> positions, std::span<const Vec3d> start,
                                        std::span<const Vec3d> before_contact,
                                        std::span<const double> inverse_masses,
                                        std::span<const geometry::Edge> edges, double thickness,
                                        double max_push, MeshFeatureContactScratch& scratch) {
    const MeshObstacle& mesh = *obstacle.mesh;
    const Pose& pose = obstacle.state.pose;
    const Pose& previous_pose = obstacle.state.previous_pose;
    const std::span<const Vec3d> now = mesh.mesh().positions;
    scratch.corrections.resize(edges.size());
    scratch.has_correction.assign(edges.size(), 0);

    // Step 1: per cloth edge, its correction.
    parallel_for(
        static_cast<std::int64_t>(edges.size()),
        [&](std::int64_t i) {
            const auto k = static_cast<std::size_t>(i);
            const auto a = static_cast<std::size_t>(edges[k][0]);
            const auto b = static_cast<std::size_t>(edges[k][1]);
            const double wa = inverse_masses[a];
            const double wb = inverse_masses[b];
            if (!(wa > 0.0) && !(wb > 0.0)) {
                return;
            }
            const Vec3d pa = pose.apply_inverse(positions[a]);
            const Vec3d pb = pose.apply_inverse(positions[b]);
            const Vec3d pa0 = previous_pose.apply_inverse(start[a]);
            const Vec3d pb0 = previous_pose.apply_inverse(start[b]);
            const std::optional<MeshObstacle::EdgeHit> hit = mesh.sweep_edge(pa0, pb0, pa, pb);
            if (!hit) {
                return;
            }
            const geometry::Edge& edge = mesh.edges()[static_cast<std::size_t>(hit->edge)];
            const Vec3d n_sum = mesh.edge_normals()[static_cast<std::size_t>(hit->edge)];
            const double n_length = norm(n_sum);
            if (!(n_length > 0.0)) {
                return;
            }
            const Vec3d n = n_sum * (1.0 / n_length);
            const Vec3d o = now[static_cast<std::size_t>(edge[0])] * (1.0 - hit->t) +
                            now[static_cast<std::size_t>(edge[1])] * hit->t;
            const double s = hit->s;
            const double c = dot(pa * (1.0 - s) + pb * s - o, n) - thickness;
            const double denominator = wa * (1.0 - s) * (1.0 - s) + wb * s * s;
            if (!(c < 0.0) || !(denominator > 0.0)) {
                return;
            }
            // As for vertices: the point's whole correction in this substep (the vertex pass's
            // and this one) at most its own motion, the thickness and max_push.
            const auto point = [s](const Vec3d& xa, const Vec3d& xb) {
                return xa * (1.0 - s) + xb * s;
            };
            const Vec3d free_move =
                point(before_contact[a], before_contact[b]) - point(start[a], start[b]);
            const Vec3d pushed =
                point(positions[a], positions[b]) - point(before_contact[a], before_contact[b]);
            const double allowed = norm(free_move) + thickness + max_push - norm(pushed);
            if (!(allowed > 0.0)) {
                return;
            }
            const double lambda = std::min(-c, allowed) / denominator;
            const Vec3d world_n = pose.rotation.apply(n);
            scratch.corrections[k] = {world_n * (wa * (1.0 - s) * lambda),
                                      world_n * (wb * s * lambda), Vec3d{}};
            scratch.has_correction[k] = 1;
        },
        FEATURE_GRAIN);

    // Step 2: averaged per vertex, summed in edge order.
    return apply_averaged<2>(positions, inverse_masses, edges, scratch);
}

std::int64_t resolve_mesh_face_contacts(const MovingMeshObstacle& obstacle,
                                        std::span<Vec3d> positions, std::span<const Vec3d> start,
                                        std::span<const Vec3d> before_contact,
                                        std::span<const double> inverse_masses,
                                        std::span<const geometry::Triangle> triangles,
                                        double thickness, double max_push,
                                        MeshFeatureContactScratch& scratch) {
    const MeshObstacle& mesh = *obstacle.mesh;
    const Pose& pose = obstacle.state.pose;
    const Pose& previous_pose = obstacle.state.previous_pose;
    const std::span<const Vec3d> now = mesh.mesh().positions;
    scratch.corrections.resize(triangles.size());
    scratch.has_correction.assign(triangles.size(), 0);

    // Step 1: per cloth triangle, its correction.
    parallel_for(
        static_cast<std::int64_t>(triangles.size()),
        [&](std::int64_t i) {
            const auto k = static_cast<std::size_t>(i);
            std::array<std::size_t, 3> v{};
            std::array<double, 3> w{};
            bool free = false;
            for (std::size_t j = 0; j < 3; ++j) {
                v[j] = static_cast<std::size_t>(triangles[k][j]);
                w[j] = inverse_masses[v[j]];
                free = free || w[j] > 0.0;
            }
            if (!free) {
                return;
            }
            std::array<Vec3d, 3> x{};
            std::array<Vec3d, 3> x0{};
            for (std::size_t j = 0; j < 3; ++j) {
                x[j] = pose.apply_inverse(positions[v[j]]);
                x0[j] = previous_pose.apply_inverse(start[v[j]]);
            }
            const std::optional<MeshObstacle::VertexHit> hit =
                mesh.sweep_triangle(x0[0], x0[1], x0[2], x[0], x[1], x[2]);
            if (!hit) {
                return;
            }
            const auto vertex = static_cast<std::size_t>(hit->vertex);
            const Vec3d n_sum = mesh.vertex_normals()[vertex];
            const double n_length = norm(n_sum);
            if (!(n_length > 0.0)) {
                return;
            }
            const Vec3d n = n_sum * (1.0 / n_length);
            const std::array<double, 3> b = {hit->barycentric.x, hit->barycentric.y,
                                             hit->barycentric.z};
            const auto point = [&b](const auto& corner) {
                return corner(0) * b[0] + corner(1) * b[1] + corner(2) * b[2];
            };
            const double c =
                dot(point([&](std::size_t j) { return x[j]; }) - now[vertex], n) - thickness;
            const double denominator = w[0] * b[0] * b[0] + w[1] * b[1] * b[1] + w[2] * b[2] * b[2];
            if (!(c < 0.0) || !(denominator > 0.0)) {
                return;
            }
            // As for edges: the point's whole correction in this substep at most its own motion,
            // the thickness and max_push.
            const Vec3d free_move = point([&](std::size_t j) { return before_contact[v[j]]; }) -
                                    point([&](std::size_t j) { return start[v[j]]; });
            const Vec3d pushed = point([&](std::size_t j) { return positions[v[j]]; }) -
                                 point([&](std::size_t j) { return before_contact[v[j]]; });
            const double allowed = norm(free_move) + thickness + max_push - norm(pushed);
            if (!(allowed > 0.0)) {
                return;
            }
            const double lambda = std::min(-c, allowed) / denominator;
            const Vec3d world_n = pose.rotation.apply(n);
            for (std::size_t j = 0; j < 3; ++j) {
                scratch.corrections[k][j] = world_n * (w[j] * b[j] * lambda);
            }
            scratch.has_correction[k] = 1;
        },
        FEATURE_GRAIN);

    // Step 2: averaged per vertex, summed in triangle order.
    return apply_averaged<3>(positions, inverse_masses, triangles, scratch);
}

}  // namespace pliant::cloth
