#include "pliant/cloth/mesh_obstacle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "pliant/bvh/traversal.hpp"
#include "pliant/collision/ccd.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/triangle_intersection.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t GEOMETRY_GRAIN = 1 << 12;
// Boxes a swept-contact query evaluates at most per triangle (collision/ccd.hpp): past it the
// query reports a conservative hit, which only places the point on the surface.
constexpr int SWEEP_MAX_ITERATIONS = 20'000;

std::size_t index(std::int32_t i) {
    return static_cast<std::size_t>(i);
}

// Row r of a CSR table (offsets of #rows + 1, values).
std::span<const std::int32_t> csr_row(std::span<const std::int32_t> offsets,
                                      std::span<const std::int32_t> values, std::size_t r) {
    return values.subspan(index(offsets[r]), index(offsets[r + 1] - offsets[r]));
}

// The direction in which two features meeting in a sweep pass through each other: `common`, the
// cross product of their directions u × w (a cloth triangle's normal; two edges' common normal),
// turned to the side of the surface's outward `pseudo_normal` at the meeting. The pseudo-normal
// itself where `common` does not decide a side: shorter than 1e-6 |u| |w| (parallel edges, a
// degenerate triangle: its direction is rounding) or within 0.06° of perpendicular to the
// pseudo-normal (features that meet edge-on).
Vec3d crossing_normal(const Vec3d& u, const Vec3d& w, const Vec3d& pseudo_normal) {
    const Vec3d common = cross(u, w);
    const double length = norm(common);
    const double along = dot(common, pseudo_normal);
    if (!(length > 1e-6 * norm(u) * norm(w)) ||
        !(std::abs(along) > 1e-3 * length * norm(pseudo_normal))) {
        return pseudo_normal;
    }
    return along > 0.0 ? common : -common;
}

}  // namespace

MeshObstacle::MeshObstacle(geometry::TriangleMeshD mesh) : m_mesh(std::move(mesh)) {
    if (m_mesh.triangles.empty()) {
        throw InvalidInput(fmt::format(
            "cloth::MeshObstacle: mesh has no triangles ({} vertices); expected at least one",
            m_mesh.positions.size()));
    }
    geometry::validate_mesh(m_mesh, "cloth::MeshObstacle: mesh");
    geometry::MeshTopology topology =
        geometry::build_topology(m_mesh.triangles, m_mesh.positions.size());
    // Closed and consistently wound: each edge in exactly two triangles, once in each direction.
    const auto runs_forward = [&](std::int32_t t, const geometry::Edge& edge) {
        const geometry::Triangle& tri = m_mesh.triangles[static_cast<std::size_t>(t)];
        for (std::size_t k = 0; k < 3; ++k) {
            if (tri[k] == edge[0]) {
                return tri[(k + 1) % 3] == edge[1];
            }
        }
        return false;
    };
    m_closed = true;
    for (std::size_t e = 0; e < topology.edges.size() && m_closed; ++e) {
        const std::int32_t begin = topology.edge_triangle_offsets[e];
        const std::int32_t end = topology.edge_triangle_offsets[e + 1];
        m_closed = end - begin == 2 &&
                   runs_forward(topology.edge_triangles[static_cast<std::size_t>(begin)],
                                topology.edges[e]) !=
                       runs_forward(topology.edge_triangles[static_cast<std::size_t>(begin) + 1],
                                    topology.edges[e]);
    }
    m_edges = std::move(topology.edges);
    m_triangle_edges = std::move(topology.triangle_edges);
    m_edge_triangle_offsets = std::move(topology.edge_triangle_offsets);
    m_edge_triangles = std::move(topology.edge_triangles);
    m_vertex_triangle_offsets = std::move(topology.vertex_triangle_offsets);
    m_vertex_triangles = std::move(topology.vertex_triangles);
    m_face_normals.resize(m_mesh.triangles.size());
    m_corner_angles.resize(m_mesh.triangles.size());
    m_boxes.resize(m_mesh.triangles.size());
    m_edge_normals.resize(m_edges.size());
    m_vertex_normals.resize(m_mesh.positions.size());
    update_geometry();
    m_tree.build(m_boxes);
    m_leaf_corners.resize(m_mesh.triangles.size());
    // The vertices' own LBVH (sweep_triangle), over their paths over the last step.
    m_vertex_boxes.resize(m_mesh.positions.size());
    for (std::size_t v = 0; v < m_mesh.positions.size(); ++v) {
        m_vertex_boxes[v] = outward_float(AABBd::of_point(m_mesh.positions[v]));
    }
    m_vertex_tree.build(m_vertex_boxes);
    m_vertex_paths.resize(m_mesh.positions.size());
    gather_leaves();
}

