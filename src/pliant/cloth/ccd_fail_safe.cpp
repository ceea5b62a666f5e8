#include "pliant/cloth/ccd_fail_safe.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "pliant/collision/ccd.hpp"
#include "pliant/collision/narrow_phase.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {

bool CCDFailSafe::separation_exceeds(const FeatureVertices& f, std::span<const Vec3d> start,
                                     std::span<const Vec3d> motion, double threshold) {
    const double sweep =
        detail::pair_largest_difference(f.v, f.num_first, [&](std::size_t i) { return motion[i]; });
    if (detail::pair_box_gap(f.v, f.num_first, start) - sweep > threshold ||
        detail::pair_centroid_axis_gap(f.v, f.num_first, start) - sweep > threshold) {
        return true;
    }
    return detail::features_distance(f, start) - sweep > threshold;
}

collision::NarrowPhaseResult CCDFailSafe::test_within_budget(
    const SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
    std::span<const Vec3d> positions, const collision::FeaturePairs& pairs, std::int64_t budget,
    std::int64_t& ccd_hits) {
    // The `budget` pairs whose fastest vertex moves farthest go to the CCD (ties: pair order):
    // freezing a slow vertex loses little motion, and the fast ones (a jumping pin's
    // neighbours) keep moving where their pairs are clear. The others are hits.
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const auto num_pairs = num_vf + static_cast<std::int64_t>(pairs.edge_edge.size());
    m_pair_motion.resize(static_cast<std::size_t>(num_pairs));
    parallel_for(
        num_pairs,
        [&](std::int64_t i) {
            const FeatureVertices f = candidates.feature_vertices(pairs, i);
            double fastest = 0.0;
            for (const std::int32_t v : f.v) {
                const auto u = static_cast<std::size_t>(v);
                fastest = std::max(fastest, squared_norm(positions[u] - positions_t0[u]));
            }
            m_pair_motion[static_cast<std::size_t>(i)] = fastest;
        },
        detail::SELF_VERTEX_GRAIN);
    m_pair_order.resize(static_cast<std::size_t>(num_pairs));
    for (std::int64_t i = 0; i < num_pairs; ++i) {
        m_pair_order[static_cast<std::size_t>(i)] = i;
    }
    const auto faster = [&](std::int64_t a, std::int64_t b) {
        const double ma = m_pair_motion[static_cast<std::size_t>(a)];
        const double mb = m_pair_motion[static_cast<std::size_t>(b)];
        return ma > mb || (ma == mb && a < b);
    };
    std::nth_element(m_pair_order.begin(), m_pair_order.begin() + budget, m_pair_order.end(),
                     faster);
    std::sort(m_pair_order.begin(), m_pair_order.begin() + budget);
    std::sort(m_pair_order.begin() + budget, m_pair_order.end());
    collision::FeaturePairs& tested = m_tested;
    tested.vertex_face.clear();
    tested.edge_edge.clear();
    const auto add = [&](collision::FeaturePairs& to, std::int64_t i) {
        if (i < num_vf) {
            to.vertex_face.push_back(pairs.vertex_face[static_cast<std::size_t>(i)]);
        } else {
            to.edge_edge.push_back(pairs.edge_edge[static_cast<std::size_t>(i - num_vf)]);
        }
    };
    for (std::int64_t k = 0; k < budget; ++k) {
        add(tested, m_pair_order[static_cast<std::size_t>(k)]);
    }
    collision::NarrowPhaseResult narrow = collision::continuous_narrow_phase(
        positions_t0, positions, candidates.triangles(), candidates.edges(), tested);
    ccd_hits = narrow.vf_hits + narrow.ee_hits;
    for (std::int64_t k = budget; k < num_pairs; ++k) {
        add(narrow.hits, m_pair_order[static_cast<std::size_t>(k)]);
    }
    narrow.vf_hits = static_cast<std::int64_t>(narrow.hits.vertex_face.size());
    narrow.ee_hits = static_cast<std::int64_t>(narrow.hits.edge_edge.size());
    return narrow;
}

