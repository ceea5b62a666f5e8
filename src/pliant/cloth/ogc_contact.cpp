#include "pliant/cloth/ogc_contact.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "pliant/cloth/detail/pair_bounds.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t PAIR_GRAIN = 2048;
// The broad phase's memory guard (collision/self_broad_phase.hpp): triangle pairs per triangle.
constexpr std::int64_t PAIR_LIMIT = 64;
// Every SHIFT_SAMPLE-th free vertex takes part in the frame shift's median.
constexpr std::size_t SHIFT_SAMPLE = 16;

double median(std::vector<double>& values) {
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

// Distance, normal and signed weights (first feature +, second −) of a pair at positions p.
struct PairGeometry {
    double distance;
    Vec3d normal;
    std::array<double, 4> weights;
    // Vertex-face: the closest point's collision::PointTriangleRegion; edge-edge: 0 when both
    // closest points are inside their edges, else 1.
    int region;
};

PairGeometry pair_geometry(const OgcContact::Pair& pair, const std::array<Vec3d, 4>& p) {
    if (pair.is_edge_edge) {
        const auto prox = collision::segment_segment_proximity(p[0], p[1], p[2], p[3]);
        const bool inside = prox.s > 0.0 && prox.s < 1.0 && prox.t > 0.0 && prox.t < 1.0;
        return {prox.distance,
                prox.normal,
                {1.0 - prox.s, prox.s, -(1.0 - prox.t), -prox.t},
                inside ? 0 : 1};
    }
    const auto prox = collision::point_triangle_proximity(p[0], p[1], p[2], p[3]);
    return {prox.distance,
            prox.normal,
            {1.0, -prox.barycentric.x, -prox.barycentric.y, -prox.barycentric.z},
            prox.region};
}

}  // namespace

void OgcContact::check_options(const OgcOptions& options) {
    const auto finite_at_least = [](double value, double low) {
        return std::isfinite(value) && value >= low;
    };
    if (!finite_at_least(options.radius, 0.0) || !finite_at_least(options.query_factor, 1.0) ||
        !(options.bound_share > 0.0 && options.bound_share < 0.5) ||
        !(options.redetect_share >= 0.0 && options.redetect_share <= 1.0) ||
        !finite_at_least(options.stiffness, 0.0)) {
        throw InvalidInput(fmt::format(
            "cloth: ogc contact: expected radius >= 0, query_factor >= 1, 0 < bound_share < 0.5, "
            "0 <= redetect_share <= 1 and stiffness >= 0, got {}, {}, {}, {} and {}",
            options.radius, options.query_factor, options.bound_share, options.redetect_share,
            options.stiffness));
    }
    if (options.wide_query_factor != 0.0 &&
        !finite_at_least(options.wide_query_factor, options.query_factor)) {
        throw InvalidInput(fmt::format(
            "cloth: ogc contact: expected wide_query_factor 0 (off) or >= query_factor {}, got {}",
            options.query_factor, options.wide_query_factor));
    }
}

