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

// Mean of end[v] − start[v]: a translation common to the whole cloth. Distances are the same in
// a frame moving with it, so broad phases sweep boxes by the motion relative to it (a falling
// sheet then sweeps nothing). Parallel sums in fixed chunks: the same for any thread count.
Vec3d mean_displacement(std::span<const Vec3d> start, std::span<const Vec3d> end) {
    if (start.empty()) {
        return {0.0, 0.0, 0.0};
    }
    const Vec3d sum = parallel_reduce(
        static_cast<std::int64_t>(start.size()), Vec3d{0.0, 0.0, 0.0},
        [&](std::int64_t begin, std::int64_t finish) {
            Vec3d partial{0.0, 0.0, 0.0};
            for (std::int64_t i = begin; i < finish; ++i) {
                partial += end[static_cast<std::size_t>(i)] - start[static_cast<std::size_t>(i)];
            }
            return partial;
        },
        [](Vec3d a, const Vec3d& b) { return a + b; }, 4096);
    return sum * (1.0 / static_cast<double>(start.size()));
}

// end − shift, per vertex.
void shifted(std::span<const Vec3d> end, const Vec3d& shift, std::vector<Vec3d>& out) {
    out.resize(end.size());
    parallel_for(static_cast<std::int64_t>(end.size()), [&](std::int64_t i) {
        out[static_cast<std::size_t>(i)] = end[static_cast<std::size_t>(i)] - shift;
    });
}

// The largest |Δ_i − Δ_j| over the pairs (i in the first feature, j in the second) of the
// vertices' displacements Δ = end − start: for linear motion the features' distance never falls
// below their distance at the start minus this.
double relative_sweep(std::span<const Vec3d> start, std::span<const Vec3d> end,
                      std::span<const std::int32_t> first, std::span<const std::int32_t> second) {
    double sweep = 0.0;
    for (const std::int32_t i : first) {
        const Vec3d di = end[static_cast<std::size_t>(i)] - start[static_cast<std::size_t>(i)];
        for (const std::int32_t j : second) {
            const Vec3d dj = end[static_cast<std::size_t>(j)] - start[static_cast<std::size_t>(j)];
            sweep = std::max(sweep, squared_norm(di - dj));
        }
    }
    return std::sqrt(sweep);
}

// The distance between the boxes of two vertex sets: a lower bound on the distance between any
// points of their convex hulls (0 when the boxes overlap).
double box_distance(std::span<const Vec3d> x, std::span<const std::int32_t> first,
                    std::span<const std::int32_t> second) {
    const auto box_of = [&](std::span<const std::int32_t> vertices) {
        AABBd box;
        for (const std::int32_t v : vertices) {
            box.extend(x[static_cast<std::size_t>(v)]);
        }
        return box;
    };
    const AABBd a = box_of(first);
    const AABBd b = box_of(second);
    const Vec3d gap = max(max(a.lo - b.hi, b.lo - a.hi), Vec3d{0.0, 0.0, 0.0});
    return norm(gap);
}

}  // namespace

bool SelfCollision::separation_exceeds(const collision::FeaturePairs& pairs, std::int64_t i,
                                       std::span<const Vec3d> start, std::span<const Vec3d> end,
                                       double threshold, double* distance) const {
    // The features' vertices; the cheap bound (box distance minus sweep) first.
    std::int32_t first[1];
    std::span<const std::int32_t> a;
    std::span<const std::int32_t> b;
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    if (i < num_vf) {
        const collision::VertexFacePair& pair = pairs.vertex_face[static_cast<std::size_t>(i)];
        first[0] = pair.vertex;
        a = first;
        b = m_triangles[static_cast<std::size_t>(pair.face)];
    } else {
        const auto& edges = m_gather_phase.topology().edges;
        const collision::EdgeEdgePair& pair = pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
        a = edges[static_cast<std::size_t>(pair.edge_a)];
        b = edges[static_cast<std::size_t>(pair.edge_b)];
    }
    const double sweep = relative_sweep(start, end, a, b);
    if (box_distance(start, a, b) - sweep > threshold) {
        return true;
    }
    const double exact = pair_distance(pairs, i, start);
    if (distance != nullptr) {
        *distance = exact;
    }
    return exact - sweep > threshold;
}

