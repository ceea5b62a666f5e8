#include "pliant/cloth/self_collision.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/cloth/detail/pair_bounds.hpp"
#include "pliant/collision/narrow_phase.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t PAIR_GRAIN = 512;
constexpr std::int64_t VERTEX_GRAIN = 4096;

// A vertex's slack around its path (× thickness): boxes grow by it, and a vertex that leaves it
// gets a new path. Smaller slacks give fewer candidates and more new paths (on the drape scene
// 0.1-0.3 cost about the same, 0.5 more).
constexpr double SLACK = 0.2;
// A path lasts until the vertex would have moved this far along it (× thickness), at least one
// window and at most MAX_PATH_WINDOWS: short paths keep the boxes small.
constexpr double PATH_LENGTH = 0.5;
constexpr int MAX_PATH_WINDOWS = 64;
// When more than this fraction of the vertices needs new paths or escapes at once, a full
// broad phase is cheaper than queries around each of them.
constexpr double FULL_FRACTION = 0.25;
// Memory guards: a broad phase that keeps more triangle pairs than this per triangle of the
// mesh, or returns more feature pairs, is an error (cloth that diverged, or layers packed far
// closer than their thickness), not gigabytes of pairs and candidates. The built-in scenes'
// worst broad phases: 14 triangle pairs and 23 feature pairs per triangle (the pile's impact).
// Small meshes may have every pair within reach (violent motion): below MIN_PAIR_BUDGET pairs
// (tens of MB) there is no limit.
constexpr std::int64_t MAX_TRIANGLE_PAIRS_PER_TRIANGLE = 64;
constexpr std::int64_t MAX_FEATURE_PAIRS_PER_TRIANGLE = 256;
constexpr std::int64_t MIN_PAIR_BUDGET = std::int64_t{1} << 22;

// The pair limits for a mesh of `triangles` triangles: per triangle, or MIN_PAIR_BUDGET in all.
std::int64_t pair_limit_per_triangle(std::int64_t per_triangle, std::int64_t triangles) {
    return std::max(per_triangle,
                    (MIN_PAIR_BUDGET + triangles - 1) / std::max<std::int64_t>(triangles, 1));
}

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

double component(const Vec3d& v, int axis) {
    return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}
double& component(Vec3d& v, int axis) {
    return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}

// The largest |coordinate| of x and y: the scale of the rounding margins.
double largest_coordinate(std::span<const Vec3d> x, std::span<const Vec3d> y) {
    return parallel_reduce(
        static_cast<std::int64_t>(x.size()), 0.0,
        [&](std::int64_t begin, std::int64_t end) {
            double m = 0.0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                m = std::max({m, std::abs(x[v].x), std::abs(x[v].y), std::abs(x[v].z),
                              std::abs(y[v].x), std::abs(y[v].y), std::abs(y[v].z)});
            }
            return m;
        },
        [](double a, double b) { return std::max(a, b); }, VERTEX_GRAIN);
}

// kernel<EDGE_EDGE>(value(v[0]), ..., value(v[3])) for the vertices v of a feature pair (first
// feature: num_first of them); value maps a vertex index to a Vec3d.
template <typename Value, typename Kernel>
inline double on_pair(const std::int32_t (&v)[4], std::size_t num_first, Value&& value,
                      Kernel&& kernel) {
    const Vec3d p0 = value(static_cast<std::size_t>(v[0]));
    const Vec3d p1 = value(static_cast<std::size_t>(v[1]));
    const Vec3d p2 = value(static_cast<std::size_t>(v[2]));
    const Vec3d p3 = value(static_cast<std::size_t>(v[3]));
    return num_first == 2 ? kernel.template operator()<true>(p0, p1, p2, p3)
                          : kernel.template operator()<false>(p0, p1, p2, p3);
}

double box_gap(const std::int32_t (&v)[4], std::size_t num_first, std::span<const Vec3d> x) {
    return on_pair(
        v, num_first, [&](std::size_t i) { return x[i]; },
        []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
            return detail::box_gap<EE>(a, b, c, d);
        });
}

double centroid_axis_gap(const std::int32_t (&v)[4], std::size_t num_first,
                         std::span<const Vec3d> x) {
    return on_pair(
        v, num_first, [&](std::size_t i) { return x[i]; },
        []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
            return detail::centroid_axis_gap<EE>(a, b, c, d);
        });
}

// The largest |d_i − d_j| over the pairs (i in the first feature, j in the second) of the
// vertices' values d = value(vertex): displacements or velocities.
template <typename Value>
double largest_difference(const std::int32_t (&v)[4], std::size_t num_first, Value&& value) {
    return on_pair(v, num_first, value,
                   []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
                       return detail::largest_pair_difference<EE>(a, b, c, d);
                   });
}

// The largest difference of the vertices' displacements Δ = end − start: for linear motion the
// features' distance never falls below their distance at the start minus this (nor, for any
// motion, their distance at the end below their distance at the start minus this).
double relative_sweep(std::span<const Vec3d> start, std::span<const Vec3d> end,
                      const std::int32_t (&v)[4], std::size_t num_first) {
    return largest_difference(v, num_first, [&](std::size_t i) { return end[i] - start[i]; });
}

}  // namespace