OgcContact::OgcContact(std::span<const geometry::Triangle> triangles, std::size_t num_vertices,
                       const OgcOptions& options, double radius, double stiffness)
    : m_options(options),
      m_num_vertices(num_vertices),
      m_radius(radius),
      m_query_radius(radius * options.query_factor),
      m_ball_radius(radius * options.query_factor * options.bound_share),
      m_base_query_radius(m_query_radius),
      m_base_ball_radius(m_ball_radius),
      m_wide_query_radius(options.wide_query_factor > 0.0 ? radius * options.wide_query_factor
                                                          : m_query_radius),
      m_wide_ball_radius(
          options.wide_query_factor > 0.0
              ? 0.5 * (m_wide_query_radius - (1.0 - 2.0 * options.bound_share) * m_query_radius)
              : m_ball_radius),
      m_stiffness(stiffness),
      m_broad_phase(triangles, num_vertices),
      m_triangles(triangles.begin(), triangles.end()) {
    check_options(options);
    if (!(radius > 0.0 && std::isfinite(radius)) ||
        !(stiffness > 0.0 && std::isfinite(stiffness))) {
        throw InvalidInput(fmt::format(
            "cloth: ogc contact: expected a contact radius > 0 m (the thickness when radius is 0) "
            "and a stiffness > 0 N/m, got {} and {}",
            radius, stiffness));
    }
    m_broad_phase.set_pair_limit(PAIR_LIMIT);
    // The pairs are kept by their exact distances: the float boxes alone (rounded outward) give
    // a superset of the broad phase's exact pairs, in the same order, without its double boxes.
    m_broad_phase.set_exact(false);
    m_snapshot.resize(num_vertices);
    const geometry::MeshTopology& topology = m_broad_phase.topology();
    m_owned_features.assign(m_triangles.size(), 0);
    for (std::size_t f = 0; f < m_triangles.size(); ++f) {
        std::uint8_t owned = 0;
        for (std::size_t k = 0; k < 3; ++k) {
            const auto e = static_cast<std::size_t>(topology.triangle_edges[f][k]);
            const auto first_of_edge = static_cast<std::size_t>(
                topology
                    .edge_triangles[static_cast<std::size_t>(topology.edge_triangle_offsets[e])]);
            const auto corner = static_cast<std::size_t>(m_triangles[f][k]);
            const auto first_at_corner =
                static_cast<std::size_t>(topology.vertex_triangles[static_cast<std::size_t>(
                    topology.vertex_triangle_offsets[corner])]);
            owned |= static_cast<std::uint8_t>((first_of_edge == f ? 1U : 0U) << k);
            owned |= static_cast<std::uint8_t>((first_at_corner == f ? 1U : 0U) << (3 + k));
        }
        m_owned_features[f] = owned;
    }
}

bool OgcContact::counts_once(const Pair& pair, int region) const {
    using Region = collision::PointTriangleRegion;
    if (pair.is_edge_edge || region == Region::FACE) {
        return region == 0;
    }
    const std::uint8_t owned = m_owned_features[static_cast<std::size_t>(pair.face)];
    if (region >= Region::EDGE_AB) {
        return ((owned >> (region - Region::EDGE_AB)) & 1U) != 0;
    }
    const int corner = region - Region::VERTEX_A;
    return ((owned >> (3 + corner)) & 1U) != 0 && pair.v[0] < pair.v[1 + corner];
}

void OgcContact::begin_substep() {
    ++m_since_redetect;
    m_wide_hold = std::max<std::int64_t>(0, m_wide_hold - 1);
}

void OgcContact::redetect(std::span<const Vec3d> x) {
    if (m_options.wide_query_factor > 0.0 && m_since_redetect <= WIDE_TRIGGER_SUBSTEPS) {
        m_wide_hold = WIDE_HOLD_SUBSTEPS;
    }
    m_since_redetect = 0;
    detect(x);
}