double SelfCollision::pair_distance(const collision::FeaturePairs& pairs, std::int64_t i,
                                    std::span<const Vec3d> x) const {
    const auto at = [&](std::int32_t v) {
        return x[static_cast<std::size_t>(v)];
    };
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    if (i < num_vf) {
        const collision::VertexFacePair& pair = pairs.vertex_face[static_cast<std::size_t>(i)];
        const geometry::Triangle& f = m_triangles[static_cast<std::size_t>(pair.face)];
        return collision::point_triangle_proximity(at(pair.vertex), at(f[0]), at(f[1]), at(f[2]))
            .distance;
    }
    const auto& edges = m_gather_phase.topology().edges;
    const collision::EdgeEdgePair& pair = pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
    const geometry::Edge& a = edges[static_cast<std::size_t>(pair.edge_a)];
    const geometry::Edge& b = edges[static_cast<std::size_t>(pair.edge_b)];
    return collision::segment_segment_proximity(at(a[0]), at(a[1]), at(b[0]), at(b[1])).distance;
}

template <typename Keep>
const std::vector<std::int64_t>& SelfCollision::indices_where(std::int64_t n, Keep&& keep) {
    m_index_chunks.reset(num_chunks(n, PAIR_GRAIN));
    parallel_for_chunks(n, PAIR_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
        AppendBuffer<std::int64_t>& out = m_index_chunks.chunk(c);
        for (std::int64_t i = begin; i < end; ++i) {
            if (keep(i)) {
                out.push_back(i);
            }
        }
    });
    m_index_chunks.gather(m_indices);
    return m_indices;
}

template <typename Keep>
collision::FeaturePairs SelfCollision::filter_pairs(const collision::FeaturePairs& pairs,
                                                    Keep&& keep) {
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const auto num_ee = static_cast<std::int64_t>(pairs.edge_edge.size());
    // Indices in pair order (VF then EE), from fixed chunks merged in order: deterministic.
    const std::vector<std::int64_t>& kept = indices_where(num_vf + num_ee, keep);
    collision::FeaturePairs result;
    for (const std::int64_t i : kept) {
        if (i < num_vf) {
            result.vertex_face.push_back(pairs.vertex_face[static_cast<std::size_t>(i)]);
        } else {
            result.edge_edge.push_back(pairs.edge_edge[static_cast<std::size_t>(i - num_vf)]);
        }
    }
    return result;
}