void CCDFailSafe::search_escaped(SelfCollisionCandidates& candidates,
                                 std::span<const Vec3d> positions_t0,
                                 std::span<const Vec3d> positions, const Vec3d& shift_t0,
                                 const Vec3d& shift, double margin, SelfCollisionStats& stats) {
    if (m_escaped_now.empty()) {
        return;
    }
    // Many escaped (or no broad phase yet): every vertex is searched on its motion over the
    // window, with boxes grown by the rounding margin only (as thin as the CCD allows; the next
    // prepare() gathers again with the half-thickness growth).
    const std::size_t n = candidates.num_vertices();
    const bool all = candidates.full_search_pays(m_escaped_now.size());
    if (all) {
        m_escaped_now.resize(n);
        for (std::size_t v = 0; v < n; ++v) {
            m_escaped_now[v] = static_cast<std::int32_t>(v);
        }
        m_escape_pairs.vertex_face.clear();
        m_escape_pairs.edge_edge.clear();
    }
    for (const std::int32_t v : m_escaped_now) {
        m_escaped[static_cast<std::size_t>(v)] = 1;
    }
    const collision::FeaturePairs& pairs = candidates.search_motions(
        m_escaped_now, all, positions_t0, positions, shift_t0, shift, margin, stats);
    // The pairs that involve an escaped vertex (the others are the candidates' business).
    Stopwatch stage;
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const std::vector<std::int64_t>& kept = m_index_filter.where(
        num_vf + static_cast<std::int64_t>(pairs.edge_edge.size()), [&](std::int64_t i) {
            const FeatureVertices f = candidates.feature_vertices(pairs, i);
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
    stats.new_paths += static_cast<std::int64_t>(m_escaped_now.size());
    stats.narrow_ms += stage.elapsed_ms();
}

void CCDFailSafe::enforce(SelfCollisionCandidates& candidates, std::span<const Vec3d> positions_t0,
                          std::span<Vec3d> positions, std::span<Vec3d> velocities, double time_t0,
                          double time, SelfCollisionStats& stats) {
    Stopwatch watch;
    const std::span<const Vec3d> end(positions);
    const std::size_t n = candidates.num_vertices();
    // Rounding margin: pairs are cleared only when they provably stay this far apart.
    const double margin = 1e-9 * (1.0 + detail::largest_coordinate(positions_t0, end));
    const bool has_paths = candidates.has_paths();
    if (!has_paths) {
        // Without paths (no prepare()): every vertex's motion is searched.
        candidates.start_without_paths(positions_t0);
    }
    const Vec3d shift_t0 = candidates.shift_of(positions_t0);
    const Vec3d shift = candidates.shift_of(end);
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
        m_index_filter.where(static_cast<std::int64_t>(n), [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            const bool out =
                !has_paths || candidates.needs_path(v) ||
                !candidates.within_path(positions_t0[v], shift_t0, time_t0, v, margin) ||
                !candidates.within_path(end[v], shift, time, v, margin);
            m_deviations[v] =
                out ? 0.0
                    : std::max(candidates.deviation(positions_t0[v], shift_t0, time_t0, v),
                               candidates.deviation(end[v], shift, time, v));
            return out;
        });
    m_escaped_now.resize(escaped.size());
    std::transform(escaped.begin(), escaped.end(), m_escaped_now.begin(),
                   [](std::int64_t v) { return static_cast<std::int32_t>(v); });
    stats.narrow_ms += stage.elapsed_ms();
    search_escaped(candidates, positions_t0, end, shift_t0, shift, margin, stats);
    // Pairs that are not candidates and involve no escaped vertex stay thickness apart; a
    // candidate can only touch when its bound over the window is not above the margin and
    // neither is its start distance minus its relative sweep.
    run_rounds(candidates, positions_t0, positions, velocities, shift_t0, shift, time, margin,
               stats);
    stats.candidate_pairs = static_cast<std::int64_t>(candidates.candidates().size());
    stats.enforce_ms += watch.elapsed_ms();
}

void CCDFailSafe::run_rounds(SelfCollisionCandidates& candidates,
                             std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                             std::span<Vec3d> velocities, const Vec3d& shift_t0, const Vec3d& shift,
                             double time, double margin, SelfCollisionStats& stats) {
    const std::size_t n = candidates.num_vertices();
    const std::span<const geometry::Triangle> triangles = candidates.triangles();
    const std::span<const geometry::Edge> edges = candidates.edges();
    const std::span<const SelfCollisionCandidates::Candidate> pairs_to_check =
        candidates.candidates();
    const std::span<const Vec3d> end(positions);
    // Each vertex's motion over the window (zero once put back).
    const std::span<const Vec3d> motion = begin_window(positions_t0, end);
    bool over_budget = false;  // this window's pair budget is spent (set by the rounds below)
    // Puts v back at its start with zero velocity; true when that moved it.
    const auto revert = [&](std::size_t v) {
        stats.reverted_vertices += m_reverted[v] == 0 ? 1 : 0;
        stats.frozen_vertices += m_reverted[v] == 0 && over_budget ? 1 : 0;
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
        const std::vector<std::int64_t>& from_candidates = m_index_filter.where(
            static_cast<std::int64_t>(pairs_to_check.size()), [&](std::int64_t i) {
                const SelfCollisionCandidates::Candidate& c =
                    pairs_to_check[static_cast<std::size_t>(i)];
                const FeatureVertices f = SelfCollisionCandidates::feature_vertices(c);
                return !marked(m_escaped, f) && (!only_changed || marked(m_changed, f)) &&
                       SelfCollisionCandidates::bound(c, m_deviations, time) <= margin &&
                       !separation_exceeds(f, positions_t0, motion, margin);
            });
        for (const std::int64_t i : from_candidates) {
            const SelfCollisionCandidates::Candidate& c =
                pairs_to_check[static_cast<std::size_t>(i)];
            if (c.is_edge_edge == 0) {
                active.vertex_face.push_back({c.feature_a, c.feature_b});
            } else {
                active.edge_edge.push_back({c.feature_a, c.feature_b});
            }
        }
        const collision::FeaturePairs& pairs = m_escape_pairs;
        const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
        const std::vector<std::int64_t>& from_escaped = m_index_filter.where(
            num_vf + static_cast<std::int64_t>(pairs.edge_edge.size()), [&](std::int64_t i) {
                const FeatureVertices f = candidates.feature_vertices(pairs, i);
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
    stats.narrow_ms += stage.elapsed_ms();
    // Pair tests left in this window's budget; once spent, every pair that may touch is a hit.
    // Unbounded when the rounding margin exceeds the thickness: the cloth has diverged (its
    // coordinates are beyond what the exact tests resolve) and holding it back would hide that
    // from the caller's divergence check.
    std::int64_t budget_left =
        margin < candidates.thickness() ? pair_budget(n) : std::numeric_limits<std::int64_t>::max();
    for (int round = 0;; ++round) {
        stats.enforce_rounds = std::max(stats.enforce_rounds, round + 1);
        stage.restart();
        // Within the budget the CCD tests every pair; past it, test_within_budget chooses which,
        // and the others count as hits.
        const auto num_active =
            static_cast<std::int64_t>(active.vertex_face.size() + active.edge_edge.size());
        collision::NarrowPhaseResult narrow;
        std::int64_t ccd_hits = 0;  // of the pairs the CCD tested
        if (num_active <= budget_left) {
            budget_left -= num_active;
            stats.ccd_pairs += num_active;
            narrow =
                collision::continuous_narrow_phase(positions_t0, end, triangles, edges, active);
            ccd_hits = narrow.vf_hits + narrow.ee_hits;
        } else {
            if (!over_budget) {
                over_budget = true;
                ++stats.budget_exceeded;
            }
            narrow =
                test_within_budget(candidates, positions_t0, end, active, budget_left, ccd_hits);
            stats.ccd_pairs += budget_left;
            budget_left = 0;
        }
        stats.narrow_ms += stage.elapsed_ms();
        if (round == 0) {
            stats.ccd_hits += ccd_hits;
        }
        if (narrow.vf_hits + narrow.ee_hits == 0) {
            break;
        }
        // The vertices of every pair the CCD cannot clear, in pair order (deterministic).
        stage.restart();
        bool moved_any = false;
        for (const collision::VertexFacePair& p : narrow.hits.vertex_face) {
            const geometry::Triangle& f = triangles[static_cast<std::size_t>(p.face)];
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
            stats.response_ms += stage.elapsed_ms();
            break;
        }
        // A vertex put back stands still: in the frame it moves from x_t0 − s(τ_t0) to
        // x_t0 − s(τ). An escaped one's box holds that already; another that leaves its slack
        // so escapes now, and its pairs are searched.
        m_escaped_now.clear();
        for (std::size_t v = 0; v < n; ++v) {
            if (m_changed[v] == 0) {
                continue;
            }
            if (m_escaped[v] != 0) {
                // Its box holds its start; it must hold the end it now has as well.
                if (!candidates.box_holds(v, end[v] - shift, margin)) {
                    m_escaped_now.push_back(static_cast<std::int32_t>(v));
                }
                continue;
            }
            if (candidates.within_path(end[v], shift, time, v, margin)) {
                m_deviations[v] =
                    std::max(m_deviations[v], candidates.deviation(end[v], shift, time, v));
            } else {
                m_escaped_now.push_back(static_cast<std::int32_t>(v));
            }
        }
        search_escaped(candidates, positions_t0, end, shift_t0, shift, margin, stats);
        collect(true);
        std::fill(m_changed.begin(), m_changed.end(), std::uint8_t{0});
        stats.response_ms += stage.elapsed_ms();
    }
}

std::span<const Vec3d> CCDFailSafe::begin_window(std::span<const Vec3d> start,
                                                 std::span<const Vec3d> end) {
    const std::size_t n = end.size();
    m_reverted.assign(n, 0);
    m_changed.assign(n, 0);
    m_window_motion.resize(n);
    parallel_for(
        static_cast<std::int64_t>(n),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_window_motion[v] = end[v] - start[v];
        },
        detail::SELF_VERTEX_GRAIN);
    return m_window_motion;
}

void CCDFailSafe::enforce_pairs(std::span<const detail::FeatureVertices> pairs,
                                std::span<const Vec3d> positions_t0, std::span<Vec3d> positions,
                                std::span<Vec3d> velocities, SelfCollisionStats& stats) {
    Stopwatch watch;
    const std::span<const Vec3d> end(positions);
    const double margin = 1e-9 * (1.0 + detail::largest_coordinate(positions_t0, end));
    const std::span<const Vec3d> motion = begin_window(positions_t0, end);
    const auto marked = [&](const FeatureVertices& f) {
        return (m_changed[static_cast<std::size_t>(f.v[0])] |
                m_changed[static_cast<std::size_t>(f.v[1])] |
                m_changed[static_cast<std::size_t>(f.v[2])] |
                m_changed[static_cast<std::size_t>(f.v[3])]) != 0;
    };
    const auto at = [](std::span<const Vec3d> x, std::int32_t v) {
        return x[static_cast<std::size_t>(v)];
    };
    const auto num_pairs = static_cast<std::int64_t>(pairs.size());
    m_pair_hits.assign(pairs.size(), 0);
    Stopwatch stage;
    for (int round = 0;; ++round) {
        stats.enforce_rounds = std::max(stats.enforce_rounds, round + 1);
        stage.restart();
        // Per pair: tested (counted) and hit (m_pair_hits), each pair alone: any thread count.
        using Counts = std::pair<std::int64_t, std::int64_t>;  // tested, hits
        const Counts counts = parallel_reduce(
            num_pairs, Counts{0, 0},
            [&](std::int64_t begin, std::int64_t stop) {
                Counts c{0, 0};
                for (std::int64_t i = begin; i < stop; ++i) {
                    const auto k = static_cast<std::size_t>(i);
                    const FeatureVertices& f = pairs[k];
                    m_pair_hits[k] = 0;
                    if ((round > 0 && !marked(f)) ||
                        separation_exceeds(f, positions_t0, motion, margin)) {
                        continue;
                    }
                    ++c.first;
                    const collision::CcdResult r =
                        f.num_first == 1 ? collision::vertex_face_ccd(
                                               at(positions_t0, f.v[0]), at(positions_t0, f.v[1]),
                                               at(positions_t0, f.v[2]), at(positions_t0, f.v[3]),
                                               at(end, f.v[0]), at(end, f.v[1]), at(end, f.v[2]),
                                               at(end, f.v[3]))
                                         : collision::edge_edge_ccd(
                                               at(positions_t0, f.v[0]), at(positions_t0, f.v[1]),
                                               at(positions_t0, f.v[2]), at(positions_t0, f.v[3]),
                                               at(end, f.v[0]), at(end, f.v[1]), at(end, f.v[2]),
                                               at(end, f.v[3]));
                    if (r.hit) {
                        m_pair_hits[k] = 1;
                        ++c.second;
                    }
                }
                return c;
            },
            [](const Counts& a, const Counts& b) {
                return Counts{a.first + b.first, a.second + b.second};
            },
            detail::PAIR_GRAIN);
        stats.ccd_pairs += counts.first;
        if (round == 0) {
            stats.ccd_hits += counts.second;
        }
        stats.narrow_ms += stage.elapsed_ms();
        if (counts.second == 0) {
            break;
        }
        // The vertices of every hit, in pair order (deterministic).
        stage.restart();
        std::fill(m_changed.begin(), m_changed.end(), std::uint8_t{0});
        bool moved_any = false;
        for (std::size_t k = 0; k < pairs.size(); ++k) {
            if (m_pair_hits[k] == 0) {
                continue;
            }
            for (const std::int32_t vertex : pairs[k].v) {
                const auto v = static_cast<std::size_t>(vertex);
                stats.reverted_vertices += m_reverted[v] == 0 ? 1 : 0;
                m_reverted[v] = 1;
                if (positions[v] == positions_t0[v]) {
                    continue;
                }
                positions[v] = positions_t0[v];
                velocities[v] = {0.0, 0.0, 0.0};
                m_window_motion[v] = {0.0, 0.0, 0.0};
                m_changed[v] = 1;
                moved_any = true;
            }
        }
        stats.response_ms += stage.elapsed_ms();
        if (!moved_any) {
            // Every vertex of every hit is at its start: touching at the window's start.
            break;
        }
    }
    stats.enforce_ms += watch.elapsed_ms();
}

void CCDFailSafe::save_state(ByteWriter& out) const {
    out.put_vector(m_deviations);
    out.put_vector(m_window_motion);
    out.put_vector(m_escaped);
    out.put_vector(m_escaped_now);
    out.put_vector(m_escape_pairs.vertex_face);
    out.put_vector(m_escape_pairs.edge_edge);
    out.put_vector(m_reverted);
    out.put_vector(m_changed);
}

void CCDFailSafe::load_state(ByteReader& in) {
    in.get_vector("fail_safe.deviations", m_deviations);
    in.get_vector("fail_safe.window_motion", m_window_motion);
    in.get_vector("fail_safe.escaped", m_escaped);
    in.get_vector("fail_safe.escaped_now", m_escaped_now);
    in.get_vector("fail_safe.escape_pairs.vertex_face", m_escape_pairs.vertex_face);
    in.get_vector("fail_safe.escape_pairs.edge_edge", m_escape_pairs.edge_edge);
    in.get_vector("fail_safe.reverted", m_reverted);
    in.get_vector("fail_safe.changed", m_changed);
}

}  // namespace pliant::cloth