void OgcContact::detect(std::span<const Vec3d> x) {
    const Stopwatch watch;
    m_wide = m_wide_hold > 0;
    m_query_radius = m_wide ? m_wide_query_radius : m_base_query_radius;
    m_ball_radius = m_wide ? m_wide_ball_radius : m_base_ball_radius;
    // Built from scratch at every detection, so that the pairs' order (and the contact forces'
    // summation order) depends on x only: a resumed run detects the same.
    m_broad_phase.request_rebuild();
    // Triangle pairs whose separating-axis lower bound on their distance (detail/pair_bounds.hpp)
    // is at least r_q, with a relative margin far above the bound's few ulps of rounding, hold no
    // feature pair within r_q: they emit none (the pairs kept and their order do not change).
    const double far = m_query_radius * (1.0 + 1e-9);
    const auto within_reach = [&](std::int32_t a, std::int32_t b) {
        const geometry::Triangle& ta = m_triangles[static_cast<std::size_t>(a)];
        const geometry::Triangle& tb = m_triangles[static_cast<std::size_t>(b)];
        const Vec3d pa[3] = {x[static_cast<std::size_t>(ta[0])], x[static_cast<std::size_t>(ta[1])],
                             x[static_cast<std::size_t>(ta[2])]};
        const Vec3d pb[3] = {x[static_cast<std::size_t>(tb[0])], x[static_cast<std::size_t>(tb[1])],
                             x[static_cast<std::size_t>(tb[2])]};
        return detail::centroid_axis_gap(pa, pb) < far;
    };
    const collision::SelfCollisionBroadPhase<double>::TrianglePairFilter filter(within_reach);
    const collision::FeaturePairs& found =
        m_broad_phase.update(x, x, 0.5 * m_query_radius, &filter);
    if (m_broad_phase.pair_limit_exceeded()) {
        m_has_detection = false;
        throw InvalidInput(fmt::format(
            "cloth: ogc contact: more than {} triangle pairs per triangle within the query radius "
            "{} m (the simulation diverged, or layers are packed far closer than the radius)",
            PAIR_LIMIT, m_query_radius));
    }
    const std::span<const geometry::Edge> edges = m_broad_phase.topology().edges;
    const std::span<const geometry::Triangle> triangles = m_triangles;
    const auto num_vf = static_cast<std::int64_t>(found.vertex_face.size());
    const auto total = num_vf + static_cast<std::int64_t>(found.edge_edge.size());
    m_distances.resize(static_cast<std::size_t>(total));
    m_geometry.resize(static_cast<std::size_t>(total));
    std::vector<Pair> candidates(static_cast<std::size_t>(total));
    // Closest points: geometry[i] = {point of the first feature, of the second, normal from the
    // second toward the first}. Most candidates are in-plane neighbours beyond the query radius
    // (the boxes meet two rings out): the same separating-axis bound on the features rejects
    // them without the exact distance; the kept pairs are the same.
    parallel_for(
        total,
        [&](std::int64_t i) {
            const auto slot = static_cast<std::size_t>(i);
            Pair& pair = candidates[slot];
            if (i < num_vf) {
                const collision::VertexFacePair& vf = found.vertex_face[slot];
                const geometry::Triangle& t = triangles[static_cast<std::size_t>(vf.face)];
                pair = {{vf.vertex, t[0], t[1], t[2]}, false, vf.face};
                const Vec3d& p = x[static_cast<std::size_t>(vf.vertex)];
                const Vec3d& a = x[static_cast<std::size_t>(t[0])];
                const Vec3d& b = x[static_cast<std::size_t>(t[1])];
                const Vec3d& c = x[static_cast<std::size_t>(t[2])];
                const double gap = detail::centroid_axis_gap<false>(p, a, b, c);
                if (gap >= far) {
                    m_distances[slot] = gap;
                    return;
                }
                const auto prox = collision::point_triangle_proximity(p, a, b, c);
                m_distances[slot] = prox.distance;
                m_geometry[slot] = {p, p - prox.normal * prox.distance, prox.normal};
            } else {
                const collision::EdgeEdgePair& ee =
                    found.edge_edge[static_cast<std::size_t>(i - num_vf)];
                const geometry::Edge& a = edges[static_cast<std::size_t>(ee.edge_a)];
                const geometry::Edge& b = edges[static_cast<std::size_t>(ee.edge_b)];
                pair = {{a[0], a[1], b[0], b[1]}, true};
                const Vec3d& p0 = x[static_cast<std::size_t>(a[0])];
                const Vec3d& p1 = x[static_cast<std::size_t>(a[1])];
                const Vec3d& q0 = x[static_cast<std::size_t>(b[0])];
                const Vec3d& q1 = x[static_cast<std::size_t>(b[1])];
                const double gap = detail::centroid_axis_gap<true>(p0, p1, q0, q1);
                if (gap >= far) {
                    m_distances[slot] = gap;
                    return;
                }
                const auto prox = collision::segment_segment_proximity(p0, p1, q0, q1);
                m_distances[slot] = prox.distance;
                m_geometry[slot] = {p0 + (p1 - p0) * prox.s, q0 + (q1 - q0) * prox.t, prox.normal};
            }
        },
        PAIR_GRAIN);

    // Kept pairs, then per vertex (CSR, in pair order) a plane and a reference each.
    m_pairs.clear();
    m_pair_normals.clear();
    m_pair_distances.clear();
    m_close_pairs = 0;
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (m_distances[i] < m_query_radius) {
            kept.push_back(i);
            m_pairs.push_back(candidates[i]);
            m_pair_normals.push_back(m_geometry[i][2]);
            m_pair_distances.push_back(m_distances[i]);
            m_close_pairs += m_distances[i] < m_radius ? 1 : 0;
        }
    }
    m_pair_first.assign(m_num_vertices + 1, 0);
    for (const Pair& pair : m_pairs) {
        for (const std::int32_t v : pair.v) {
            ++m_pair_first[static_cast<std::size_t>(v) + 1];
        }
    }
    for (std::size_t v = 0; v < m_num_vertices; ++v) {
        m_pair_first[v + 1] += m_pair_first[v];
    }
    m_pair_refs.resize(static_cast<std::size_t>(m_pair_first[m_num_vertices]));
    m_planes.resize(m_pair_refs.size());
    std::vector<std::int32_t> fill(m_pair_first.begin(), m_pair_first.end() - 1);
    for (std::size_t p = 0; p < m_pairs.size(); ++p) {
        const std::size_t i = kept[p];
        const std::array<Vec3d, 3>& g = m_geometry[i];
        const Vec3d& n = g[2];
        const Vec3d middle = (g[0] + g[1]) * 0.5;
        const double keep = PLANE_MARGIN * 0.5 * m_distances[i];
        const int num_first = m_pairs[p].is_edge_edge ? 2 : 1;
        for (int k = 0; k < 4; ++k) {
            const auto v = static_cast<std::size_t>(m_pairs[p].v[k]);
            const auto slot = static_cast<std::size_t>(fill[v]++);
            m_pair_refs[slot] = static_cast<std::int32_t>(p * 4 + static_cast<std::size_t>(k));
            const Vec3d side = k < num_first ? n : n * -1.0;
            m_planes[slot] = {side, dot(side, middle) + keep};
        }
    }
    // The planes a vertex's ball can reach: a plane whose half-space holds the whole ball (its
    // value at the centre, x_v here, at least b, with a relative margin far above rounding) never
    // truncates a move that the ball has not truncated first, nor rejects a point inside the
    // ball, so truncate() and feasible() skip it. A larger query radius adds many such pairs (the
    // in-plane neighbours one ring beyond a vertex's triangles), which cost nothing here then.
    m_plane_first.assign(m_num_vertices + 1, 0);
    std::size_t kept_planes = 0;
    const double reach = m_ball_radius * (1.0 + 1e-6);
    for (std::size_t v = 0; v < m_num_vertices; ++v) {
        m_plane_first[v] = static_cast<std::int32_t>(kept_planes);
        for (auto k = m_pair_first[v]; k < m_pair_first[v + 1]; ++k) {
            const Plane& plane = m_planes[static_cast<std::size_t>(k)];
            if (!(dot(plane.normal, x[v]) - plane.offset > reach)) {
                m_planes[kept_planes++] = plane;
            }
        }
    }
    m_plane_first[m_num_vertices] = static_cast<std::int32_t>(kept_planes);
    m_planes.resize(kept_planes);
    m_contact_vertices.clear();
    m_slack.assign(m_num_vertices, std::numeric_limits<double>::infinity());
    for (std::size_t v = 0; v < m_num_vertices; ++v) {
        if (m_pair_first[v + 1] > m_pair_first[v]) {
            m_contact_vertices.push_back(static_cast<std::int32_t>(v));
            // project()'s per-vertex slack: half the least margin d − r of v's pairs, less a
            // rounding margin of 1e-14 d (0 or less: v's pairs are always tested).
            double slack = std::numeric_limits<double>::infinity();
            for (auto k = m_pair_first[v]; k < m_pair_first[v + 1]; ++k) {
                const auto p =
                    static_cast<std::size_t>(m_pair_refs[static_cast<std::size_t>(k)]) / 4;
                const double d = m_pair_distances[p];
                slack = std::min(slack, 0.5 * (d - m_radius) - 1e-14 * d);
            }
            m_slack[v] = slack;
        }
    }
    m_detected.assign(x.begin(), x.end());
    m_shift = {0.0, 0.0, 0.0};
    m_has_detection = true;
    ++m_detections;
    m_wide_detections += m_wide ? 1 : 0;
    m_detect_ms += watch.elapsed_ms();
}