std::optional<double> MeshObstacle::enclosed_volume() const {
    if (!m_closed) {
        return std::nullopt;
    }
    double six_volume = 0.0;
    for (const geometry::Triangle& t : m_mesh.triangles) {
        const Vec3d& a = m_mesh.positions[static_cast<std::size_t>(t[0])];
        const Vec3d& b = m_mesh.positions[static_cast<std::size_t>(t[1])];
        const Vec3d& c = m_mesh.positions[static_cast<std::size_t>(t[2])];
        six_volume += dot(a, cross(b, c));
    }
    return six_volume / 6.0;
}

void MeshObstacle::set_positions(std::span<const Vec3d> positions) {
    if (positions.size() != m_mesh.positions.size()) {
        throw InvalidInput(fmt::format(
            "cloth::MeshObstacle::set_positions: positions.size() ({}) != the mesh's vertex count "
            "({})",
            positions.size(), m_mesh.positions.size()));
    }
    geometry::validate_positions(positions, "cloth::MeshObstacle::set_positions: positions");
    std::copy(positions.begin(), positions.end(), m_mesh.positions.begin());
    m_previous_positions.clear();
    m_max_vertex_step = 0.0;
    update_geometry();
    m_tree.refit(m_boxes);
    gather_leaves();
}

void MeshObstacle::move_to(std::span<const Vec3d> positions) {
    if (positions.size() != m_mesh.positions.size()) {
        throw InvalidInput(fmt::format(
            "cloth::MeshObstacle::move_to: positions.size() ({}) != the mesh's vertex count ({})",
            positions.size(), m_mesh.positions.size()));
    }
    geometry::validate_positions(positions, "cloth::MeshObstacle::move_to: positions");
    m_previous_positions.assign(m_mesh.positions.begin(), m_mesh.positions.end());
    std::copy(positions.begin(), positions.end(), m_mesh.positions.begin());
    update_geometry();
    // Each leaf box covers its triangle at both placements, hence (by convexity) its whole sweep.
    const std::span<const geometry::Triangle> triangles = m_mesh.triangles;
    parallel_for(
        static_cast<std::int64_t>(triangles.size()),
        [&](std::int64_t t) {
            const auto i = static_cast<std::size_t>(t);
            AABBd box;
            for (const std::int32_t v : triangles[i]) {
                box.extend(m_mesh.positions[index(v)]);
                box.extend(m_previous_positions[index(v)]);
            }
            m_boxes[i] = outward_float(box);
        },
        GEOMETRY_GRAIN);
    m_max_vertex_step = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), 0.0,
        [&](std::int64_t begin, std::int64_t end) {
            double largest = 0.0;
            for (std::int64_t v = begin; v < end; ++v) {
                const auto i = static_cast<std::size_t>(v);
                largest = std::max(largest, norm(m_mesh.positions[i] - m_previous_positions[i]));
            }
            return largest;
        },
        [](double a, double b) { return std::max(a, b); }, GEOMETRY_GRAIN);
    m_tree.refit(m_boxes);
    gather_leaves();
}

void MeshObstacle::gather_leaves() {
    // The vertices' paths: their boxes (the vertex tree refit) and, per leaf position, the
    // path's two ends.
    const std::span<const Vec3d> start = previous_positions();
    const std::span<const std::uint32_t> vertices = m_vertex_tree.primitives();
    parallel_for(static_cast<std::int64_t>(vertices.size()), [&](std::int64_t k) {
        const auto i = static_cast<std::size_t>(k);  // vertex i's box, leaf i's path
        AABBd path = AABBd::of_point(start[i]);
        path.extend(m_mesh.positions[i]);
        m_vertex_boxes[i] = outward_float(path);
        m_vertex_paths[i] = {start[vertices[i]], m_mesh.positions[vertices[i]]};
    });
    m_vertex_tree.refit(m_vertex_boxes);
    const std::span<const std::uint32_t> primitives = m_tree.primitives();
    parallel_for(
        static_cast<std::int64_t>(primitives.size()),
        [&](std::int64_t j) {
            const auto leaf = static_cast<std::size_t>(j);
            const geometry::Triangle& tri = m_mesh.triangles[primitives[leaf]];
            m_leaf_corners[leaf] = {m_mesh.positions[index(tri[0])],
                                    m_mesh.positions[index(tri[1])],
                                    m_mesh.positions[index(tri[2])]};
        },
        GEOMETRY_GRAIN);
}

