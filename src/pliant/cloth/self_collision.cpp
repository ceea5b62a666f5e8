#include "pliant/cloth/self_collision.hpp"

#include <algorithm>
#include <cmath>

#include "pliant/collision/narrow_phase.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t PAIR_GRAIN = 512;

// Pushes the features apart along normal so that their distance grows by `gap`, weighted by the
// inverse masses w[k] and the closest point's barycentric weights b[k] (signed: + for the first
// feature, - for the second). XPBD with zero compliance: Δλ = gap / Σ w_k b_k².
void separate(std::span<Vec3d> positions, std::span<const double> inverse_masses,
              const std::int32_t (&vertices)[4], const double (&weights)[4], const Vec3d& normal,
              double gap) {
    double denominator = 0.0;
    for (int k = 0; k < 4; ++k) {
        denominator +=
            inverse_masses[static_cast<std::size_t>(vertices[k])] * weights[k] * weights[k];
    }
    if (!(denominator > 0.0)) {
        return;
    }
    const double lambda = gap / denominator;
    for (int k = 0; k < 4; ++k) {
        const auto v = static_cast<std::size_t>(vertices[k]);
        positions[v] += normal * (inverse_masses[v] * weights[k] * lambda);
    }
}

}  // namespace

SelfCollision::SelfCollision(std::span<const geometry::Triangle> triangles,
                             std::size_t num_vertices, double thickness)
    : m_triangles(triangles.begin(), triangles.end()),
      m_thickness(thickness),
      m_gather_phase(triangles, num_vertices),
      m_swept_phase(triangles, num_vertices) {}

void SelfCollision::gather(std::span<const Vec3d> positions, std::span<const Vec3d> velocities,
                           double dt, const Vec3d& gravity) {
    Stopwatch watch;
    // The predicted end of the step, x + dt v + ½ g dt² (exact for free flight); boxes swept from
    // here to there and grown by the thickness.
    m_predicted.resize(positions.size());
    const Vec3d fall = gravity * (0.5 * dt * dt);
    parallel_for(static_cast<std::int64_t>(positions.size()), [&](std::int64_t i) {
        const auto v = static_cast<std::size_t>(i);
        m_predicted[v] = positions[v] + velocities[v] * dt + fall;
    });
    const collision::FeaturePairs& candidates =
        m_gather_phase.update(positions, std::span<const Vec3d>(m_predicted), m_thickness);
    m_stats.candidate_pairs =
        static_cast<std::int64_t>(candidates.vertex_face.size() + candidates.edge_edge.size());
    add_broad_phase_times(m_gather_phase.stats());
    m_stats.gather_ms += watch.elapsed_ms();
}

void SelfCollision::add_broad_phase_times(const collision::BroadPhaseStats& broad) {
    m_stats.refit_ms += broad.build_ms + broad.refit_ms;
    m_stats.traverse_ms += broad.traverse_ms + broad.features_ms;
}

std::int64_t SelfCollision::project(std::span<Vec3d> positions,
                                    std::span<const Vec3d> previous_positions,
                                    std::span<const double> inverse_masses,
                                    const ClothMaterial& material) {
    Stopwatch watch;
    const collision::FeaturePairs& candidates = m_gather_phase.pairs();
    const auto& edges = m_gather_phase.topology().edges;
    const auto num_vf = static_cast<std::int64_t>(candidates.vertex_face.size());
    const auto num_ee = static_cast<std::int64_t>(candidates.edge_edge.size());
    const auto at = [&](std::int32_t v) {
        return positions[static_cast<std::size_t>(v)];
    };
    // A pair's features, weights, normal and distance at the current positions.
    struct Proximity {
        std::int32_t vertices[4];
        double weights[4];
        Vec3d normal;
        double distance;
    };
    const auto proximity = [&](std::int64_t i) {
        Proximity p{};
        if (i < num_vf) {
            const collision::VertexFacePair& pair =
                candidates.vertex_face[static_cast<std::size_t>(i)];
            const geometry::Triangle& f = m_triangles[static_cast<std::size_t>(pair.face)];
            const collision::PointTriangleProximity<double> q =
                collision::point_triangle_proximity(at(pair.vertex), at(f[0]), at(f[1]), at(f[2]));
            p = {{pair.vertex, f[0], f[1], f[2]},
                 {1.0, -q.barycentric.x, -q.barycentric.y, -q.barycentric.z},
                 q.normal,
                 q.distance};
        } else {
            const collision::EdgeEdgePair& pair =
                candidates.edge_edge[static_cast<std::size_t>(i - num_vf)];
            const geometry::Edge& a = edges[static_cast<std::size_t>(pair.edge_a)];
            const geometry::Edge& b = edges[static_cast<std::size_t>(pair.edge_b)];
            const collision::SegmentSegmentProximity<double> q =
                collision::segment_segment_proximity(at(a[0]), at(a[1]), at(b[0]), at(b[1]));
            p = {{a[0], a[1], b[0], b[1]},
                 {1.0 - q.s, q.s, -(1.0 - q.t), -q.t},
                 q.normal,
                 q.distance};
        }
        return p;
    };
    // In parallel, the pairs closer than thickness (in pair order); then, sequentially, push each
    // apart with its proximity at the positions as they are by then.
    const std::vector<std::int64_t> close = parallel_reduce(
        num_vf + num_ee, std::vector<std::int64_t>{},
        [&](std::int64_t begin, std::int64_t end) {
            std::vector<std::int64_t> found;
            for (std::int64_t i = begin; i < end; ++i) {
                if (proximity(i).distance < m_thickness) {
                    found.push_back(i);
                }
            }
            return found;
        },
        [](std::vector<std::int64_t> a, const std::vector<std::int64_t>& b) {
            a.insert(a.end(), b.begin(), b.end());
            return a;
        },
        PAIR_GRAIN);
    const double narrow_ms = watch.elapsed_ms();
    m_stats.narrow_ms += narrow_ms;
    std::int64_t contacts = 0;
    for (const std::int64_t i : close) {
        const Proximity p = proximity(i);
        if (!(p.distance < m_thickness)) {
            continue;
        }
        const double gap = m_thickness - p.distance;
        separate(positions, inverse_masses, p.vertices, p.weights, p.normal, gap);
        ++contacts;
        // Friction: the pair's relative motion over the substep (first feature minus second, at
        // the closest points), tangential part.
        Vec3d relative{0.0, 0.0, 0.0};
        for (int k = 0; k < 4; ++k) {
            const auto v = static_cast<std::size_t>(p.vertices[k]);
            relative += (positions[v] - previous_positions[v]) * p.weights[k];
        }
        const Vec3d tangential = relative - p.normal * dot(relative, p.normal);
        const double slide = norm(tangential);
        if (!(slide > 0.0)) {
            continue;
        }
        const double removed = slide <= material.self_static_friction * gap
                                   ? slide
                                   : std::min(slide, material.self_kinetic_friction * gap);
        separate(positions, inverse_masses, p.vertices, p.weights, tangential * (-1.0 / slide),
                 removed);
    }
    m_stats.contacts = contacts;
    const double total_ms = watch.elapsed_ms();
    m_stats.response_ms += total_ms - narrow_ms;
    m_stats.project_ms += total_ms;
    return contacts;
}