bool OgcContact::set_shift(std::span<const Vec3d> predicted,
                           std::span<const double> inverse_masses) {
    std::vector<double> dx;
    std::vector<double> dy;
    std::vector<double> dz;
    for (std::size_t v = 0, seen = 0; v < m_num_vertices; ++v) {
        if (inverse_masses[v] > 0.0 && seen++ % SHIFT_SAMPLE == 0) {
            const Vec3d d = predicted[v] - m_detected[v];
            dx.push_back(d.x);
            dy.push_back(d.y);
            dz.push_back(d.z);
        }
    }
    if (dx.empty()) {
        return false;
    }
    const Vec3d previous = m_shift;
    m_shift = {median(dx), median(dy), median(dz)};
    const std::int64_t outside = parallel_reduce(
        static_cast<std::int64_t>(m_num_vertices), std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                count += feasible(v, predicted[v]) ? 0 : 1;
            }
            return count;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, PAIR_GRAIN);
    if (outside > 0) {
        m_shift = previous;
        return false;
    }
    return true;
}

bool OgcContact::truncate(std::size_t v, const Vec3d& from, Vec3d& x) const {
    const Vec3d centre = m_detected[v] + m_shift;
    const Vec3d start = feasible(v, from) ? from : centre;
    const Vec3d move = x - start;
    double t = 1.0;
    if (norm(x - centre) > m_ball_radius) {
        // |start − centre + t move| = b, the root in [0, 1] (start is inside: c <= 0).
        const Vec3d s = start - centre;
        const double a = dot(move, move);
        const double b = dot(s, move);
        const double c = dot(s, s) - m_ball_radius * m_ball_radius;
        t = a > 0.0 ? std::clamp((-b + std::sqrt(std::max(0.0, b * b - a * c))) / a, 0.0, 1.0)
                    : 0.0;
    }
    const Vec3d local_start = start - m_shift;
    const Vec3d local_end = x - m_shift;
    for (auto k = m_plane_first[v]; k < m_plane_first[v + 1]; ++k) {
        const Plane& plane = m_planes[static_cast<std::size_t>(k)];
        const double end = dot(plane.normal, local_end) - plane.offset;
        if (end < 0.0) {
            const double begin = dot(plane.normal, local_start) - plane.offset;
            t = std::min(t, begin > 0.0 ? begin / (begin - end) : 0.0);
        }
    }
    if (t < 1.0) {
        x = start + move * t;
        return true;
    }
    return false;
}