// Three passes, each writing by index (deterministic for any number of threads): per triangle
// (unit normal, corner angles, box), per edge and per vertex (sums over incident triangles in
// ascending order).
void MeshObstacle::update_geometry() {
    const std::span<const Vec3d> positions = m_mesh.positions;
    const std::span<const geometry::Triangle> triangles = m_mesh.triangles;
    const auto num_triangles = static_cast<std::int64_t>(triangles.size());

    // Step 1: triangles.
    parallel_for(
        num_triangles,
        [&](std::int64_t t) {
            const auto i = static_cast<std::size_t>(t);
            const geometry::Triangle& tri = triangles[i];
            const Vec3d corners[3] = {positions[index(tri[0])], positions[index(tri[1])],
                                      positions[index(tri[2])]};
            const Vec3d n = cross(corners[1] - corners[0], corners[2] - corners[0]);
            const double length = norm(n);
            m_face_normals[i] = length > 0.0 ? n * (1.0 / length) : Vec3d{};
            for (int k = 0; k < 3; ++k) {
                const Vec3d e1 = corners[(k + 1) % 3] - corners[k];
                const Vec3d e2 = corners[(k + 2) % 3] - corners[k];
                m_corner_angles[i][static_cast<std::size_t>(k)] =
                    std::atan2(norm(cross(e1, e2)), dot(e1, e2));
            }
            AABBd box;
            for (const Vec3d& c : corners) {
                box.extend(c);
            }
            m_boxes[i] = outward_float(box);
        },
        GEOMETRY_GRAIN);

    // Step 2: edge pseudo-normals.
    parallel_for(
        static_cast<std::int64_t>(m_edge_normals.size()),
        [&](std::int64_t e) {
            const auto i = static_cast<std::size_t>(e);
            Vec3d sum{};
            for (std::int32_t k = m_edge_triangle_offsets[i]; k < m_edge_triangle_offsets[i + 1];
                 ++k) {
                sum += m_face_normals[index(m_edge_triangles[index(k)])];
            }
            m_edge_normals[i] = sum;
        },
        GEOMETRY_GRAIN);

    // Step 3: angle-weighted vertex pseudo-normals.
    parallel_for(
        static_cast<std::int64_t>(m_vertex_normals.size()),
        [&](std::int64_t v) {
            const auto i = static_cast<std::size_t>(v);
            Vec3d sum{};
            for (std::int32_t k = m_vertex_triangle_offsets[i];
                 k < m_vertex_triangle_offsets[i + 1]; ++k) {
                const std::int32_t t = m_vertex_triangles[index(k)];
                const geometry::Triangle& tri = triangles[index(t)];
                const int corner = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
                sum += m_face_normals[index(t)] *
                       m_corner_angles[index(t)][static_cast<std::size_t>(corner)];
            }
            m_vertex_normals[i] = sum;
        },
        GEOMETRY_GRAIN);

    // Step 4: bounds of the surface (exact min/max: order independent).
    m_bounds = parallel_reduce(
        num_triangles, AABBd{},
        [&](std::int64_t begin, std::int64_t end) {
            AABBd box;
            for (std::int64_t t = begin; t < end; ++t) {
                for (const std::int32_t v : triangles[static_cast<std::size_t>(t)]) {
                    box.extend(positions[index(v)]);
                }
            }
            return box;
        },
        [](const AABBd& a, const AABBd& b) { return merge(a, b); }, GEOMETRY_GRAIN);
}

std::optional<SurfaceDistance> MeshObstacle::surface_distance(const Vec3d& x,
                                                              double max_distance) const {
    const std::optional<SurfacePoint> point = closest(x, max_distance);
    if (!point) {
        return std::nullopt;
    }
    return point->surface;
}

std::optional<MeshObstacle::SurfacePoint> MeshObstacle::surface_point(const Vec3d& x,
                                                                      double max_distance) const {
    return closest(x, max_distance);
}