SelfCollision::SelfCollision(std::span<const geometry::Triangle> triangles,
                             std::size_t num_vertices, double thickness)
    : m_triangles(triangles.begin(), triangles.end()),
      m_thickness(thickness),
      m_gather_phase(triangles, num_vertices),
      m_swept_phase(triangles, num_vertices),
      m_revert_phase(triangles, num_vertices) {}

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
    // Boxes swept by the motion relative to the cloth's mean motion (the same pairs come close).
    m_gather_shift = mean_displacement(positions, m_predicted);
    shifted(m_predicted, m_gather_shift, m_gather_end);
    const collision::FeaturePairs& swept =
        m_gather_phase.update(positions, std::span<const Vec3d>(m_gather_end), 0.5 * m_thickness);
    add_broad_phase_times(m_gather_phase.stats());
    // Keep the pairs whose distance can fall below thickness + slack on the predicted motion
    // (slack = thickness, for the difference between prediction and the solved motion; pairs
    // that come closer anyway are the fail-safe's).
    // The filter computes a kept pair's distance now (by index, no races); project() skips a pair
    // while that distance minus how far its vertices have since moved stays at least the
    // thickness.
    Stopwatch filter;
    const std::span<const Vec3d> predicted(m_predicted);
    m_swept_distances.resize(swept.vertex_face.size() + swept.edge_edge.size());
    m_candidates = filter_pairs(swept, [&](std::int64_t i) {
        return !separation_exceeds(swept, i, positions, predicted, 2.0 * m_thickness,
                                   &m_swept_distances[static_cast<std::size_t>(i)]);
    });
    // filter_pairs leaves the kept indices, in the candidates' order, in m_indices.
    const auto num_candidates = static_cast<std::int64_t>(m_indices.size());
    m_gather_distances.resize(m_indices.size());
    for (std::size_t k = 0; k < m_indices.size(); ++k) {
        m_gather_distances[k] = m_swept_distances[static_cast<std::size_t>(m_indices[k])];
    }
    m_gather_positions.assign(positions.begin(), positions.end());
    m_pair_sweeps.assign(static_cast<std::size_t>(num_candidates), 0.0);
    m_stats.narrow_ms += filter.elapsed_ms();
    m_stats.candidate_pairs = num_candidates;
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
    const collision::FeaturePairs& candidates = m_candidates;
    const auto& edges = m_gather_phase.topology().edges;
    const auto num_vf = static_cast<std::int64_t>(candidates.vertex_face.size());
    const auto num_ee = static_cast<std::int64_t>(candidates.edge_edge.size());
    // A pair's features, weights (closest points' barycentric weights, + first feature, −
    // second), normal and distance in a configuration.
    struct Proximity {
        std::int32_t vertices[4];
        double weights[4];
        Vec3d normal;
        double distance;
    };
    const auto proximity = [&](std::int64_t i, std::span<const Vec3d> x) {
        const auto at = [&](std::int32_t v) {
            return x[static_cast<std::size_t>(v)];
        };
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
    // The contact: the closest points now and their normal, except for a pair that passed
    // through each other within the substep (the current closest points lie behind the side it
    // was on at the substep's start): it is pushed back along the start's normal (the current
    // normal would push it further through). Pairs touching at the start have no side to keep.
    const std::span<const Vec3d> current(positions);
    const auto contact = [&](std::int64_t i) {
        Proximity now = proximity(i, current);
        // A pair that passed through each other was at distance 0 within the substep, so its
        // distance now is at most its relative sweep over the substep.
        const std::size_t first = i < num_vf ? 1 : 2;  // VF: the vertex; EE: edge a
        if (now.distance >= m_thickness &&
            now.distance >
                relative_sweep(previous_positions, current,
                               std::span<const std::int32_t>(now.vertices, first),
                               std::span<const std::int32_t>(now.vertices + first, 4 - first))) {
            return now;
        }
        const Proximity start = proximity(i, previous_positions);
        if (start.distance > 1e-3 * m_thickness) {
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
    // A pair's distance cannot have fallen below its distance at the gather minus the largest
    // relative displacement since then of a vertex of one feature and a vertex of the other
    // (straight substeps: the largest over the window so far is at a substep's end, so a running
    // maximum per pair). Pairs for which that stays at least the thickness are neither in contact
    // nor passed through: no proximity test.
    const std::span<const Vec3d> gathered(m_gather_positions);
    const auto far_apart = [&](std::int64_t i) {
        double sweep = 0.0;
        if (i < num_vf) {
            const collision::VertexFacePair& pair =
                candidates.vertex_face[static_cast<std::size_t>(i)];
            const std::int32_t vertex[1] = {pair.vertex};
            sweep = relative_sweep(gathered, current, vertex,
                                   m_triangles[static_cast<std::size_t>(pair.face)]);
        } else {
            const collision::EdgeEdgePair& pair =
                candidates.edge_edge[static_cast<std::size_t>(i - num_vf)];
            sweep = relative_sweep(gathered, current, edges[static_cast<std::size_t>(pair.edge_a)],
                                   edges[static_cast<std::size_t>(pair.edge_b)]);
        }
        double& largest = m_pair_sweeps[static_cast<std::size_t>(i)];
        largest = std::max(largest, sweep);
        return m_gather_distances[static_cast<std::size_t>(i)] - largest >= m_thickness;
    };
    // In parallel, the pairs closer than thickness (in pair order); then, sequentially, push each
    // apart with its contact at the positions as they are by then.
    const std::vector<std::int64_t>& close = indices_where(num_vf + num_ee, [&](std::int64_t i) {
        return !far_apart(i) && contact(i).distance < m_thickness;
    });
    const double narrow_ms = watch.elapsed_ms();
    m_stats.narrow_ms += narrow_ms;
    std::int64_t contacts = 0;
    for (const std::int64_t i : close) {
        const Proximity p = contact(i);
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
    std::vector<std::uint8_t> reverted(positions.size(), 0);
    std::vector<std::uint8_t> changed(positions.size(), 0);  // moved back in this round
    // Puts v back at its start with zero velocity; true when that moved it.
    const auto revert = [&](std::size_t v) {
        m_stats.reverted_vertices += reverted[v] == 0 ? 1 : 0;
        reverted[v] = 1;
        if (positions[v] == positions_t0[v]) {
            return false;
        }
        positions[v] = positions_t0[v];
        velocities[v] = {0.0, 0.0, 0.0};
        changed[v] = 1;
        return true;
    };
    // Round 0: every pair that can touch during the step, from boxes swept by the motion relative
    // to the mean motion (the same pairs; boxes grown by `margin` against the rounding of the
    // shift).
    const double extent = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), 0.0,
        [&](std::int64_t begin, std::int64_t end) {
            double m = 0.0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                m = std::max({m, std::abs(positions[v].x), std::abs(positions[v].y),
                              std::abs(positions[v].z), std::abs(positions_t0[v].x),
                              std::abs(positions_t0[v].y), std::abs(positions_t0[v].z)});
            }
            return m;
        },
        [](double a, double b) { return std::max(a, b); }, 4096);
    const double margin = 1e-9 * (1.0 + extent);
    const collision::FeaturePairs* all_pairs = nullptr;
    if (gather_boxes_hold(positions_t0, positions, margin)) {
        // Every vertex ended inside its box of the gather (which starts at positions_t0): its
        // motion lies in that box, so the gather's broad-phase pairs hold every pair that can
        // touch (no second broad phase).
        all_pairs = &m_gather_phase.pairs();
    } else {
        shifted(positions, mean_displacement(positions_t0, positions), m_relative_end);
        all_pairs =
            &m_swept_phase.update(positions_t0, std::span<const Vec3d>(m_relative_end), margin);
        add_broad_phase_times(m_swept_phase.stats());
    }
    // Pairs whose distance provably stays above `margin` (start distance minus relative sweep)
    // cannot touch: the CCD runs on the rest.
    Stopwatch stage;
    const auto may_touch = [&](const collision::FeaturePairs& pairs, std::int64_t i) {
        return !separation_exceeds(pairs, i, positions_t0, positions, margin);
    };
    collision::FeaturePairs active =
        filter_pairs(*all_pairs, [&](std::int64_t i) { return may_touch(*all_pairs, i); });
    m_stats.narrow_ms += stage.elapsed_ms();
    const collision::FeaturePairs* pairs = &active;
    for (int round = 0;; ++round) {
        m_stats.enforce_rounds = std::max(m_stats.enforce_rounds, round + 1);
        stage.restart();
        const collision::NarrowPhaseResult narrow =
            collision::continuous_narrow_phase(positions_t0, std::span<const Vec3d>(positions),
                                               std::span<const geometry::Triangle>(m_triangles),
                                               std::span<const geometry::Edge>(edges), *pairs);
        m_stats.narrow_ms += stage.elapsed_ms();
        if (round == 0) {
            m_stats.ccd_hits += narrow.vf_hits + narrow.ee_hits;
        }
        if (narrow.vf_hits + narrow.ee_hits == 0) {
            break;
        }
        // The vertices of every pair the CCD cannot clear, in pair order (deterministic).
        stage.restart();
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
        if (!moved_any) {
            // Every vertex of every remaining hit is already at its start: a contact at the
            // frame's start itself (touching input). Nothing more a revert can do.
            m_stats.response_ms += stage.elapsed_ms();
            break;
        }
        if (round == 0) {
            // A vertex put back stands still, which in the frame of the mean motion is a motion
            // outside its relative box: from now on, boxes swept in world space from the start to
            // the positions after this round's reverts. Later reverts shrink a motion to a point
            // inside such a box, so this broad phase holds every pair until the end.
            all_pairs =
                &m_revert_phase.update(positions_t0, std::span<const Vec3d>(positions), margin);
            add_broad_phase_times(m_revert_phase.stats());
        }
        // Only pairs with a vertex moved back in this round can have changed their verdict: the
        // others were cleared on the same motion.
        active = filter_pairs(*all_pairs, [&](std::int64_t i) {
            return touches(*all_pairs, i, changed) && may_touch(*all_pairs, i);
        });
        for (std::size_t v = 0; v < changed.size(); ++v) {
            changed[v] = 0;
        }
        pairs = &active;
        m_stats.response_ms += stage.elapsed_ms();
    }
    m_stats.enforce_ms += watch.elapsed_ms();
}