bool OgcContact::feasible(std::size_t v, const Vec3d& x) const {
    const double slop = 1e-12 * (1.0 + norm(x));
    if (norm(x - m_detected[v] - m_shift) > m_ball_radius + slop) {
        return false;
    }
    for (auto k = m_plane_first[v]; k < m_plane_first[v + 1]; ++k) {
        const Plane& plane = m_planes[static_cast<std::size_t>(k)];
        if (dot(plane.normal, x - m_shift) - plane.offset < -slop) {
            return false;
        }
    }
    return true;
}

bool OgcContact::at_ball(std::size_t v, const Vec3d& x) const {
    return norm(x - m_detected[v] - m_shift) >= m_ball_radius * (1.0 - 1e-6);
}

void OgcContact::snapshot(std::span<const Vec3d> x) {
    parallel_for(
        static_cast<std::int64_t>(m_contact_vertices.size()),
        [&](std::int64_t i) {
            const auto v =
                static_cast<std::size_t>(m_contact_vertices[static_cast<std::size_t>(i)]);
            m_snapshot[v] = x[v];
        },
        PAIR_GRAIN);
}

void OgcContact::add_forces(std::size_t v, const Vec3d& x_v, std::span<const Vec3d> start,
                            double friction, double slip, Vec3d& force,
                            detail::Sym3& hessian) const {
    for (auto r = m_pair_first[v]; r < m_pair_first[v + 1]; ++r) {
        const auto ref = static_cast<std::size_t>(m_pair_refs[static_cast<std::size_t>(r)]);
        const Pair& pair = m_pairs[ref / 4];
        const std::size_t k = ref % 4;
        std::array<Vec3d, 4> p;
        for (std::size_t j = 0; j < 4; ++j) {
            p[j] = j == k ? x_v : m_snapshot[static_cast<std::size_t>(pair.v[j])];
        }
        const PairGeometry g = pair_geometry(pair, p);
        const double distance = g.distance;
        const double weight = g.weights[k];
        const Vec3d& normal = g.normal;
        if (!(distance < m_radius) || weight == 0.0 || !counts_once(pair, g.region)) {
            continue;
        }
        // E = ½ k_c (r − d)², ∂d/∂x_v = weight · n̂.
        const double lambda = m_stiffness * (m_radius - distance);
        force += normal * (lambda * weight);
        hessian.add_outer(normal, m_stiffness * weight * weight);
        if (!(friction > 0.0)) {
            continue;
        }
        Vec3d relative{0.0, 0.0, 0.0};
        for (std::size_t j = 0; j < 4; ++j) {
            relative += (p[j] - start[static_cast<std::size_t>(pair.v[j])]) * g.weights[j];
        }
        const Vec3d tangential = relative - normal * dot(relative, normal);
        const double y = norm(tangential);
        // f₁(y) / y: 2/ε − y/ε² while sticking, 1/y sliding.
        const double f1_over_y = y < slip ? (2.0 - y / slip) / slip : 1.0 / y;
        const double scale = friction * lambda * f1_over_y;
        force -= tangential * (scale * weight);
        // μ λ w² f₁/y (I − n̂n̂ᵀ): the identity's part on the diagonal, less the normal's outer
        // product.
        const double diagonal = scale * weight * weight;
        hessian.add_outer(normal, -diagonal);
        hessian.add_diagonal(diagonal);
    }
}

