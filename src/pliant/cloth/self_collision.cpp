#include "pliant/cloth/self_collision.hpp"

#include <algorithm>
#include <cmath>

#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

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
    : m_candidates(triangles, num_vertices, thickness) {}

std::int64_t SelfCollision::project(std::span<Vec3d> positions,
                                    std::span<const Vec3d> previous_positions,
                                    std::span<const double> inverse_masses,
                                    const ClothMaterial& material, double time, double h) {
    m_stats.contacts = 0;
    if (!m_candidates.has_paths() || positions.size() != m_candidates.num_vertices()) {
        return 0;
    }
    Stopwatch watch;
    const std::size_t num_vertices = m_candidates.num_vertices();
    const double thickness = m_candidates.thickness();
    const double filter_margin = m_candidates.filter_margin();
    const std::span<Candidate> candidates = m_candidates.candidates();
    // A pair's features, weights (closest points' barycentric weights, + first feature, −
    // second), normal and distance in a configuration.
    struct Proximity {
        std::int32_t vertices[4];
        double weights[4];
        Vec3d normal;
        double distance;
    };
    const auto proximity = [&](const auto& c, std::span<const Vec3d> x) {
        const auto at = [&](int k) {
            return x[static_cast<std::size_t>(c.vertices[k])];
        };
        Proximity p{{c.vertices[0], c.vertices[1], c.vertices[2], c.vertices[3]}, {}, {}, 0.0};
        if (c.is_edge_edge == 0) {
            const collision::PointTriangleProximity<double> q =
                collision::point_triangle_proximity(at(0), at(1), at(2), at(3));
            p.weights[0] = 1.0;
            p.weights[1] = -q.barycentric.x;
            p.weights[2] = -q.barycentric.y;
            p.weights[3] = -q.barycentric.z;
            p.normal = q.normal;
            p.distance = q.distance;
        } else {
            const collision::SegmentSegmentProximity<double> q =
                collision::segment_segment_proximity(at(0), at(1), at(2), at(3));
            p.weights[0] = 1.0 - q.s;
            p.weights[1] = q.s;
            p.weights[2] = -(1.0 - q.t);
            p.weights[3] = -q.t;
            p.normal = q.normal;
            p.distance = q.distance;
        }
        return p;
    };
    // The contact: the closest points now and their normal, except for a pair that passed
    // through each other within the substep (the current closest points lie behind the side it
    // was on at the substep's start): it is pushed back along the start's normal (the current
    // normal would push it further through). Pairs touching at the start have no side to keep.
    const std::span<const Vec3d> current(positions);
    // contact() returns a pair's distance now when that is at least the thickness and beyond the
    // pair's relative sweep over the substep (a pair that passed through each other was at
    // distance 0 within the substep, so its distance now is at most that sweep); a lower bound
    // on the distance that passes this test proves the pair no contact.
    const auto beyond_contact = [&](double distance, const std::int32_t(&v)[4],
                                    std::size_t num_first) {
        return distance >= thickness &&
               distance > detail::relative_sweep(previous_positions, current, v, num_first);
    };
    const auto contact = [&](const auto& c, double* now_distance = nullptr) {
        Proximity now = proximity(c, current);
        if (now_distance != nullptr) {
            *now_distance = now.distance;
        }
        if (beyond_contact(now.distance, now.vertices, c.is_edge_edge != 0 ? 2 : 1)) {
            return now;
        }
        const Proximity start = proximity(c, previous_positions);
        if (start.distance > 1e-3 * thickness) {
            Vec3d gap{0.0, 0.0, 0.0};
            for (int k = 0; k < 4; ++k) {
                gap += current[static_cast<std::size_t>(now.vertices[k])] * now.weights[k];
            }
            const double along_start = dot(gap, start.normal);
            if (along_start < 0.0) {
                now.normal = start.normal;
                now.distance = along_start;
            }
        }
        return now;
    };
    // Candidates that are no contacts, decided on lower bounds of their distance now without the
    // exact proximity: their box gap or gap along the centroids' line, or the distance the last
    // call measured less their relative displacement since (features' distance is 1-Lipschitz
    // in max |Δ_i − Δ_j|), which skips pairs resting a little farther apart than the thickness.
    const std::int64_t call = m_project_calls++;
    const bool has_measured = m_measured_positions.size() == num_vertices;
    const std::span<const Vec3d> measured(m_measured_positions);
    const auto no_contact = [&](const Candidate& c) {
        const detail::FeatureVertices f = SelfCollisionCandidates::feature_vertices(c);
        if (beyond_contact(std::max(detail::pair_box_gap(f.v, f.num_first, current),
                                    detail::pair_centroid_axis_gap(f.v, f.num_first, current)) -
                               filter_margin,
                           f.v, f.num_first)) {
            return true;
        }
        return has_measured && c.measured_call == call - 1 &&
               beyond_contact(c.measured_distance -
                                  detail::relative_sweep(measured, current, f.v, f.num_first) -
                                  filter_margin,
                              f.v, f.num_first);
    };
    // Deviations over the straight substep are at most the larger of their values at its ends:
    // candidates whose bound stays at least the thickness over it are neither in contact nor
    // passed through, with no proximity test.
    const Vec3d shift_now = m_candidates.shift_of(current);
    const Vec3d shift_before = m_candidates.shift_of(previous_positions);
    const auto substep_deviation = [&](std::size_t v) {
        return std::max(m_candidates.deviation(previous_positions[v], shift_before, time - h, v),
                        m_candidates.deviation(current[v], shift_now, time, v));
    };
    // In parallel, the pairs closer than thickness (in pair order); then, sequentially, push each
    // apart with its contact at the positions as they are by then. The deviations are computed
    // per vertex first when the candidates' vertices outnumber the vertices, else per use.
    const auto closer = [&](const auto& deviations) -> const std::vector<std::int64_t>& {
        return m_index_filter.where(
            static_cast<std::int64_t>(candidates.size()), [&](std::int64_t i) {
                Candidate& c = candidates[static_cast<std::size_t>(i)];
                if (!(SelfCollisionCandidates::bound(c, deviations, time) < thickness) ||
                    no_contact(c)) {
                    return false;
                }
                const bool touching = contact(c, &c.measured_distance).distance < thickness;
                c.measured_call = call;
                return touching;
            });
    };
    const bool per_vertex = 4 * candidates.size() > num_vertices;
    if (per_vertex) {
        m_deviations.resize(num_vertices);
        parallel_for(
            static_cast<std::int64_t>(num_vertices),
            [&](std::int64_t i) {
                const auto v = static_cast<std::size_t>(i);
                m_deviations[v] = substep_deviation(v);
            },
            detail::SELF_VERTEX_GRAIN);
    }
    const std::vector<std::int64_t>& close =
        per_vertex ? closer(std::span<const double>(m_deviations)) : closer(substep_deviation);
    m_measured_positions.assign(current.begin(), current.end());
    const double narrow_ms = watch.elapsed_ms();
    m_stats.narrow_ms += narrow_ms;
    std::int64_t contacts = 0;
    for (const std::int64_t i : close) {
        const Proximity p = contact(candidates[static_cast<std::size_t>(i)]);
        if (!(p.distance < thickness)) {
            continue;
        }
        const double gap = thickness - p.distance;
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

void SelfCollision::save_state(ByteWriter& out) const {
    m_candidates.save_state(out);
    m_fail_safe.save_state(out);
    out.put(m_project_calls);
    out.put_vector(m_measured_positions);
    out.put_vector(m_deviations);
}

void SelfCollision::load_state(ByteReader& in) {
    m_candidates.load_state(in);
    m_fail_safe.load_state(in);
    m_project_calls = in.get<std::int64_t>("self_collision.project_calls");
    in.get_vector("self_collision.measured_positions", m_measured_positions);
    in.get_vector("self_collision.deviations", m_deviations);
}

}  // namespace pliant::cloth