std::optional<MeshObstacle::SweptHit> MeshObstacle::sweep(const Vec3d& x_t0,
                                                          const Vec3d& x_t1) const {
    if (!is_finite(x_t0) || !is_finite(x_t1)) {
        return std::nullopt;
    }
    AABBd segment;
    segment.extend(x_t0);
    segment.extend(x_t1);
    const std::span<const Vec3d> start = previous_positions();
    const std::span<const Vec3d> end = m_mesh.positions;
    const std::uint32_t* primitives = m_tree.primitives().data();
    collision::CcdOptions options;
    options.max_iterations = SWEEP_MAX_ITERATIONS;
    std::optional<SweptHit> best;
    bvh::query_wide(
        m_tree.nodes().data(), outward_float(segment), -1, [&](std::int32_t leaf, const AABB&) {
            const auto t = static_cast<std::int32_t>(primitives[leaf]);
            const geometry::Triangle& tri = m_mesh.triangles[index(t)];
            const Vec3d& a0 = start[index(tri[0])];
            const Vec3d& b0 = start[index(tri[1])];
            const Vec3d& c0 = start[index(tri[2])];
            // From the outside only: in front of the triangle's plane at the start.
            if (!(dot(x_t0 - a0, cross(b0 - a0, c0 - a0)) > 0.0)) {
                return;
            }
            const Vec3d& a1 = end[index(tri[0])];
            const Vec3d& b1 = end[index(tri[1])];
            const Vec3d& c1 = end[index(tri[2])];
            const collision::CcdResult r =
                collision::vertex_face_ccd(x_t0, a0, b0, c0, x_t1, a1, b1, c1, options);
            if (!r.hit ||
                (best && (r.toi > best->toi || (r.toi == best->toi && t > best->triangle)))) {
                return;
            }
            const double s = r.toi;
            const collision::PointTriangleProximity<double> at =
                collision::point_triangle_proximity(x_t0 + (x_t1 - x_t0) * s, a0 + (a1 - a0) * s,
                                                    b0 + (b1 - b0) * s, c0 + (c1 - c0) * s);
            best = SweptHit{t, at.barycentric, s};
        });
    return best;
}

bool MeshObstacle::meets_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) const {
    if (!is_finite(a) || !is_finite(b) || !is_finite(c)) {
        return false;
    }
    AABBd box = AABBd::of_point(a);
    box.extend(b);
    box.extend(c);
    const std::span<const Vec3d> now = m_mesh.positions;
    const std::uint32_t* primitives = m_tree.primitives().data();
    bool meets = false;
    bvh::query_wide(m_tree.nodes().data(), outward_float(box), -1,
                    [&](std::int32_t leaf, const AABB&) {
                        if (meets) {
                            return;
                        }
                        const geometry::Triangle& tri =
                            m_mesh.triangles[index(static_cast<std::int32_t>(primitives[leaf]))];
                        meets = geometry::triangles_intersect(
                            a, b, c, now[index(tri[0])], now[index(tri[1])], now[index(tri[2])]);
                    });
    return meets;
}