std::int64_t OgcContact::project(std::span<Vec3d> x, std::span<const Vec3d> previous,
                                 std::span<const double> inverse_masses, double static_friction,
                                 double kinetic_friction) {
    const auto gather = [&](const Pair& pair) {
        std::array<Vec3d, 4> p;
        for (std::size_t j = 0; j < 4; ++j) {
            p[j] = x[static_cast<std::size_t>(pair.v[j])];
        }
        return p;
    };
    // The pair's geometry now, with the normal on the detection's side.
    const auto contact = [&](std::size_t i) {
        const Pair& pair = m_pairs[i];
        PairGeometry g = pair_geometry(pair, gather(pair));
        const Vec3d& detected = m_pair_normals[i];
        if (dot(g.normal, detected) < 0.0) {
            Vec3d gap{0.0, 0.0, 0.0};
            for (std::size_t j = 0; j < 4; ++j) {
                gap += x[static_cast<std::size_t>(pair.v[j])] * g.weights[j];
            }
            g.normal = detected;
            g.distance = dot(gap, detected);
        }
        return g;
    };
    // A pair is tested only when one of its vertices deviates from its shifted detection
    // position by at least its slack (detect(): half the least margin d − r of its pairs, less a
    // rounding margin). A pair none of whose vertices does is inactive: with first, second < (d −
    // r) / 2 − 1e-14 d each, d − first − second > r + 2e-14 d, so the per-pair skip below (whose
    // evaluation rounds by a few ulps of d) skips it too, and a feature's distance moves by at
    // most its vertices' largest deviation (every point of a feature is a convex combination of
    // its vertices; a common translation S leaves distances unchanged): it stays at least r
    // apart. The pairs tested and pushed, and their order, are those of a test of every pair.
    m_deviations.resize(m_num_vertices);
    parallel_for(
        static_cast<std::int64_t>(m_contact_vertices.size()),
        [&](std::int64_t i) {
            const auto v =
                static_cast<std::size_t>(m_contact_vertices[static_cast<std::size_t>(i)]);
            m_deviations[v] = norm(x[v] - m_detected[v] - m_shift);
        },
        PAIR_GRAIN);
    // The pairs of the vertices past their slack, in pair order: marked in a bit set (cleared as
    // it is read), so that a substep costs O(#V + #pairs / 64 + the pairs tested).
    m_marks.resize((m_pairs.size() + 63) / 64, 0);
    for (const std::int32_t v : m_contact_vertices) {
        const auto u = static_cast<std::size_t>(v);
        if (!(m_deviations[u] < m_slack[u])) {  // past its slack (NaN: tested)
            for (auto r = m_pair_first[u]; r < m_pair_first[u + 1]; ++r) {
                const auto p =
                    static_cast<std::size_t>(m_pair_refs[static_cast<std::size_t>(r)]) / 4;
                m_marks[p / 64] |= std::uint64_t{1} << (p % 64);
            }
        }
    }
    m_tested.clear();
    for (std::size_t word = 0; word < m_marks.size(); ++word) {
        for (std::uint64_t bits = m_marks[word]; bits != 0; bits &= bits - 1) {
            m_tested.push_back(static_cast<std::int32_t>(
                word * 64 + static_cast<std::size_t>(std::countr_zero(bits))));
        }
        m_marks[word] = 0;
    }
    m_close.resize(m_tested.size());
    parallel_for(
        static_cast<std::int64_t>(m_tested.size()),
        [&](std::int64_t i) {
            const auto slot = static_cast<std::size_t>(m_tested[static_cast<std::size_t>(i)]);
            const auto entry = static_cast<std::size_t>(i);
            const Pair& pair = m_pairs[slot];
            const auto deviation = [&](std::size_t j) {
                return m_deviations[static_cast<std::size_t>(pair.v[j])];
            };
            const double first =
                pair.is_edge_edge ? std::max(deviation(0), deviation(1)) : deviation(0);
            const double second = pair.is_edge_edge
                                      ? std::max(deviation(2), deviation(3))
                                      : std::max({deviation(1), deviation(2), deviation(3)});
            const double detected = m_pair_distances[slot];
            if (detected - first - second >= m_radius) {
                m_close[entry] = 0;
                return;
            }
            // The features' relative motion since the detection, δ = max |u_i − u_j| over a
            // vertex i of the first feature and j of the second, u = x − detected position. The
            // pair's Minkowski difference M = {p − q} moves by at most δ point by point (every
            // point is Σ a_i b_j (x_i − x_j), Σ a_i = Σ b_j = 1), and every point of M at the
            // detection lies at least d₀ along the detection's normal n₀ (n₀ is its least point's
            // direction; M is convex). So the least point w of M now has |w| >= dot(w, n₀) >=
            // d₀ − δ: with d₀ − δ >= r (less a rounding margin) the distance is at least r and
            // the normal is not against n₀, so contact() finds the pair no closer than r. In-plane
            // neighbours that move with the sheet (past the frame shift's translation) move little
            // relative to each other.
            const auto at = [&](std::size_t j) {
                return static_cast<std::size_t>(pair.v[j]);
            };
            std::array<Vec3d, 4> u;
            for (std::size_t j = 0; j < 4; ++j) {
                u[j] = x[at(j)] - m_detected[at(j)];
            }
            const std::size_t num_first = pair.is_edge_edge ? 2 : 1;
            double relative = 0.0;
            for (std::size_t a = 0; a < num_first; ++a) {
                for (std::size_t b = num_first; b < 4; ++b) {
                    const Vec3d d = u[a] - u[b];
                    relative = std::max(relative, dot(d, d));
                }
            }
            const Vec3d& anchor = x[at(0)];
            const double rounding =
                1e-9 * (1.0 + detected +
                        std::max({std::abs(anchor.x), std::abs(anchor.y), std::abs(anchor.z)}));
            if (detected - std::sqrt(relative) >= m_radius + rounding) {
                m_close[entry] = 0;
                return;
            }
            m_close[entry] = contact(slot).distance < m_radius ? 1 : 0;
        },
        PAIR_GRAIN);
    // Moves the pair's vertices along `direction` so that their weighted difference grows by
    // `amount`.
    const auto separate = [&](const Pair& pair, const std::array<double, 4>& weights,
                              const Vec3d& direction, double amount) {
        double denominator = 0.0;
        for (std::size_t j = 0; j < 4; ++j) {
            denominator +=
                inverse_masses[static_cast<std::size_t>(pair.v[j])] * weights[j] * weights[j];
        }
        if (!(denominator > 0.0)) {
            return;
        }
        const double lambda = amount / denominator;
        for (std::size_t j = 0; j < 4; ++j) {
            const auto v = static_cast<std::size_t>(pair.v[j]);
            x[v] += direction * (inverse_masses[v] * weights[j] * lambda);
        }
    };
    std::int64_t pushed = 0;
    for (std::size_t entry = 0; entry < m_tested.size(); ++entry) {
        if (m_close[entry] == 0) {
            continue;
        }
        const auto i = static_cast<std::size_t>(m_tested[entry]);
        const Pair& pair = m_pairs[i];
        const PairGeometry g = contact(i);
        if (!(g.distance < m_radius)) {
            continue;
        }
        const double gap = m_radius - g.distance;
        separate(pair, g.weights, g.normal, gap);
        ++pushed;
        Vec3d relative{0.0, 0.0, 0.0};
        for (std::size_t j = 0; j < 4; ++j) {
            const auto v = static_cast<std::size_t>(pair.v[j]);
            relative += (x[v] - previous[v]) * g.weights[j];
        }
        const Vec3d tangential = relative - g.normal * dot(relative, g.normal);
        const double slide = norm(tangential);
        if (!(slide > 0.0)) {
            continue;
        }
        const double removed =
            slide <= static_friction * gap ? slide : std::min(slide, kinetic_friction * gap);
        separate(pair, g.weights, tangential * (-1.0 / slide), removed);
    }
    return pushed;
}