SelfCollision::SelfCollision(std::span<const geometry::Triangle> triangles,
                             std::size_t num_vertices, double thickness)
    : m_triangles(triangles.begin(), triangles.end()),
      m_num_vertices(num_vertices),
      m_thickness(thickness),
      m_broad_phase(triangles, num_vertices),
      m_edges(&m_broad_phase.topology().edges) {
    // Every pair is filtered further on exact distances: the float boxes are enough.
    m_broad_phase.set_exact(false);
    m_broad_phase.set_pair_limit(pair_limit_per_triangle(
        MAX_TRIANGLE_PAIRS_PER_TRIANGLE, static_cast<std::int64_t>(triangles.size())));
}

void SelfCollision::check_pair_limit(const collision::FeaturePairs& found) {
    const auto triangles = static_cast<std::int64_t>(m_triangles.size());
    const auto feature_pairs =
        static_cast<std::int64_t>(found.vertex_face.size() + found.edge_edge.size());
    if (m_broad_phase.pair_limit_exceeded() ||
        feature_pairs >
            pair_limit_per_triangle(MAX_FEATURE_PAIRS_PER_TRIANGLE, triangles) * triangles) {
        // Paths and candidates are half renewed: the next call starts over.
        m_has_gather = false;
        m_broad_phase_ready = false;
        m_candidates.clear();
        throw InvalidInput(fmt::format(
            "cloth self-collision: more than {} pairs of triangles or {} pairs of features per "
            "triangle within reach of each other (thickness {} m): the simulation diverged "
            "(substeps too long for the cloth: raise substeps) or layers of cloth are packed far "
            "closer than their thickness",
            MAX_TRIANGLE_PAIRS_PER_TRIANGLE, MAX_FEATURE_PAIRS_PER_TRIANGLE, m_thickness));
    }
}

inline SelfCollision::FeatureVertices SelfCollision::feature_vertices(
    const collision::FeaturePairs& pairs, std::int64_t i) const {
    FeatureVertices f{};
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    if (i < num_vf) {
        const collision::VertexFacePair& pair = pairs.vertex_face[static_cast<std::size_t>(i)];
        const geometry::Triangle& t = m_triangles[static_cast<std::size_t>(pair.face)];
        f.v[0] = pair.vertex;
        f.v[1] = t[0];
        f.v[2] = t[1];
        f.v[3] = t[2];
        f.num_first = 1;
    } else {
        const collision::EdgeEdgePair& pair = pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
        const geometry::Edge& a = (*m_edges)[static_cast<std::size_t>(pair.edge_a)];
        const geometry::Edge& b = (*m_edges)[static_cast<std::size_t>(pair.edge_b)];
        f.v[0] = a[0];
        f.v[1] = a[1];
        f.v[2] = b[0];
        f.v[3] = b[1];
        f.num_first = 2;
    }
    return f;
}

double SelfCollision::features_distance(const FeatureVertices& f, std::span<const Vec3d> x) {
    const auto at = [&](int k) {
        return x[static_cast<std::size_t>(f.v[k])];
    };
    if (f.num_first == 1) {
        return collision::point_triangle_proximity(at(0), at(1), at(2), at(3)).distance;
    }
    return collision::segment_segment_proximity(at(0), at(1), at(2), at(3)).distance;
}