std::optional<MeshObstacle::EdgeHit> MeshObstacle::sweep_edge(const Vec3d& p_t0, const Vec3d& q_t0,
                                                              const Vec3d& p_t1,
                                                              const Vec3d& q_t1) const {
    if (!is_finite(p_t0) || !is_finite(q_t0) || !is_finite(p_t1) || !is_finite(q_t1)) {
        return std::nullopt;
    }
    AABBd swept;
    for (const Vec3d& x : {p_t0, q_t0, p_t1, q_t1}) {
        swept.extend(x);
    }
    const std::span<const Vec3d> start = previous_positions();
    const std::span<const Vec3d> end = m_mesh.positions;
    const std::uint32_t* primitives = m_tree.primitives().data();
    collision::CcdOptions options;
    options.max_iterations = SWEEP_MAX_ITERATIONS;
    std::optional<EdgeHit> best;
    bvh::query_wide(
        m_tree.nodes().data(), outward_float(swept), -1, [&](std::int32_t leaf, const AABB&) {
            const auto t = static_cast<std::int32_t>(primitives[leaf]);
            for (const std::int32_t e : m_triangle_edges[index(t)]) {
                const std::size_t ei = index(e);
                // Each edge once: from its first triangle.
                if (m_edge_triangles[index(m_edge_triangle_offsets[ei])] != t) {
                    continue;
                }
                const geometry::Edge& edge = m_edges[ei];
                const Vec3d& a0 = start[index(edge[0])];
                const Vec3d& b0 = start[index(edge[1])];
                const Vec3d& a1 = end[index(edge[0])];
                const Vec3d& b1 = end[index(edge[1])];
                AABBd edge_box;
                for (const Vec3d& x : {a0, b0, a1, b1}) {
                    edge_box.extend(x);
                }
                if (!overlaps(edge_box, swept)) {
                    continue;
                }
                const collision::CcdResult r =
                    collision::edge_edge_ccd(p_t0, q_t0, a0, b0, p_t1, q_t1, a1, b1, options);
                if (!r.hit ||
                    (best && (r.toi > best->toi || (r.toi == best->toi && e > best->edge)))) {
                    continue;
                }
                const double u = r.toi;
                const Vec3d p = p_t0 + (p_t1 - p_t0) * u;
                const Vec3d q = q_t0 + (q_t1 - q_t0) * u;
                const Vec3d a = a0 + (a1 - a0) * u;
                const Vec3d b = b0 + (b1 - b0) * u;
                const collision::SegmentSegmentProximity<double> at =
                    collision::segment_segment_proximity(p, q, a, b);
                // Entering: the cloth point crosses the surface edge toward the inside, along the
                // edges' common normal turned to the outside (the edge's pseudo-normal at the
                // meeting; the pseudo-normal itself for parallel edges).
                const Vec3d normal = crossing_normal(
                    q - p, b - a,
                    unit_normal_sum(csr_row(m_edge_triangle_offsets, m_edge_triangles, ei), u));
                const Vec3d cloth_motion = (p_t1 - p_t0) * (1.0 - at.s) + (q_t1 - q_t0) * at.s;
                const Vec3d surface_motion = (a1 - a0) * (1.0 - at.t) + (b1 - b0) * at.t;
                if (!(dot(cloth_motion - surface_motion, normal) < 0.0)) {
                    continue;
                }
                best = EdgeHit{e, r.toi, at.s, at.t};
            }
        });
    return best;
}

Vec3d MeshObstacle::unit_normal_sum(std::span<const std::int32_t> triangles, double u) const {
    const std::span<const Vec3d> start = previous_positions();
    const std::span<const Vec3d> end = m_mesh.positions;
    Vec3d sum{};
    for (const std::int32_t t : triangles) {
        const geometry::Triangle& tri = m_mesh.triangles[index(t)];
        std::array<Vec3d, 3> corner;
        for (std::size_t j = 0; j < 3; ++j) {
            const Vec3d& x0 = start[index(tri[j])];
            corner[j] = x0 + (end[index(tri[j])] - x0) * u;
        }
        const Vec3d n = cross(corner[1] - corner[0], corner[2] - corner[0]);
        const double length = norm(n);
        if (length > 0.0) {
            sum += n * (1.0 / length);
        }
    }
    return sum;
}

std::optional<MeshObstacle::VertexHit> MeshObstacle::sweep_triangle(
    const Vec3d& a_t0, const Vec3d& b_t0, const Vec3d& c_t0, const Vec3d& a_t1, const Vec3d& b_t1,
    const Vec3d& c_t1) const {
    AABBd swept;
    for (const Vec3d& x : {a_t0, b_t0, c_t0, a_t1, b_t1, c_t1}) {
        if (!is_finite(x)) {
            return std::nullopt;
        }
        swept.extend(x);
    }
    collision::CcdOptions options;
    options.max_iterations = SWEEP_MAX_ITERATIONS;
    std::optional<VertexHit> best;
    const std::uint32_t* vertices = m_vertex_tree.primitives().data();
    bvh::query_wide(
        m_vertex_tree.nodes().data(), outward_float(swept), -1,
        [&](std::int32_t leaf, const AABB&) {
            const auto v = static_cast<std::int32_t>(vertices[leaf]);
            const std::size_t vi = index(v);
            const auto& [x0, x1] = m_vertex_paths[index(leaf)];
            const collision::CcdResult r =
                collision::vertex_face_ccd(x0, a_t0, b_t0, c_t0, x1, a_t1, b_t1, c_t1, options);
            if (!r.hit ||
                (best && (r.toi > best->toi || (r.toi == best->toi && v > best->vertex)))) {
                return;
            }
            const double u = r.toi;
            const Vec3d a = a_t0 + (a_t1 - a_t0) * u;
            const Vec3d b = b_t0 + (b_t1 - b_t0) * u;
            const Vec3d c = c_t0 + (c_t1 - c_t0) * u;
            const collision::PointTriangleProximity<double> at =
                collision::point_triangle_proximity(x0 + (x1 - x0) * u, a, b, c);
            // Entering: the surface vertex crosses the triangle toward the outside, along
            // the triangle's normal turned to the outside (the vertex's pseudo-normal at the
            // meeting; the pseudo-normal itself for a degenerate triangle).
            const Vec3d normal = crossing_normal(
                b - a, c - a,
                unit_normal_sum(csr_row(m_vertex_triangle_offsets, m_vertex_triangles, vi), u));
            const Vec3d& w = at.barycentric;
            const Vec3d cloth_motion =
                (a_t1 - a_t0) * w.x + (b_t1 - b_t0) * w.y + (c_t1 - c_t0) * w.z;
            if (!(dot(x1 - x0 - cloth_motion, normal) > 0.0)) {
                return;
            }
            best = VertexHit{v, r.toi, w};
        });
    return best;
}

