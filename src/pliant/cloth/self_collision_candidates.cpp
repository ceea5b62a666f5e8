#include "pliant/cloth/self_collision_candidates.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/cloth/detail/pair_bounds.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

// A vertex's slack around its path (× thickness): boxes grow by it, and a vertex that leaves it
// gets a new path. Smaller slacks give fewer candidates and more new paths.
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

double component(const Vec3d& v, int axis) {
    return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}
double& component(Vec3d& v, int axis) {
    return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}

}  // namespace

SelfCollisionCandidates::SelfCollisionCandidates(std::span<const geometry::Triangle> triangles,
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

void SelfCollisionCandidates::check_pair_limit(const collision::FeaturePairs& found) {
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

void SelfCollisionCandidates::add_broad_phase_times(SelfCollisionStats& stats) const {
    const collision::BroadPhaseStats& broad = m_broad_phase.stats();
    stats.refit_ms += broad.build_ms + broad.refit_ms;
    stats.traverse_ms += broad.traverse_ms + broad.features_ms;
}

Vec3d SelfCollisionCandidates::median_of(std::span<const Vec3d> x, bool from_origin) const {
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

Vec3d SelfCollisionCandidates::shift_of(std::span<const Vec3d> x) const {
    return median_of(x, true);
}

void SelfCollisionCandidates::reset_frame(std::span<const Vec3d> x) {
    m_frame_samples.clear();
    for (std::size_t v = 0; v < m_num_vertices; v += FRAME_SAMPLE_STRIDE) {
        m_frame_samples.push_back(static_cast<std::int32_t>(v));
    }
    m_frame_origin.resize(m_frame_samples.size());
    for (std::size_t k = 0; k < m_frame_samples.size(); ++k) {
        m_frame_origin[k] = x[static_cast<std::size_t>(m_frame_samples[k])];
    }
}

bool SelfCollisionCandidates::within_path(const Vec3d& x, const Vec3d& shift, double time,
                                          std::size_t v, double margin) const {
    // For the CCD the boxes' half-thickness growth counts too: a vertex within slack + th/2 of
    // its path is inside its grown box, and pairs whose grown boxes do not overlap cannot touch.
    const double slop = 1e-6 * m_window_dt;
    return time >= m_anchor_times[v] - slop && time <= m_path_ends[v] + slop &&
           deviation(x, shift, time, v) <= m_slacks[v] + 0.5 * m_thickness - margin;
}

void SelfCollisionCandidates::set_path(std::size_t v, const Vec3d& anchor, const Vec3d& velocity,
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

void SelfCollisionCandidates::add_candidates(const collision::FeaturePairs& pairs,
                                             std::span<const Vec3d> x, const Vec3d& shift,
                                             double time, std::span<const std::uint8_t> involving) {
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
        detail::SELF_VERTEX_GRAIN);
    const FilterVertex* vertices = m_filter_vertices.data();
    const std::span<const double> slacks(m_slacks);
    const double margin = 1e-9 * (1.0 + detail::largest_coordinate(x, m_box_hi));
    const double keep_below = m_thickness + margin;
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const auto num_pairs = num_vf + static_cast<std::int64_t>(pairs.edge_edge.size());
    // Pair i becomes a candidate when its distance at x, less the most its features can approach
    // each other while every vertex stays within its slack until the first of their paths ends,
    // is below the thickness: the lower bounds first (boxes, the centroids' line), the exact
    // distance for the pairs they leave.
    // Inlined into the loops below (always_inline): it runs once per broad-phase pair.
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
        const double distance = detail::features_distance(f, x);
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
    m_candidate_chunks.reset(num_chunks(num_pairs, detail::PAIR_GRAIN));
    parallel_for_chunks(num_pairs, detail::PAIR_GRAIN,
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

void SelfCollisionCandidates::compute_triangle_motions(double time) {
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
        detail::SELF_VERTEX_GRAIN);
}

bool SelfCollisionCandidates::may_come_close(std::int32_t a, std::int32_t b) const {
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

void SelfCollisionCandidates::gather(std::span<const Vec3d> x, std::span<const Vec3d> u,
                                     double time, double window_dt, SelfCollisionStats& stats) {
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
        detail::SELF_VERTEX_GRAIN);
    m_inflation = 0.5 * m_thickness;
    compute_triangle_motions(time);
    m_filter_margin = 1e-9 * (1.0 + detail::largest_coordinate(x, m_box_hi));
    const auto close = [this](std::int32_t a, std::int32_t b) {
        return may_come_close(a, b);
    };
    const collision::SelfCollisionBroadPhase<double>::TrianglePairFilter keep(close);
    const collision::FeaturePairs& pairs = m_broad_phase.update(
        std::span<const Vec3d>(m_box_lo), std::span<const Vec3d>(m_box_hi), m_inflation, &keep);
    check_pair_limit(pairs);
    m_broad_phase_ready = true;
    add_broad_phase_times(stats);
    ++stats.gathers;
    Stopwatch filter;
    m_candidates.clear();
    add_candidates(pairs, x, Vec3d{0.0, 0.0, 0.0}, time, {});
    stats.narrow_ms += filter.elapsed_ms();
    m_has_gather = true;
    stats.candidate_pairs = static_cast<std::int64_t>(m_candidates.size());
    stats.gather_ms += watch.elapsed_ms();
}

void SelfCollisionCandidates::renew_paths(std::span<const Vec3d> x, const Vec3d& shift,
                                          std::span<const Vec3d> u, double time,
                                          SelfCollisionStats& stats) {
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
        m_index_filter.where(static_cast<std::int64_t>(m_candidates.size()), [&](std::int64_t i) {
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
    m_filter_margin = 1e-9 * (1.0 + detail::largest_coordinate(x, m_box_hi));
    const auto close = [this](std::int32_t a, std::int32_t b) {
        return may_come_close(a, b);
    };
    const collision::SelfCollisionBroadPhase<double>::TrianglePairFilter keep(close);
    if (full || m_inflation != 0.5 * m_thickness) {
        m_inflation = 0.5 * m_thickness;
        found = &m_broad_phase.update(lo, hi, m_inflation, &keep);
        ++stats.gathers;
    } else {
        found = &m_broad_phase.update_vertices(lo, hi, m_inflation, m_new_path_vertices, &keep);
        ++stats.path_updates;
    }
    check_pair_limit(*found);
    add_broad_phase_times(stats);
    stats.new_paths += static_cast<std::int64_t>(m_new_path_vertices.size());
    Stopwatch filter;
    add_candidates(*found, x, shift, time, m_marks);
    stats.narrow_ms += filter.elapsed_ms();
    stats.candidate_pairs = static_cast<std::int64_t>(m_candidates.size());
    stats.gather_ms += watch.elapsed_ms();
}

int SelfCollisionCandidates::windows_for_next_gather() {
    // Hysteresis on the candidate count: a draped sheet has fewer candidates than vertices, an
    // impact many times more (docs/journal/2026-11-24-self-collision-gather-two-windows.md).
    const auto candidates = static_cast<double>(m_candidates.size());
    const auto vertices = static_cast<double>(m_num_vertices);
    m_dense_contact = m_dense_contact ? candidates > vertices / 8.0 : candidates > vertices;
    return m_dense_contact ? 1 : 2;
}

void SelfCollisionCandidates::prepare(std::span<const Vec3d> positions,
                                      std::span<const Vec3d> velocities, double time,
                                      double window_dt, SelfCollisionStats& stats) {
    const Vec3d mean_velocity = median_of(velocities, false);
    m_new_velocities.resize(m_num_vertices);
    parallel_for(
        static_cast<std::int64_t>(m_num_vertices),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_new_velocities[v] = velocities[v] - mean_velocity;
        },
        detail::SELF_VERTEX_GRAIN);
    const std::span<const Vec3d> u(m_new_velocities);
    if (!m_has_gather) {
        gather(positions, u, time, window_dt, stats);
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
    renew_paths(positions, shift, u, time, stats);
}

void SelfCollisionCandidates::start_without_paths(std::span<const Vec3d> x) {
    reset_frame(x);
    m_box_lo.resize(m_num_vertices);
    m_box_hi.resize(m_num_vertices);
    m_needs_path.assign(m_num_vertices, 1);
    m_candidates.clear();
}

bool SelfCollisionCandidates::box_holds(std::size_t v, const Vec3d& p, double margin) const {
    const double grow = m_inflation - margin;
    const Vec3d& lo = m_box_lo[v];
    const Vec3d& hi = m_box_hi[v];
    return p.x >= lo.x - grow && p.y >= lo.y - grow && p.z >= lo.z - grow && p.x <= hi.x + grow &&
           p.y <= hi.y + grow && p.z <= hi.z + grow;
}

bool SelfCollisionCandidates::full_search_pays(std::size_t count) const {
    return !m_broad_phase_ready ||
           static_cast<double>(count) > FULL_FRACTION * static_cast<double>(m_num_vertices);
}

const collision::FeaturePairs& SelfCollisionCandidates::search_motions(
    std::span<const std::int32_t> vertices, bool full, std::span<const Vec3d> positions_t0,
    std::span<const Vec3d> positions, const Vec3d& shift_t0, const Vec3d& shift, double margin,
    SelfCollisionStats& stats) {
    // Boxes around each vertex's motion over the window in the frame: from x_t0 − s_t0 to x − s
    // (for a vertex put back, x = x_t0).
    for (const std::int32_t v : vertices) {
        const auto k = static_cast<std::size_t>(v);
        const Vec3d a = positions_t0[k] - shift_t0;
        const Vec3d b = positions[k] - shift;
        m_box_lo[k] = min(a, b);
        m_box_hi[k] = max(a, b);
        m_needs_path[k] = 1;
    }
    const std::span<const Vec3d> lo(m_box_lo);
    const std::span<const Vec3d> hi(m_box_hi);
    const collision::FeaturePairs* found = nullptr;
    if (full) {
        m_inflation = margin;
        found = &m_broad_phase.update(lo, hi, m_inflation);
        m_broad_phase_ready = true;
        ++stats.gathers;
    } else {
        found = &m_broad_phase.update_vertices(lo, hi, m_inflation, vertices);
        ++stats.path_updates;
    }
    check_pair_limit(*found);
    add_broad_phase_times(stats);
    return *found;
}

void SelfCollisionCandidates::save_state(ByteWriter& out) const {
    m_broad_phase.save_state(out);
    out.put(m_has_gather);
    out.put(m_dense_contact);
    out.put(m_broad_phase_ready);
    out.put(m_inflation);
    out.put(m_window_dt);
    out.put_vector(m_frame_samples);
    out.put_vector(m_frame_origin);
    out.put_vector(m_anchors);
    out.put_vector(m_path_velocities);
    out.put_vector(m_anchor_times);
    out.put_vector(m_path_ends);
    out.put_vector(m_slacks);
    out.put_vector(m_box_lo);
    out.put_vector(m_box_hi);
    out.put_vector(m_needs_path);
    out.put(m_filter_margin);
    out.put_vector(m_candidates);
    out.put_vector(m_new_path_vertices);
}

void SelfCollisionCandidates::load_state(ByteReader& in) {
    m_broad_phase.load_state(in);
    m_has_gather = in.get_bool("candidates.has_gather");
    m_dense_contact = in.get_bool("candidates.dense_contact");
    m_broad_phase_ready = in.get_bool("candidates.broad_phase_ready");
    m_inflation = in.get<double>("candidates.inflation");
    m_window_dt = in.get<double>("candidates.window_dt");
    const auto n = static_cast<std::int64_t>(m_num_vertices);
    in.get_vector("candidates.frame_samples", m_frame_samples);
    for (const std::int32_t v : m_frame_samples) {
        if (v < 0 || v >= n) {
            throw InvalidInput(fmt::format("{}: candidates: frame sample {} of {} vertices",
                                           in.source(), v, m_num_vertices));
        }
    }
    in.get_vector("candidates.frame_origin", m_frame_origin,
                  static_cast<std::int64_t>(m_frame_samples.size()));
    // Per vertex, or empty where no prepare() ran yet (a fail-safe without paths fills some).
    const auto per_vertex = [&](const char* field, auto& values) {
        in.get_vector(field, values);
        if (!values.empty() && static_cast<std::int64_t>(values.size()) != n) {
            throw InvalidInput(fmt::format("{}: {}: expected {} elements, got {}", in.source(),
                                           field, n, values.size()));
        }
    };
    per_vertex("candidates.anchors", m_anchors);
    per_vertex("candidates.path_velocities", m_path_velocities);
    per_vertex("candidates.anchor_times", m_anchor_times);
    per_vertex("candidates.path_ends", m_path_ends);
    per_vertex("candidates.slacks", m_slacks);
    per_vertex("candidates.box_lo", m_box_lo);
    per_vertex("candidates.box_hi", m_box_hi);
    per_vertex("candidates.needs_path", m_needs_path);
    if (m_has_gather && (m_anchors.empty() || m_path_velocities.empty() || m_anchor_times.empty() ||
                         m_path_ends.empty() || m_slacks.empty() || m_box_lo.empty() ||
                         m_box_hi.empty() || m_needs_path.empty())) {
        throw InvalidInput(
            fmt::format("{}: candidates: paths without per-vertex state", in.source()));
    }
    m_filter_margin = in.get<double>("candidates.filter_margin");
    in.get_vector("candidates.candidates", m_candidates);
    for (const Candidate& c : m_candidates) {
        for (const std::int32_t v : c.vertices) {
            if (v < 0 || v >= n) {
                throw InvalidInput(
                    fmt::format("{}: candidates: vertex {} of {}", in.source(), v, m_num_vertices));
            }
        }
    }
    in.get_vector("candidates.new_path_vertices", m_new_path_vertices);
}

}  // namespace pliant::cloth