bool SelfCollision::separation_exceeds(const FeatureVertices& f, std::span<const Vec3d> start,
                                       std::span<const Vec3d> motion, double threshold) {
    const double sweep =
        largest_difference(f.v, f.num_first, [&](std::size_t i) { return motion[i]; });
    if (box_gap(f.v, f.num_first, start) - sweep > threshold ||
        centroid_axis_gap(f.v, f.num_first, start) - sweep > threshold) {
        return true;
    }
    return features_distance(f, start) - sweep > threshold;
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

void SelfCollision::add_broad_phase_times(const collision::BroadPhaseStats& broad) {
    m_stats.refit_ms += broad.build_ms + broad.refit_ms;
    m_stats.traverse_ms += broad.traverse_ms + broad.features_ms;
}

Vec3d SelfCollision::median_of(std::span<const Vec3d> x, bool from_origin) const {
    // Componentwise median over the sample vertices (the lower middle for an even count).
    const std::size_t n = m_frame_samples.size();
    if (n == 0) {
        return {0.0, 0.0, 0.0};
    }
    std::vector<double>& values = m_median_scratch;
    values.resize(n);
    Vec3d median{};
    for (int axis = 0; axis < 3; ++axis) {
        for (std::size_t k = 0; k < n; ++k) {
            const Vec3d& p = x[static_cast<std::size_t>(m_frame_samples[k])];
            const double origin = from_origin ? component(m_frame_origin[k], axis) : 0.0;
            values[k] = component(p, axis) - origin;
        }
        const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
        std::nth_element(values.begin(), mid, values.end());
        component(median, axis) = *mid;
    }
    return median;
}

Vec3d SelfCollision::shift_of(std::span<const Vec3d> x) const {
    return median_of(x, true);
}

void SelfCollision::reset_frame(std::span<const Vec3d> x) {
    m_frame_samples.clear();
    for (std::size_t v = 0; v < m_num_vertices; v += FRAME_SAMPLE_STRIDE) {
        m_frame_samples.push_back(static_cast<std::int32_t>(v));
    }
    m_frame_origin.resize(m_frame_samples.size());
    for (std::size_t k = 0; k < m_frame_samples.size(); ++k) {
        m_frame_origin[k] = x[static_cast<std::size_t>(m_frame_samples[k])];
    }
}

bool SelfCollision::within_path(const Vec3d& x, const Vec3d& shift, double time, std::size_t v,
                                double margin) const {
    // For the CCD the boxes' half-thickness growth counts too: a vertex within slack + th/2 of
    // its path is inside its grown box, and pairs whose grown boxes do not overlap cannot touch.
    const double slop = 1e-6 * m_window_dt;
    return time >= m_anchor_times[v] - slop && time <= m_path_ends[v] + slop &&
           deviation(x, shift, time, v) <= m_slacks[v] + 0.5 * m_thickness - margin;
}

void SelfCollision::set_path(std::size_t v, const Vec3d& anchor, const Vec3d& velocity,
                             double time) {
    // As long as the path stays short (its box small), within [1, max_windows] windows.
    const double speed = norm(velocity);
    const double longest = MAX_PATH_WINDOWS * m_window_dt;
    const double length = PATH_LENGTH * m_thickness;
    const double duration =
        std::max(m_window_dt, speed * longest > length ? length / speed : longest);
    m_anchors[v] = anchor;
    m_path_velocities[v] = velocity;
    m_anchor_times[v] = time;
    m_path_ends[v] = time + duration;
    m_slacks[v] = SLACK * m_thickness;
    // The box of the path over [τ_v − slop, end + slop] grown by the slack (within_path allows
    // the slop for rounding of the times).
    const double slop = 1e-6 * m_window_dt;
    const Vec3d early = anchor - velocity * slop;
    const Vec3d late = anchor + velocity * (duration + slop);
    const Vec3d grow{m_slacks[v], m_slacks[v], m_slacks[v]};
    m_box_lo[v] = min(early, late) - grow;
    m_box_hi[v] = max(early, late) + grow;
}

void SelfCollision::add_candidates(const collision::FeaturePairs& pairs, std::span<const Vec3d> x,
                                   const Vec3d& shift, double time,
                                   std::span<const std::uint8_t> involving) {
    // Per vertex, what the filter reads of it, in one cache line: its position, its deviation
    // from its path at `time` (for the bounds), its path velocity and the time left on its path.
    m_filter_vertices.resize(m_num_vertices);
    parallel_for(
        static_cast<std::int64_t>(m_num_vertices),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_filter_vertices[v] = {x[v], deviation(x[v], shift, time, v), m_path_velocities[v],
                                    m_path_ends[v] - time};
        },
        VERTEX_GRAIN);
    const FilterVertex* vertices = m_filter_vertices.data();
    const std::span<const double> slacks(m_slacks);
    const double margin = 1e-9 * (1.0 + largest_coordinate(x, m_box_hi));
    const double keep_below = m_thickness + margin;
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const auto num_pairs = num_vf + static_cast<std::int64_t>(pairs.edge_edge.size());
    // Pair i becomes a candidate when its distance at x, less the most its features can approach
    // each other while every vertex stays within its slack until the first of their paths ends,
    // is below the thickness: the lower bounds first (boxes, the centroids' line), the exact
    // distance for the pairs they leave.
    // Inlined into the loops below: a call per pair cost about 4 % of the drape's CPU time.
    // clang-format off
    const auto filter = [&]<bool EDGE_EDGE>(std::int64_t i, AppendBuffer<Candidate>& out)
                            __attribute__((always_inline)) {
        // clang-format on
        const FeatureVertices f = feature_vertices(pairs, i);
        if (!involving.empty() && (involving[static_cast<std::size_t>(f.v[0])] |
                                   involving[static_cast<std::size_t>(f.v[1])] |
                                   involving[static_cast<std::size_t>(f.v[2])] |
                                   involving[static_cast<std::size_t>(f.v[3])]) == 0) {
            return;
        }
        const FilterVertex& a = vertices[f.v[0]];
        const FilterVertex& b = vertices[f.v[1]];
        const FilterVertex& c = vertices[f.v[2]];
        const FilterVertex& d = vertices[f.v[3]];
        const double remaining = std::min({a.remaining, b.remaining, c.remaining, d.remaining});
        const double spread = detail::largest_pair_difference<EDGE_EDGE>(a.velocity, b.velocity,
                                                                         c.velocity, d.velocity);
        const double offset =
            EDGE_EDGE ? std::max(a.deviation, b.deviation) + std::max(c.deviation, d.deviation)
                      : a.deviation + std::max({b.deviation, c.deviation, d.deviation});
        const double reach =
            offset + feature_sum(f, slacks) + spread * std::max(0.0, remaining) + margin;
        if (detail::box_gap<EDGE_EDGE>(a.x, b.x, c.x, d.x) - reach >= keep_below ||
            detail::centroid_axis_gap<EDGE_EDGE>(a.x, b.x, c.x, d.x) - reach >= keep_below) {
            return;
        }
        const double distance = features_distance(f, x);
        if (distance - reach >= keep_below) {
            return;
        }
        Candidate candidate{};
        if constexpr (EDGE_EDGE) {
            const collision::EdgeEdgePair& p =
                pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
            candidate.feature_a = p.edge_a;
            candidate.feature_b = p.edge_b;
            candidate.is_edge_edge = 1;
        } else {
            const collision::VertexFacePair& p = pairs.vertex_face[static_cast<std::size_t>(i)];
            candidate.feature_a = p.vertex;
            candidate.feature_b = p.face;
            candidate.is_edge_edge = 0;
        }
        for (int k = 0; k < 4; ++k) {
            candidate.vertices[k] = f.v[k];
        }
        candidate.distance = distance;
        candidate.offset = offset;
        candidate.spread = spread;
        candidate.time = time;
        out.push_back(candidate);
    };
    m_candidate_chunks.reset(num_chunks(num_pairs, PAIR_GRAIN));
    parallel_for_chunks(num_pairs, PAIR_GRAIN,
                        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
                            AppendBuffer<Candidate>& out = m_candidate_chunks.chunk(chunk);
                            const std::int64_t split = std::clamp(num_vf, begin, end);
                            for (std::int64_t i = begin; i < split; ++i) {
                                filter.template operator()<false>(i, out);
                            }
                            for (std::int64_t i = split; i < end; ++i) {
                                filter.template operator()<true>(i, out);
                            }
                        });
    // Appended in pair order (chunks merged in order): deterministic.
    const std::size_t old_size = m_candidates.size();
    std::vector<Candidate> added;
    m_candidate_chunks.gather(added);
    m_candidates.resize(old_size + added.size());
    std::copy(added.begin(), added.end(),
              m_candidates.begin() + static_cast<std::ptrdiff_t>(old_size));
}