std::optional<MeshObstacle::SurfacePoint> MeshObstacle::closest(const Vec3d& x,
                                                                double max_distance) const {
    if (!(max_distance >= 0.0) || !is_finite(x)) {
        return std::nullopt;
    }
    const geometry::Triangle* triangles = m_mesh.triangles.data();
    const std::array<Vec3d, 3>* leaf_corners = m_leaf_corners.data();
    const std::uint32_t* primitives = m_tree.primitives().data();

    // Closest triangle: least (distance, triangle index) within max_distance. The radius handed
    // back to the traversal is the best distance so far; a tie at that distance is still visited
    // (closed boxes), so the choice does not depend on the visit order.
    bool found = false;
    std::int32_t best_triangle = -1;
    collision::PointTriangleProximity<double> best{};
    best.distance = max_distance;
    bvh::query_wide_nearest(
        m_tree.nodes().data(), x, max_distance, [&](std::int32_t leaf, const AABB&) {
            const std::array<Vec3d, 3>& c = leaf_corners[leaf];
            const collision::PointTriangleProximity<double> proximity =
                collision::point_triangle_proximity(x, c[0], c[1], c[2]);
            if (proximity.distance <= best.distance) {
                const auto t = static_cast<std::int32_t>(primitives[leaf]);
                if (proximity.distance < best.distance || !found || t < best_triangle) {
                    best = proximity;
                    best_triangle = t;
                    found = true;
                }
            }
            return best.distance;
        });
    if (!found) {
        return std::nullopt;
    }

    // The pseudo-normal of the closest feature decides the side.
    using Region = collision::PointTriangleRegion;
    const geometry::Triangle& tri = triangles[best_triangle];
    Vec3d pseudo_normal;
    if (best.region == Region::FACE) {
        pseudo_normal = m_face_normals[index(best_triangle)];
    } else if (best.region <= Region::VERTEX_C) {
        pseudo_normal = m_vertex_normals[index(tri[best.region - Region::VERTEX_A])];
    } else {
        pseudo_normal = m_edge_normals[index(m_triangle_edges[index(
            best_triangle)][static_cast<std::size_t>(best.region - Region::EDGE_AB)])];
    }
    if (best.distance > 0.0) {
        const bool inside = dot(best.normal, pseudo_normal) < 0.0;
        return SurfacePoint{SurfaceDistance{inside ? -best.distance : best.distance,
                                            inside ? -best.normal : best.normal},
                            best_triangle, best.barycentric};
    }
    // On the surface: the feature's own direction (the triangle's when the pseudo-normal vanishes,
    // e.g. on a degenerate triangle or a fin folded flat onto itself).
    const double length = norm(pseudo_normal);
    return SurfacePoint{
        SurfaceDistance{0.0, length > 0.0 ? pseudo_normal * (1.0 / length) : best.normal},
        best_triangle, best.barycentric};
}

ContactCorrection push_out(const MeshObstacle& obstacle, Vec3d& x, double thickness,
                           double max_depth) {
    const std::optional<SurfaceDistance> surface =
        obstacle.surface_distance(x, std::max(thickness, max_depth));
    if (!surface) {
        return {0.0, Vec3d{}};
    }
    const double depth = thickness - surface->distance;
    if (!(depth > 0.0) || surface->distance < -max_depth) {
        return {0.0, surface->normal};
    }
    x += surface->normal * depth;
    return {depth, surface->normal};
}

}  // namespace pliant::cloth