void SelfCollision::enforce(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                            std::span<Vec3d> velocities) {
    Stopwatch watch;
    const auto& edges = m_swept_phase.topology().edges;
    m_stats.ccd_hits = 0;
    m_stats.reverted_vertices = 0;
    m_stats.enforce_rounds = 0;
    Stopwatch response;  // restarted before each revert pass
    std::vector<std::uint8_t> reverted(positions.size(), 0);
    // Puts v back at its start with zero velocity; true when that moved it.
    const auto revert = [&](std::size_t v) {
        m_stats.reverted_vertices += reverted[v] == 0 ? 1 : 0;
        reverted[v] = 1;
        if (positions[v] == positions_t0[v]) {
            return false;
        }
        positions[v] = positions_t0[v];
        velocities[v] = {0.0, 0.0, 0.0};
        return true;
    };
    for (int round = 0;; ++round) {
        m_stats.enforce_rounds = round + 1;
        if (round == ENFORCE_ROUNDS) {
            // Last resort: every vertex that moved goes back; the frame's start is
            // intersection-free.
            response.restart();
            for (std::size_t v = 0; v < positions.size(); ++v) {
                if (positions[v] != positions_t0[v]) {
                    revert(v);
                }
            }
            m_stats.response_ms += response.elapsed_ms();
            break;
        }
        const collision::FeaturePairs& pairs =
            m_swept_phase.update(positions_t0, std::span<const Vec3d>(positions), 0.0);
        add_broad_phase_times(m_swept_phase.stats());
        Stopwatch ccd;
        const collision::NarrowPhaseResult narrow =
            collision::continuous_narrow_phase(positions_t0, std::span<const Vec3d>(positions),
                                               std::span<const geometry::Triangle>(m_triangles),
                                               std::span<const geometry::Edge>(edges), pairs);
        m_stats.narrow_ms += ccd.elapsed_ms();
        if (round == 0) {
            m_stats.ccd_hits = narrow.vf_hits + narrow.ee_hits;
        }
        if (narrow.vf_hits + narrow.ee_hits == 0) {
            break;
        }
        // The vertices of every pair the CCD cannot clear, in pair order (deterministic).
        response.restart();
        bool moved_any = false;
        for (const collision::VertexFacePair& p : narrow.hits.vertex_face) {
            const geometry::Triangle& f = m_triangles[static_cast<std::size_t>(p.face)];
            for (const std::int32_t v : {p.vertex, f[0], f[1], f[2]}) {
                moved_any |= revert(static_cast<std::size_t>(v));
            }
        }
        for (const collision::EdgeEdgePair& p : narrow.hits.edge_edge) {
            const geometry::Edge& a = edges[static_cast<std::size_t>(p.edge_a)];
            const geometry::Edge& b = edges[static_cast<std::size_t>(p.edge_b)];
            for (const std::int32_t v : {a[0], a[1], b[0], b[1]}) {
                moved_any |= revert(static_cast<std::size_t>(v));
            }
        }
        m_stats.response_ms += response.elapsed_ms();
        if (!moved_any) {
            // Every vertex of every remaining hit is already at its start: a contact at the
            // frame's start itself (touching input). Nothing more a revert can do.
            break;
        }
    }
    m_stats.enforce_ms += watch.elapsed_ms();
}

}  // namespace pliant::cloth