std::int64_t OgcContact::remove_separating_velocity(std::span<const Vec3d> x,
                                                    std::span<Vec3d> velocities,
                                                    std::span<const double> inverse_masses) const {
    std::int64_t changed = 0;
    for (const Pair& pair : m_pairs) {
        std::array<Vec3d, 4> p;
        for (std::size_t j = 0; j < 4; ++j) {
            p[j] = x[static_cast<std::size_t>(pair.v[j])];
        }
        const PairGeometry g = pair_geometry(pair, p);
        if (!(g.distance < m_radius)) {
            continue;
        }
        double separating = 0.0;
        double weight = 0.0;
        for (std::size_t j = 0; j < 4; ++j) {
            const auto v = static_cast<std::size_t>(pair.v[j]);
            separating += g.weights[j] * dot(velocities[v], g.normal);
            weight += g.weights[j] * g.weights[j] * inverse_masses[v];
        }
        if (separating > 0.0 && weight > 0.0) {
            const double impulse = separating / weight;
            for (std::size_t j = 0; j < 4; ++j) {
                const auto v = static_cast<std::size_t>(pair.v[j]);
                velocities[v] -= g.normal * (impulse * g.weights[j] * inverse_masses[v]);
            }
            ++changed;
        }
    }
    return changed;
}