bool SelfCollision::gather_boxes_hold(std::span<const Vec3d> positions_t0,
                                      std::span<const Vec3d> positions, double margin) const {
    const double grow = 0.5 * m_thickness - margin;  // the gather's inflation, less rounding
    if (!(grow >= 0.0) || m_gather_positions.size() != positions.size() ||
        m_gather_end.size() != positions.size()) {
        return false;
    }
    const std::int64_t outside = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                // The gather's boxes start where this motion starts, in the gather's frame.
                const Vec3d& start = m_gather_positions[v];
                const Vec3d lo = min(start, m_gather_end[v]);
                const Vec3d hi = max(start, m_gather_end[v]);
                const Vec3d a = positions[v] - m_gather_shift;
                const bool same_start = positions_t0[v] == start;
                const bool inside = a.x >= lo.x - grow && a.y >= lo.y - grow &&
                                    a.z >= lo.z - grow && a.x <= hi.x + grow &&
                                    a.y <= hi.y + grow && a.z <= hi.z + grow;
                count += same_start && inside ? 0 : 1;
            }
            return count;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, 4096);
    return outside == 0;
}

bool SelfCollision::touches(const collision::FeaturePairs& pairs, std::int64_t i,
                            std::span<const std::uint8_t> marked) const {
    const auto is_marked = [&](std::int32_t v) {
        return marked[static_cast<std::size_t>(v)] != 0;
    };
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    if (i < num_vf) {
        const collision::VertexFacePair& p = pairs.vertex_face[static_cast<std::size_t>(i)];
        const geometry::Triangle& f = m_triangles[static_cast<std::size_t>(p.face)];
        return is_marked(p.vertex) || is_marked(f[0]) || is_marked(f[1]) || is_marked(f[2]);
    }
    const auto& edges = m_swept_phase.topology().edges;
    const collision::EdgeEdgePair& p = pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
    const geometry::Edge& a = edges[static_cast<std::size_t>(p.edge_a)];
    const geometry::Edge& b = edges[static_cast<std::size_t>(p.edge_b)];
    return is_marked(a[0]) || is_marked(a[1]) || is_marked(b[0]) || is_marked(b[1]);
}

}  // namespace pliant::cloth