void SelfCollision::compute_triangle_motions(double time) {
    // Per triangle: its vertices' path positions at `time` (frame coordinates), the box of their
    // path velocities, their largest slack and the time to the last path end.
    m_triangle_motions.resize(m_triangles.size());
    parallel_for(
        static_cast<std::int64_t>(m_triangles.size()),
        [&](std::int64_t t) {
            const geometry::Triangle& tri = m_triangles[static_cast<std::size_t>(t)];
            TriangleMotion m{};
            for (int k = 0; k < 3; ++k) {
                const auto v = static_cast<std::size_t>(tri[static_cast<std::size_t>(k)]);
                const Vec3d p = m_anchors[v] + m_path_velocities[v] * (time - m_anchor_times[v]);
                const Vec3d& u = m_path_velocities[v];
                m.p[k] = p;
                m.u_lo = k == 0 ? u : min(m.u_lo, u);
                m.u_hi = k == 0 ? u : max(m.u_hi, u);
                m.slack = std::max(m.slack, m_slacks[v]);
                m.duration = std::max(m.duration, m_path_ends[v] - time);
            }
            m_triangle_motions[static_cast<std::size_t>(t)] = m;
        },
        VERTEX_GRAIN);
}

bool SelfCollision::may_come_close(std::int32_t a, std::int32_t b) const {
    // Within [time, time + duration] each vertex is within its slack of its path, which moves
    // with its velocity: the triangles' distance is at least the gap between their path boxes
    // now, minus both slacks, minus the largest relative speed of their vertices times the
    // duration. Pairs for which that stays at least the thickness (plus the rounding margin)
    // need no feature tests: none of their features comes within the thickness.
    const TriangleMotion& p = m_triangle_motions[static_cast<std::size_t>(a)];
    const TriangleMotion& q = m_triangle_motions[static_cast<std::size_t>(b)];
    const Vec3d zero{0.0, 0.0, 0.0};
    const Vec3d speed = max(max(p.u_hi - q.u_lo, q.u_hi - p.u_lo), zero);
    const double reach = p.slack + q.slack + norm(speed) * std::max(p.duration, q.duration);
    const double keep_below = m_thickness + m_filter_margin;
    // The same with the gap along the line through the triangles' centroids (a separating axis:
    // the speed box's norm bounds the relative speed along it too).
    return !(detail::box_gap(p.p, q.p) - reach >= keep_below ||
             detail::centroid_axis_gap(p.p, q.p) - reach >= keep_below);
}

void SelfCollision::gather(std::span<const Vec3d> x, std::span<const Vec3d> u, double time,
                           double window_dt) {
    Stopwatch watch;
    const std::size_t n = m_num_vertices;
    m_window_dt = window_dt;
    reset_frame(x);
    m_anchors.resize(n);
    m_path_velocities.resize(n);
    m_anchor_times.resize(n);
    m_path_ends.resize(n);
    m_slacks.resize(n);
    m_box_lo.resize(n);
    m_box_hi.resize(n);
    m_needs_path.assign(n, 0);
    parallel_for(
        static_cast<std::int64_t>(n),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            set_path(v, x[v], u[v], time);
        },
        VERTEX_GRAIN);
    m_inflation = 0.5 * m_thickness;
    compute_triangle_motions(time);
    m_filter_margin = 1e-9 * (1.0 + largest_coordinate(x, m_box_hi));
    const auto close = [this](std::int32_t a, std::int32_t b) {
        return may_come_close(a, b);
    };
    const collision::SelfCollisionBroadPhase<double>::TrianglePairFilter keep(close);
    const collision::FeaturePairs& pairs = m_broad_phase.update(
        std::span<const Vec3d>(m_box_lo), std::span<const Vec3d>(m_box_hi), m_inflation, &keep);
    check_pair_limit(pairs);
    m_broad_phase_ready = true;
    add_broad_phase_times(m_broad_phase.stats());
    ++m_stats.gathers;
    Stopwatch filter;
    m_candidates.clear();
    add_candidates(pairs, x, Vec3d{0.0, 0.0, 0.0}, time, {});
    m_stats.narrow_ms += filter.elapsed_ms();
    m_has_gather = true;
    m_stats.candidate_pairs = static_cast<std::int64_t>(m_candidates.size());
    m_stats.gather_ms += watch.elapsed_ms();
}