void OgcContact::save_state(ByteWriter& out) const {
    out.put(static_cast<std::uint64_t>(m_num_vertices));
    out.put(m_has_detection);
    out.put(m_detections);
    if (m_has_detection) {
        out.put_vector(m_detected);
        out.put(m_shift);
    }
    if (m_options.wide_query_factor > 0.0) {
        out.put(m_wide);
        out.put(m_wide_detections);
        out.put(m_since_redetect);
        out.put(m_wide_hold);
    }
}

void OgcContact::load_state(ByteReader& in) {
    const auto num_vertices = in.get<std::uint64_t>("ogc.num_vertices");
    if (num_vertices != m_num_vertices) {
        throw InvalidInput(fmt::format("{}: ogc contact: a state of {} vertices, the cloth has {}",
                                       in.source(), num_vertices, m_num_vertices));
    }
    const bool has_detection = in.get_bool("ogc.has_detection");
    const auto detections = in.get<std::int64_t>("ogc.detections");
    std::vector<Vec3d> detected;
    Vec3d shift{0.0, 0.0, 0.0};
    if (has_detection) {
        in.get_vector("ogc.detected", detected, static_cast<std::int64_t>(m_num_vertices));
        shift = in.get<Vec3d>("ogc.shift");
        if (!std::isfinite(shift.x) || !std::isfinite(shift.y) || !std::isfinite(shift.z)) {
            throw InvalidInput(
                fmt::format("{}: ogc contact: a frame shift that is not finite", in.source()));
        }
    }
    bool wide = false;
    std::int64_t wide_detections = 0;
    std::int64_t since_redetect = m_since_redetect;
    std::int64_t wide_hold = 0;
    if (m_options.wide_query_factor > 0.0) {
        wide = in.get_bool("ogc.wide");
        wide_detections = in.get<std::int64_t>("ogc.wide_detections");
        since_redetect = in.get<std::int64_t>("ogc.since_redetect");
        wide_hold = in.get<std::int64_t>("ogc.wide_hold");
        if (wide_detections < 0 || since_redetect < 0 || wide_hold < 0 ||
            wide_hold > WIDE_HOLD_SUBSTEPS) {
            throw InvalidInput(fmt::format(
                "{}: ogc contact: expected wide-radius counters >= 0 and a hold <= {}, got {}, {} "
                "and {}",
                in.source(), WIDE_HOLD_SUBSTEPS, wide_detections, since_redetect, wide_hold));
        }
    }
    if (has_detection) {
        // The detection again, at the radius it had.
        m_wide_hold = wide ? 1 : 0;
        detect(detected);
        m_shift = shift;
    } else {
        m_has_detection = false;
    }
    m_detections = detections;
    m_wide_detections = wide_detections;
    m_since_redetect = since_redetect;
    m_wide_hold = wide_hold;
}

}  // namespace pliant::cloth