void SelfCollision::renew_paths(std::span<const Vec3d> x, const Vec3d& shift,
                                std::span<const Vec3d> u, double time) {
    if (m_new_path_vertices.empty()) {
        return;
    }
    Stopwatch watch;
    m_marks.assign(m_num_vertices, 0);
    for (const std::int32_t v : m_new_path_vertices) {
        const auto k = static_cast<std::size_t>(v);
        m_marks[k] = 1;
        m_needs_path[k] = 0;
        set_path(k, x[k] - shift, u[k], time);
    }
    // Drop the old candidates of the renewed vertices (their bounds assumed the old paths).
    const std::vector<std::int64_t>& kept =
        indices_where(static_cast<std::int64_t>(m_candidates.size()), [&](std::int64_t i) {
            const Candidate& c = m_candidates[static_cast<std::size_t>(i)];
            return (m_marks[static_cast<std::size_t>(c.vertices[0])] |
                    m_marks[static_cast<std::size_t>(c.vertices[1])] |
                    m_marks[static_cast<std::size_t>(c.vertices[2])] |
                    m_marks[static_cast<std::size_t>(c.vertices[3])]) == 0;
        });
    m_scratch_candidates.resize(kept.size());
    for (std::size_t k = 0; k < kept.size(); ++k) {
        m_scratch_candidates[k] = m_candidates[static_cast<std::size_t>(kept[k])];
    }
    std::swap(m_candidates, m_scratch_candidates);
    // The pairs that involve a renewed vertex: a partial broad phase, or for many vertices a
    // full one (cheaper then) of which only those pairs are kept.
    const collision::FeaturePairs* found = nullptr;
    const std::span<const Vec3d> lo(m_box_lo);
    const std::span<const Vec3d> hi(m_box_hi);
    const bool full = static_cast<double>(m_new_path_vertices.size()) >
                      FULL_FRACTION * static_cast<double>(m_num_vertices);
    compute_triangle_motions(time);
    m_filter_margin = 1e-9 * (1.0 + largest_coordinate(x, m_box_hi));
    const auto close = [this](std::int32_t a, std::int32_t b) {
        return may_come_close(a, b);
    };
    const collision::SelfCollisionBroadPhase<double>::TrianglePairFilter keep(close);
    if (full || m_inflation != 0.5 * m_thickness) {
        m_inflation = 0.5 * m_thickness;
        found = &m_broad_phase.update(lo, hi, m_inflation, &keep);
        ++m_stats.gathers;
    } else {
        found = &m_broad_phase.update_vertices(lo, hi, m_inflation, m_new_path_vertices, &keep);
        ++m_stats.path_updates;
    }
    check_pair_limit(*found);
    add_broad_phase_times(m_broad_phase.stats());
    m_stats.new_paths += static_cast<std::int64_t>(m_new_path_vertices.size());
    Stopwatch filter;
    add_candidates(*found, x, shift, time, m_marks);
    m_stats.narrow_ms += filter.elapsed_ms();
    m_stats.candidate_pairs = static_cast<std::int64_t>(m_candidates.size());
    m_stats.gather_ms += watch.elapsed_ms();
}

int SelfCollision::windows_for_next_gather() {
    // Hysteresis on the candidate count (drape, 18,225 vertices: 1-12k candidates while draped
    // with two windows, 35-300k at the impact, where one window is 1.3-2.5x cheaper).
    const auto candidates = static_cast<double>(m_candidates.size());
    const auto vertices = static_cast<double>(m_num_vertices);
    m_dense_contact = m_dense_contact ? candidates > vertices / 8.0 : candidates > vertices;
    return m_dense_contact ? 1 : 2;
}

void SelfCollision::prepare(std::span<const Vec3d> positions, std::span<const Vec3d> velocities,
                            double time, double window_dt) {
    const Vec3d mean_velocity = median_of(velocities, false);
    m_new_velocities.resize(m_num_vertices);
    parallel_for(
        static_cast<std::int64_t>(m_num_vertices),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_new_velocities[v] = velocities[v] - mean_velocity;
        },
        VERTEX_GRAIN);
    const std::span<const Vec3d> u(m_new_velocities);
    if (!m_has_gather) {
        gather(positions, u, time, window_dt);
        return;
    }
    // A different window length (windows_for_next_gather, or another step length) needs no full
    // gather: the paths that end within the window are renewed below.
    m_window_dt = window_dt;
    // New paths for the vertices that escaped in the last window, whose path ends within this
    // one or that are predicted to leave their slack in it (their deviation grows at most by
    // their velocity's difference from the path's, over the window).
    const Vec3d shift = shift_of(positions);
    const double end = time + window_dt * (1.0 - 1e-6);
    m_new_path_vertices.clear();
    for (std::size_t v = 0; v < m_num_vertices; ++v) {
        const double growth = norm(m_new_velocities[v] - m_path_velocities[v]) * window_dt;
        if (m_needs_path[v] != 0 || m_path_ends[v] < end || time < m_anchor_times[v] ||
            deviation(positions[v], shift, time, v) + growth > m_slacks[v]) {
            m_new_path_vertices.push_back(static_cast<std::int32_t>(v));
        }
    }
    renew_paths(positions, shift, u, time);
}

std::int64_t SelfCollision::project(std::span<Vec3d> positions,
                                    std::span<const Vec3d> previous_positions,
                                    std::span<const double> inverse_masses,
                                    const ClothMaterial& material, double time, double h) {
    m_stats.contacts = 0;
    if (!m_has_gather || positions.size() != m_num_vertices) {
        return 0;
    }
    Stopwatch watch;
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
        return distance >= m_thickness &&
               distance > relative_sweep(previous_positions, current, v, num_first);
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
    // Candidates that are no contacts, decided on lower bounds of their distance now without the
    // exact proximity: their box gap or gap along the centroids' line, or the distance the last
    // call measured less their relative displacement since (features' distance is 1-Lipschitz
    // in max |Δ_i − Δ_j|), which skips pairs resting a little farther apart than the thickness.
    const std::int64_t call = m_project_calls++;
    const bool has_measured = m_measured_positions.size() == m_num_vertices;
    const std::span<const Vec3d> measured(m_measured_positions);
    const auto no_contact = [&](const Candidate& c) {
        const FeatureVertices f = feature_vertices(c);
        if (beyond_contact(std::max(box_gap(f.v, f.num_first, current),
                                    centroid_axis_gap(f.v, f.num_first, current)) -
                               m_filter_margin,
                           f.v, f.num_first)) {
            return true;
        }
        return has_measured && c.measured_call == call - 1 &&
               beyond_contact(c.measured_distance -
                                  relative_sweep(measured, current, f.v, f.num_first) -
                                  m_filter_margin,
                              f.v, f.num_first);
    };
    // Deviations over the straight substep are at most the larger of their values at its ends:
    // candidates whose bound stays at least the thickness over it are neither in contact nor
    // passed through, with no proximity test.
    const Vec3d shift_now = shift_of(current);
    const Vec3d shift_before = shift_of(previous_positions);
    const auto substep_deviation = [&](std::size_t v) {
        return std::max(deviation(previous_positions[v], shift_before, time - h, v),
                        deviation(current[v], shift_now, time, v));
    };
    // In parallel, the pairs closer than thickness (in pair order); then, sequentially, push each
    // apart with its contact at the positions as they are by then. The deviations are computed
    // per vertex first when the candidates' vertices outnumber the vertices, else per use.
    const auto closer = [&](const auto& deviations) -> const std::vector<std::int64_t>& {
        return indices_where(static_cast<std::int64_t>(m_candidates.size()), [&](std::int64_t i) {
            Candidate& c = m_candidates[static_cast<std::size_t>(i)];
            if (!(bound(c, deviations, time) < m_thickness) || no_contact(c)) {
                return false;
            }
            const bool touching = contact(c, &c.measured_distance).distance < m_thickness;
            c.measured_call = call;
            return touching;
        });
    };
    const bool per_vertex = 4 * m_candidates.size() > m_num_vertices;
    if (per_vertex) {
        m_deviations.resize(m_num_vertices);
        parallel_for(
            static_cast<std::int64_t>(m_num_vertices),
            [&](std::int64_t i) {
                const auto v = static_cast<std::size_t>(i);
                m_deviations[v] = substep_deviation(v);
            },
            VERTEX_GRAIN);
    }
    const std::vector<std::int64_t>& close =
        per_vertex ? closer(std::span<const double>(m_deviations)) : closer(substep_deviation);
    m_measured_positions.assign(current.begin(), current.end());
    const double narrow_ms = watch.elapsed_ms();
    m_stats.narrow_ms += narrow_ms;
    std::int64_t contacts = 0;
    for (const std::int64_t i : close) {
        const Proximity p = contact(m_candidates[static_cast<std::size_t>(i)]);
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

void SelfCollision::search_escaped(std::span<const Vec3d> positions_t0,
                                   std::span<const Vec3d> positions, const Vec3d& shift_t0,
                                   const Vec3d& shift, double margin) {
    if (m_escaped_now.empty()) {
        return;
    }
    // Many escaped (or no broad phase yet): every vertex is searched on its motion over the
    // window, with boxes grown by the rounding margin only (as thin as the CCD allows; the next
    // step 1 gathers again with the half-thickness growth).
    const bool all =
        !m_broad_phase_ready || static_cast<double>(m_escaped_now.size()) >
                                    FULL_FRACTION * static_cast<double>(m_num_vertices);
    if (all) {
        m_escaped_now.resize(m_num_vertices);
        for (std::size_t v = 0; v < m_num_vertices; ++v) {
            m_escaped_now[v] = static_cast<std::int32_t>(v);
        }
        m_escape_pairs.vertex_face.clear();
        m_escape_pairs.edge_edge.clear();
    }
    // Boxes around each escaped vertex's motion over the window in the frame: from x_t0 − s_t0
    // to x − s (for a vertex put back, x = x_t0).
    for (const std::int32_t v : m_escaped_now) {
        const auto k = static_cast<std::size_t>(v);
        const Vec3d a = positions_t0[k] - shift_t0;
        const Vec3d b = positions[k] - shift;
        m_box_lo[k] = min(a, b);
        m_box_hi[k] = max(a, b);
        m_escaped[k] = 1;
        m_needs_path[k] = 1;
    }
    const std::span<const Vec3d> lo(m_box_lo);
    const std::span<const Vec3d> hi(m_box_hi);
    const collision::FeaturePairs* found = nullptr;
    if (all) {
        m_inflation = margin;
        found = &m_broad_phase.update(lo, hi, m_inflation);
        m_broad_phase_ready = true;
        ++m_stats.gathers;
    } else {
        found = &m_broad_phase.update_vertices(lo, hi, m_inflation, m_escaped_now);
        ++m_stats.path_updates;
    }
    check_pair_limit(*found);
    add_broad_phase_times(m_broad_phase.stats());
    // The pairs that involve an escaped vertex (the others are the candidates' business).
    Stopwatch stage;
    const collision::FeaturePairs& pairs = *found;
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const std::vector<std::int64_t>& kept = indices_where(
        num_vf + static_cast<std::int64_t>(pairs.edge_edge.size()), [&](std::int64_t i) {
            const FeatureVertices f = feature_vertices(pairs, i);
            return (m_escaped[static_cast<std::size_t>(f.v[0])] |
                    m_escaped[static_cast<std::size_t>(f.v[1])] |
                    m_escaped[static_cast<std::size_t>(f.v[2])] |
                    m_escaped[static_cast<std::size_t>(f.v[3])]) != 0;
        });
    for (const std::int64_t i : kept) {
        if (i < num_vf) {
            m_escape_pairs.vertex_face.push_back(pairs.vertex_face[static_cast<std::size_t>(i)]);
        } else {
            m_escape_pairs.edge_edge.push_back(
                pairs.edge_edge[static_cast<std::size_t>(i - num_vf)]);
        }
    }
    m_stats.new_paths += static_cast<std::int64_t>(m_escaped_now.size());
    m_stats.narrow_ms += stage.elapsed_ms();
}

void SelfCollision::enforce(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                            std::span<Vec3d> velocities, double time_t0, double time) {
    Stopwatch watch;
    const std::span<const Vec3d> end(positions);
    const std::size_t n = m_num_vertices;
    // Rounding margin: pairs are cleared only when they provably stay this far apart.
    const double margin = 1e-9 * (1.0 + largest_coordinate(positions_t0, end));
    if (!m_has_gather) {
        // Without paths (no step 1): every vertex's motion is searched.
        reset_frame(positions_t0);
        m_box_lo.resize(n);
        m_box_hi.resize(n);
        m_needs_path.assign(n, 1);
        m_candidates.clear();
    }
    const Vec3d shift_t0 = shift_of(positions_t0);
    const Vec3d shift = shift_of(end);
    // Escaped: vertices whose motion over the window is not within their path's slack (or that
    // have no path). Their pairs are searched on their actual motion; the others' motion lies
    // within their slacks (convex: the deviation along the straight motion, the frame's
    // translation interpolated, is at most the larger of its ends'), so inside their boxes.
    Stopwatch stage;
    m_escaped.assign(n, 0);
    m_escape_pairs.vertex_face.clear();
    m_escape_pairs.edge_edge.clear();
    m_deviations.resize(n);
    const std::vector<std::int64_t>& escaped =
        indices_where(static_cast<std::int64_t>(n), [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            const bool out = !m_has_gather || m_needs_path[v] != 0 ||
                             !within_path(positions_t0[v], shift_t0, time_t0, v, margin) ||
                             !within_path(end[v], shift, time, v, margin);
            m_deviations[v] = out ? 0.0
                                  : std::max(deviation(positions_t0[v], shift_t0, time_t0, v),
                                             deviation(end[v], shift, time, v));
            return out;
        });
    m_escaped_now.resize(escaped.size());
    std::transform(escaped.begin(), escaped.end(), m_escaped_now.begin(),
                   [](std::int64_t v) { return static_cast<std::int32_t>(v); });
    m_stats.narrow_ms += stage.elapsed_ms();
    search_escaped(positions_t0, end, shift_t0, shift, margin);
    // Pairs that are not candidates and involve no escaped vertex stay thickness apart; a
    // candidate can only touch when its bound over the window is not above the margin and
    // neither is its start distance minus its relative sweep.
    run_fail_safe(positions_t0, positions, velocities, shift_t0, shift, time, margin);
    m_stats.candidate_pairs = static_cast<std::int64_t>(m_candidates.size());
    m_stats.enforce_ms += watch.elapsed_ms();
}

void SelfCollision::run_fail_safe(std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                                  std::span<Vec3d> velocities, const Vec3d& shift_t0,
                                  const Vec3d& shift, double time, double margin) {
    const auto& edges = *m_edges;
    const std::span<const Vec3d> end(positions);
    m_reverted.assign(m_num_vertices, 0);
    m_changed.assign(m_num_vertices, 0);
    // Each vertex's motion over the window (zero once put back).
    m_window_motion.resize(m_num_vertices);
    parallel_for(
        static_cast<std::int64_t>(m_num_vertices),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_window_motion[v] = end[v] - positions_t0[v];
        },
        VERTEX_GRAIN);
    const std::span<const Vec3d> motion(m_window_motion);
    // Puts v back at its start with zero velocity; true when that moved it.
    const auto revert = [&](std::size_t v) {
        m_stats.reverted_vertices += m_reverted[v] == 0 ? 1 : 0;
        m_reverted[v] = 1;
        if (positions[v] == positions_t0[v]) {
            return false;
        }
        positions[v] = positions_t0[v];
        velocities[v] = {0.0, 0.0, 0.0};
        m_window_motion[v] = {0.0, 0.0, 0.0};
        m_changed[v] = 1;
        return true;
    };
    const auto marked = [](std::span<const std::uint8_t> marks, const FeatureVertices& f) {
        return (marks[static_cast<std::size_t>(f.v[0])] | marks[static_cast<std::size_t>(f.v[1])] |
                marks[static_cast<std::size_t>(f.v[2])] |
                marks[static_cast<std::size_t>(f.v[3])]) != 0;
    };
    // The pairs that may touch, as feature pairs for the CCD: candidates without an escaped
    // vertex whose bound allows it, and pairs of escaped vertices; both only when the start
    // distance minus the relative sweep allows it too. With only_changed, just the pairs with a
    // vertex put back in the last round (the others were cleared on the same motion).
    collision::FeaturePairs active;
    const auto collect = [&](bool only_changed) {
        active.vertex_face.clear();
        active.edge_edge.clear();
        const std::vector<std::int64_t>& from_candidates =
            indices_where(static_cast<std::int64_t>(m_candidates.size()), [&](std::int64_t i) {
                const Candidate& c = m_candidates[static_cast<std::size_t>(i)];
                const FeatureVertices f = feature_vertices(c);
                return !marked(m_escaped, f) && (!only_changed || marked(m_changed, f)) &&
                       bound(c, m_deviations, time) <= margin &&
                       !separation_exceeds(f, positions_t0, motion, margin);
            });
        for (const std::int64_t i : from_candidates) {
            const Candidate& c = m_candidates[static_cast<std::size_t>(i)];
            if (c.is_edge_edge == 0) {
                active.vertex_face.push_back({c.feature_a, c.feature_b});
            } else {
                active.edge_edge.push_back({c.feature_a, c.feature_b});
            }
        }
        const collision::FeaturePairs& pairs = m_escape_pairs;
        const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
        const std::vector<std::int64_t>& from_escaped = indices_where(
            num_vf + static_cast<std::int64_t>(pairs.edge_edge.size()), [&](std::int64_t i) {
                const FeatureVertices f = feature_vertices(pairs, i);
                return (!only_changed || marked(m_changed, f)) &&
                       !separation_exceeds(f, positions_t0, motion, margin);
            });
        for (const std::int64_t i : from_escaped) {
            if (i < num_vf) {
                active.vertex_face.push_back(pairs.vertex_face[static_cast<std::size_t>(i)]);
            } else {
                active.edge_edge.push_back(pairs.edge_edge[static_cast<std::size_t>(i - num_vf)]);
            }
        }
    };
    Stopwatch stage;
    collect(false);
    m_stats.narrow_ms += stage.elapsed_ms();
    for (int round = 0;; ++round) {
        m_stats.enforce_rounds = std::max(m_stats.enforce_rounds, round + 1);
        stage.restart();
        const collision::NarrowPhaseResult narrow = collision::continuous_narrow_phase(
            positions_t0, end, std::span<const geometry::Triangle>(m_triangles),
            std::span<const geometry::Edge>(edges), active);
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
            // window's start itself (touching input). Nothing more a revert can do.
            m_stats.response_ms += stage.elapsed_ms();
            break;
        }
        // A vertex put back stands still: in the frame it moves from x_t0 − s(τ_t0) to
        // x_t0 − s(τ). An escaped one's box holds that already; another that leaves its slack
        // so escapes now, and its pairs are searched.
        m_escaped_now.clear();
        const double grow = m_inflation - margin;
        for (std::size_t v = 0; v < m_num_vertices; ++v) {
            if (m_changed[v] == 0) {
                continue;
            }
            if (m_escaped[v] != 0) {
                // Its box holds its start; it must hold the end it now has as well.
                const Vec3d p = end[v] - shift;
                const Vec3d& lo = m_box_lo[v];
                const Vec3d& hi = m_box_hi[v];
                if (!(p.x >= lo.x - grow && p.y >= lo.y - grow && p.z >= lo.z - grow &&
                      p.x <= hi.x + grow && p.y <= hi.y + grow && p.z <= hi.z + grow)) {
                    m_escaped_now.push_back(static_cast<std::int32_t>(v));
                }
                continue;
            }
            if (within_path(end[v], shift, time, v, margin)) {
                m_deviations[v] = std::max(m_deviations[v], deviation(end[v], shift, time, v));
            } else {
                m_escaped_now.push_back(static_cast<std::int32_t>(v));
            }
        }
        search_escaped(positions_t0, end, shift_t0, shift, margin);
        collect(true);
        std::fill(m_changed.begin(), m_changed.end(), std::uint8_t{0});
        m_stats.response_ms += stage.elapsed_ms();
    }
}

}  // namespace pliant::cloth
