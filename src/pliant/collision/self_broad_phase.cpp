#include "pliant/collision/self_broad_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdint>

#include "pliant/bvh/traversal.hpp"
#include "pliant/collision/incidence.hpp"
#include "pliant/collision/orphan_set.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::collision {
namespace {

constexpr std::int64_t BOX_GRAIN = 1 << 13;
constexpr std::int64_t PAIR_GRAIN = 1 << 12;

}  // namespace

template <typename Real>
SelfCollisionBroadPhase<Real>::SelfCollisionBroadPhase(
    std::span<const geometry::Triangle> triangles, std::size_t num_vertices)
    : m_triangles(triangles.begin(), triangles.end()), m_num_vertices(num_vertices) {
    geometry::validate_triangles(triangles, num_vertices, "SelfCollisionBroadPhase: triangles");
    m_topology = geometry::build_topology(triangles, num_vertices);
    m_owners = assign_representative_triangles(triangles, m_topology);
    m_orphans = build_orphan_set(triangles, m_topology, m_owners);
}

template <typename Real>
auto SelfCollisionBroadPhase<Real>::exact_edge_box(std::int32_t edge) const -> Box {
    const geometry::Edge& e = m_topology.edges[static_cast<std::size_t>(edge)];
    return merge(m_exact_vertex_boxes[static_cast<std::size_t>(e[0])],
                 m_exact_vertex_boxes[static_cast<std::size_t>(e[1])]);
}

template <typename Real>
auto SelfCollisionBroadPhase<Real>::exact_triangle_box(std::int32_t triangle) const -> Box {
    const geometry::Triangle& t = m_triangles[static_cast<std::size_t>(triangle)];
    return merge(merge(m_exact_vertex_boxes[static_cast<std::size_t>(t[0])],
                       m_exact_vertex_boxes[static_cast<std::size_t>(t[1])]),
                 m_exact_vertex_boxes[static_cast<std::size_t>(t[2])]);
}

// Confirmation of a pair that passed the float test: exact for double input, nothing to do for
// float input (the float boxes are the exact ones).
template <typename Real>
bool SelfCollisionBroadPhase<Real>::overlaps_exact_vf(std::int32_t vertex,
                                                      std::int32_t face) const {
    if constexpr (std::is_same_v<Real, float>) {
        return true;
    } else {
        if (!m_confirm_exact) {
            return true;
        }
        return overlaps(m_exact_vertex_boxes[static_cast<std::size_t>(vertex)],
                        exact_triangle_box(face));
    }
}

template <typename Real>
bool SelfCollisionBroadPhase<Real>::overlaps_exact_ee(std::int32_t edge_a,
                                                      std::int32_t edge_b) const {
    if constexpr (std::is_same_v<Real, float>) {
        return true;
    } else {
        if (!m_confirm_exact) {
            return true;
        }
        return overlaps(exact_edge_box(edge_a), exact_edge_box(edge_b));
    }
}

template <typename Real>
bool SelfCollisionBroadPhase<Real>::overlaps_exact_tt(std::int32_t triangle_a,
                                                      std::int32_t triangle_b) const {
    if constexpr (std::is_same_v<Real, float>) {
        return true;
    } else {
        if (!m_confirm_exact) {
            return true;
        }
        return overlaps(exact_triangle_box(triangle_a), exact_triangle_box(triangle_b));
    }
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::set_vertex_box(std::size_t v, const Vec& p0, const Vec& p1,
                                                   Real inflation) {
    const Box box = Box{min(p0, p1), max(p0, p1)}.inflated(inflation);
    if constexpr (!std::is_same_v<Real, float>) {
        if (m_confirm_exact) {
            m_exact_vertex_boxes[v] = box;
        }
    }
    m_vertex_boxes[v] = outward_float(box);
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::compute_boxes(std::span<const Vec> positions_t0,
                                                  std::span<const Vec> positions_t1,
                                                  Real inflation) {
    m_vertex_boxes.resize(m_num_vertices);
    m_edge_boxes.resize(m_topology.num_edges());
    m_triangle_boxes.resize(m_triangles.size());
    if constexpr (!std::is_same_v<Real, float>) {
        m_exact_vertex_boxes.resize(m_num_vertices);
    }
    // Edge and triangle boxes are merges of vertex boxes; outward rounding commutes with min/max,
    // so the merged float boxes are the outward-rounded exact ones.
    parallel_for(
        static_cast<std::int64_t>(m_num_vertices),
        [&](std::int64_t v) {
            const auto k = static_cast<std::size_t>(v);
            set_vertex_box(k, positions_t0[k], positions_t1[k], inflation);
        },
        BOX_GRAIN);
    parallel_for(
        static_cast<std::int64_t>(m_topology.num_edges()),
        [&](std::int64_t e) {
            const geometry::Edge& edge = m_topology.edges[static_cast<std::size_t>(e)];
            m_edge_boxes[static_cast<std::size_t>(e)] =
                merge(m_vertex_boxes[static_cast<std::size_t>(edge[0])],
                      m_vertex_boxes[static_cast<std::size_t>(edge[1])]);
        },
        BOX_GRAIN);
    parallel_for(
        static_cast<std::int64_t>(m_triangles.size()),
        [&](std::int64_t t) {
            const geometry::Triangle& tri = m_triangles[static_cast<std::size_t>(t)];
            m_triangle_boxes[static_cast<std::size_t>(t)] =
                merge(merge(m_vertex_boxes[static_cast<std::size_t>(tri[0])],
                            m_vertex_boxes[static_cast<std::size_t>(tri[1])]),
                      m_vertex_boxes[static_cast<std::size_t>(tri[2])]);
        },
        BOX_GRAIN);
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::traverse(const TrianglePairFilter* keep) {
    m_triangle_pair_chunks.reset(bvh::num_overlap_chunks(m_bvh));
    const geometry::Triangle* triangles = m_triangles.data();
    // The limit on all kept pairs, counted in steps of PAIR_LIMIT_STEP per chunk (so it may be
    // passed by less than a step per chunk).
    constexpr std::size_t PAIR_LIMIT_STEP = 256;
    const std::int64_t budget =
        m_pair_limit > 0 ? m_pair_limit * static_cast<std::int64_t>(m_triangles.size()) : INT64_MAX;
    std::atomic<std::int64_t> kept{0};
    std::atomic<bool> exceeded{false};
    bvh::for_each_self_overlap(m_bvh, [&](std::int64_t chunk, std::uint32_t a, std::uint32_t b) {
        if (exceeded.load(std::memory_order_relaxed) || share_vertex(triangles[a], triangles[b])) {
            return;
        }
        const auto ia = static_cast<std::int32_t>(a);
        const auto ib = static_cast<std::int32_t>(b);
        if (overlaps_exact_tt(ia, ib) && (keep == nullptr || (*keep)(ia, ib))) {
            AppendBuffer<std::pair<std::int32_t, std::int32_t>>& out =
                m_triangle_pair_chunks.chunk(chunk);
            out.emplace_back(ia, ib);
            if (out.size() % PAIR_LIMIT_STEP == 0 &&
                kept.fetch_add(PAIR_LIMIT_STEP, std::memory_order_relaxed) +
                        static_cast<std::int64_t>(PAIR_LIMIT_STEP) >
                    budget) {
                exceeded.store(true, std::memory_order_relaxed);
            }
        }
    });
    m_pair_limit_exceeded = exceeded.load();
    if (m_pair_limit_exceeded) {  // incomplete: not gathered (the copy would double the peak)
        m_triangle_pairs.clear();
        m_stats.triangle_pairs = 0;
        return;
    }
    m_triangle_pair_chunks.gather(m_triangle_pairs);
    m_stats.triangle_pairs = static_cast<std::int64_t>(m_triangle_pairs.size());
}

template <typename Real>
template <bool PARTIAL>
void SelfCollisionBroadPhase<Real>::emit_feature_pairs(std::int32_t a, std::int32_t b,
                                                       AppendBuffer<VertexFacePair>& vf,
                                                       AppendBuffer<EdgeEdgePair>& ee) const {
    const AABB* vertex_boxes = m_vertex_boxes.data();
    const AABB* edge_boxes = m_edge_boxes.data();
    const OwnedFeatures& owned_a = m_owners.owned[static_cast<std::size_t>(a)];
    const OwnedFeatures& owned_b = m_owners.owned[static_cast<std::size_t>(b)];
    const AABB box_a = m_triangle_boxes[static_cast<std::size_t>(a)];
    const AABB box_b = m_triangle_boxes[static_cast<std::size_t>(b)];
    // With PARTIAL, a pair is kept only when one of its vertices changed.
    const auto marked = [&](std::int32_t v) {
        return int{m_vertex_marks[static_cast<std::size_t>(v)]};
    };
    const auto face_marked = [&](std::int32_t t) {
        return int{m_triangle_marks[static_cast<std::size_t>(t)]};
    };
    const auto edge_marked = [&](std::int32_t e) {
        const geometry::Edge& edge = m_topology.edges[static_cast<std::size_t>(e)];
        return marked(edge[0]) | marked(edge[1]);
    };
    VertexFacePair* out_vf = vf.grow(6);
    std::size_t num_vf = 0;
    for (int k = 0; k < owned_a.num_vertices; ++k) {
        const std::int32_t v = owned_a.vertices[k];
        out_vf[num_vf] = {v, b};
        bool keep = overlaps(vertex_boxes[v], box_b) && overlaps_exact_vf(v, b);
        if constexpr (PARTIAL) {
            keep = keep && (marked(v) | face_marked(b)) != 0;
        }
        num_vf += keep ? 1 : 0;
    }
    for (int k = 0; k < owned_b.num_vertices; ++k) {
        const std::int32_t v = owned_b.vertices[k];
        out_vf[num_vf] = {v, a};
        bool keep = overlaps(vertex_boxes[v], box_a) && overlaps_exact_vf(v, a);
        if constexpr (PARTIAL) {
            keep = keep && (marked(v) | face_marked(a)) != 0;
        }
        num_vf += keep ? 1 : 0;
    }
    vf.commit(num_vf);
    EdgeEdgePair* out_ee = ee.grow(9);
    std::size_t num_ee = 0;
    for (int i_a = 0; i_a < owned_a.num_edges; ++i_a) {
        const std::int32_t ea = owned_a.edges[i_a];
        const AABB box_ea = edge_boxes[ea];
        if (!overlaps(box_ea, box_b)) {
            continue;
        }
        for (int i_b = 0; i_b < owned_b.num_edges; ++i_b) {
            const std::int32_t eb = owned_b.edges[i_b];
            out_ee[num_ee] = {std::min(ea, eb), std::max(ea, eb)};
            bool keep = overlaps(box_ea, edge_boxes[eb]) && overlaps_exact_ee(ea, eb);
            if constexpr (PARTIAL) {
                keep = keep && (edge_marked(ea) | edge_marked(eb)) != 0;
            }
            num_ee += keep ? 1 : 0;
        }
    }
    ee.commit(num_ee);
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::test_features() {
    const auto num_pairs = static_cast<std::int64_t>(m_triangle_pairs.size());
    const auto num_orphan_vf = static_cast<std::int64_t>(m_orphans.vertex_face.size());
    const auto num_orphan_ee = static_cast<std::int64_t>(m_orphans.edge_edge.size());
    const std::int64_t pair_chunks = num_chunks(num_pairs, PAIR_GRAIN);
    m_vf_chunks.reset(pair_chunks + num_chunks(num_orphan_vf, PAIR_GRAIN));
    m_ee_chunks.reset(pair_chunks + num_chunks(num_orphan_ee, PAIR_GRAIN));
    const AABB* vertex_boxes = m_vertex_boxes.data();
    const AABB* edge_boxes = m_edge_boxes.data();
    const AABB* triangle_boxes = m_triangle_boxes.data();

    // R-triangle pairs: the vertices each triangle owns against the other's face, owned edges
    // against owned edges. Non-adjacent triangles: no feature pair here is incident. Candidates
    // are written unconditionally and kept by advancing the count (branch-free compaction).
    parallel_for_chunks(num_pairs, PAIR_GRAIN,
                        [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                            auto& vf = m_vf_chunks.chunk(c);
                            auto& ee = m_ee_chunks.chunk(c);
                            for (std::int64_t i = begin; i < end; ++i) {
                                const auto [a, b] = m_triangle_pairs[static_cast<std::size_t>(i)];
                                emit_feature_pairs<false>(a, b, vf, ee);
                            }
                        });
    // Orphans: pairs between triangles that share a vertex; only their boxes are left to test.
    parallel_for_chunks(
        num_orphan_vf, PAIR_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            auto& vf = m_vf_chunks.chunk(pair_chunks + c);
            VertexFacePair* out = vf.grow(static_cast<std::size_t>(end - begin));
            std::size_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const VertexFacePair p = m_orphans.vertex_face[static_cast<std::size_t>(i)];
                out[count] = p;
                count += overlaps(vertex_boxes[p.vertex], triangle_boxes[p.face]) &&
                                 overlaps_exact_vf(p.vertex, p.face)
                             ? 1
                             : 0;
            }
            vf.commit(count);
        });
    parallel_for_chunks(
        num_orphan_ee, PAIR_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            auto& ee = m_ee_chunks.chunk(pair_chunks + c);
            EdgeEdgePair* out = ee.grow(static_cast<std::size_t>(end - begin));
            std::size_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const EdgeEdgePair p = m_orphans.edge_edge[static_cast<std::size_t>(i)];
                out[count] = p;
                count += overlaps(edge_boxes[p.edge_a], edge_boxes[p.edge_b]) &&
                                 overlaps_exact_ee(p.edge_a, p.edge_b)
                             ? 1
                             : 0;
            }
            ee.commit(count);
        });
    m_vf_chunks.gather(m_pairs.vertex_face);
    m_ee_chunks.gather(m_pairs.edge_edge);
}

template <typename Real>
const FeaturePairs& SelfCollisionBroadPhase<Real>::update(std::span<const Vec> positions_t0,
                                                          std::span<const Vec> positions_t1,
                                                          Real inflation,
                                                          const TrianglePairFilter* keep) {
    if (positions_t0.size() != m_num_vertices || positions_t1.size() != m_num_vertices) {
        throw InvalidInput(
            fmt::format("SelfCollisionBroadPhase::update: positions_t0.size() ({}) and "
                        "positions_t1.size() ({}) "
                        "must equal the mesh's vertex count ({})",
                        positions_t0.size(), positions_t1.size(), m_num_vertices));
    }
    if (!(inflation >= Real(0)) || !std::isfinite(inflation)) {
        throw InvalidInput(fmt::format(
            "SelfCollisionBroadPhase::update: inflation ({}) must be finite and >= 0", inflation));
    }
    m_stats = {};
    Stopwatch watch;
    compute_boxes(positions_t0, positions_t1, inflation);
    m_stats.features_ms += watch.elapsed_ms();

    watch.restart();
    if (m_needs_build || m_bvh.num_primitives() != static_cast<std::int32_t>(m_triangles.size())) {
        m_bvh.build(m_triangle_boxes);
        m_needs_build = false;
        m_stats.build_ms = watch.elapsed_ms();
    } else {
        m_bvh.refit(m_triangle_boxes);
        m_stats.refit_ms = watch.elapsed_ms();
    }

    watch.restart();
    traverse(keep);
    m_stats.traverse_ms = watch.elapsed_ms();
    if (m_pair_limit_exceeded) {  // incomplete: no feature pairs, no partial updates on it
        m_pairs.vertex_face.clear();
        m_pairs.edge_edge.clear();
        m_has_boxes = false;
        return m_pairs;
    }

    watch.restart();
    test_features();
    m_stats.features_ms += watch.elapsed_ms();
    m_has_boxes = true;
    return m_pairs;
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::index_orphans() {
    const auto num_vf = static_cast<std::int32_t>(m_orphans.vertex_face.size());
    const auto num_ee = static_cast<std::int32_t>(m_orphans.edge_edge.size());
    // Each pair under each of its (distinct) vertices: count, scan, fill.
    const auto vertices_of = [&](std::int32_t i, std::int32_t(&v)[4]) {
        if (i < num_vf) {
            const VertexFacePair& p = m_orphans.vertex_face[static_cast<std::size_t>(i)];
            const geometry::Triangle& f = m_triangles[static_cast<std::size_t>(p.face)];
            v[0] = p.vertex;
            v[1] = f[0];
            v[2] = f[1];
            v[3] = f[2];
        } else {
            const EdgeEdgePair& p = m_orphans.edge_edge[static_cast<std::size_t>(i - num_vf)];
            const geometry::Edge& a = m_topology.edges[static_cast<std::size_t>(p.edge_a)];
            const geometry::Edge& b = m_topology.edges[static_cast<std::size_t>(p.edge_b)];
            v[0] = a[0];
            v[1] = a[1];
            v[2] = b[0];
            v[3] = b[1];
        }
    };
    m_orphan_offsets.assign(m_num_vertices + 1, 0);
    for (std::int32_t i = 0; i < num_vf + num_ee; ++i) {
        std::int32_t v[4];
        vertices_of(i, v);
        for (const std::int32_t u : v) {
            ++m_orphan_offsets[static_cast<std::size_t>(u) + 1];
        }
    }
    for (std::size_t v = 0; v < m_num_vertices; ++v) {
        m_orphan_offsets[v + 1] += m_orphan_offsets[v];
    }
    m_orphan_indices.resize(static_cast<std::size_t>(m_orphan_offsets.back()));
    std::vector<std::int32_t> next(m_orphan_offsets.begin(), m_orphan_offsets.end() - 1);
    for (std::int32_t i = 0; i < num_vf + num_ee; ++i) {
        std::int32_t v[4];
        vertices_of(i, v);
        for (const std::int32_t u : v) {
            m_orphan_indices[static_cast<std::size_t>(next[static_cast<std::size_t>(u)]++)] = i;
        }
    }
}

template <typename Real>
const FeaturePairs& SelfCollisionBroadPhase<Real>::update_vertices(
    std::span<const Vec> positions_t0, std::span<const Vec> positions_t1, Real inflation,
    std::span<const std::int32_t> changed, const TrianglePairFilter* keep) {
    if (!m_has_boxes) {
        throw InvalidInput("SelfCollisionBroadPhase::update_vertices: no full update yet");
    }
    if (positions_t0.size() != m_num_vertices || positions_t1.size() != m_num_vertices) {
        throw InvalidInput(
            fmt::format("SelfCollisionBroadPhase::update_vertices: positions_t0.size() ({}) and "
                        "positions_t1.size() ({}) must equal the mesh's vertex count ({})",
                        positions_t0.size(), positions_t1.size(), m_num_vertices));
    }
    for (const std::int32_t v : changed) {
        if (v < 0 || static_cast<std::size_t>(v) >= m_num_vertices) {
            throw InvalidInput(fmt::format(
                "SelfCollisionBroadPhase::update_vertices: vertex {} out of range [0, {})", v,
                m_num_vertices));
        }
    }
    m_stats = {};
    Stopwatch watch;
    // 1. Boxes: the changed vertices, then every edge and triangle that contains one.
    m_vertex_marks.resize(m_num_vertices, 0);
    m_triangle_marks.resize(m_triangles.size(), 0);
    m_affected_triangles.clear();
    for (const std::int32_t v : changed) {
        const auto k = static_cast<std::size_t>(v);
        m_vertex_marks[k] = 1;
        set_vertex_box(k, positions_t0[k], positions_t1[k], inflation);
        for (const std::int32_t t : m_topology.triangles_of_vertex(v)) {
            if (m_triangle_marks[static_cast<std::size_t>(t)] == 0) {
                m_triangle_marks[static_cast<std::size_t>(t)] = 1;
                m_affected_triangles.push_back(t);
            }
        }
    }
    std::sort(m_affected_triangles.begin(), m_affected_triangles.end());
    m_affected_edges.clear();
    for (const std::int32_t t : m_affected_triangles) {
        for (const std::int32_t e : m_topology.triangle_edges[static_cast<std::size_t>(t)]) {
            const geometry::Edge& edge = m_topology.edges[static_cast<std::size_t>(e)];
            if ((m_vertex_marks[static_cast<std::size_t>(edge[0])] |
                 m_vertex_marks[static_cast<std::size_t>(edge[1])]) != 0) {
                m_affected_edges.push_back(e);
            }
        }
    }
    std::sort(m_affected_edges.begin(), m_affected_edges.end());
    m_affected_edges.erase(std::unique(m_affected_edges.begin(), m_affected_edges.end()),
                           m_affected_edges.end());
    for (const std::int32_t e : m_affected_edges) {
        const geometry::Edge& edge = m_topology.edges[static_cast<std::size_t>(e)];
        m_edge_boxes[static_cast<std::size_t>(e)] =
            merge(m_vertex_boxes[static_cast<std::size_t>(edge[0])],
                  m_vertex_boxes[static_cast<std::size_t>(edge[1])]);
    }
    for (const std::int32_t t : m_affected_triangles) {
        const geometry::Triangle& tri = m_triangles[static_cast<std::size_t>(t)];
        m_triangle_boxes[static_cast<std::size_t>(t)] =
            merge(merge(m_vertex_boxes[static_cast<std::size_t>(tri[0])],
                        m_vertex_boxes[static_cast<std::size_t>(tri[1])]),
                  m_vertex_boxes[static_cast<std::size_t>(tri[2])]);
    }
    m_stats.features_ms += watch.elapsed_ms();
    // 2. Refit.
    watch.restart();
    m_bvh.refit(m_triangle_boxes);
    m_stats.refit_ms = watch.elapsed_ms();
    // 3 + 4. Each affected triangle queries the tree; a pair of two affected triangles is
    // reported by the lower one. Then the orphan pairs around the changed vertices.
    watch.restart();
    const auto num_affected = static_cast<std::int64_t>(m_affected_triangles.size());
    if (m_orphan_offsets.empty()) {
        index_orphans();
    }
    m_affected_orphans.clear();
    for (const std::int32_t v : changed) {
        const auto k = static_cast<std::size_t>(v);
        for (std::int32_t j = m_orphan_offsets[k]; j < m_orphan_offsets[k + 1]; ++j) {
            m_affected_orphans.push_back(m_orphan_indices[static_cast<std::size_t>(j)]);
        }
    }
    std::sort(m_affected_orphans.begin(), m_affected_orphans.end());
    m_affected_orphans.erase(std::unique(m_affected_orphans.begin(), m_affected_orphans.end()),
                             m_affected_orphans.end());
    const auto num_orphans = static_cast<std::int64_t>(m_affected_orphans.size());
    constexpr std::int64_t TRIANGLE_GRAIN = 64;
    const std::int64_t triangle_chunks = num_chunks(num_affected, TRIANGLE_GRAIN);
    m_vf_chunks.reset(triangle_chunks + num_chunks(num_orphans, PAIR_GRAIN));
    m_ee_chunks.reset(triangle_chunks + num_chunks(num_orphans, PAIR_GRAIN));
    const bvh::WideNode* nodes = m_bvh.nodes().data();
    const std::uint32_t* prims = m_bvh.primitives().data();
    std::int64_t triangle_pairs = 0;
    // The limit: 2 L per changed triangle in all (checked as each block ends; each pair counts
    // for both of its triangles here, for the lower one in update()), and 4 L per triangle
    // within a block (contact is local: a block's triangles may all be in the densest spot).
    const std::int64_t budget = m_pair_limit > 0 ? 2 * m_pair_limit * num_affected : INT64_MAX;
    std::atomic<std::int64_t> kept{0};
    std::atomic<bool> exceeded{false};
    if (m_bvh.has_nodes()) {
        triangle_pairs = parallel_reduce(
            num_affected, std::int64_t{0},
            [&](std::int64_t begin, std::int64_t end) {
                const std::int64_t c = begin / TRIANGLE_GRAIN;
                auto& vf = m_vf_chunks.chunk(c);
                auto& ee = m_ee_chunks.chunk(c);
                std::int64_t count = 0;
                if (exceeded.load(std::memory_order_relaxed)) {
                    return count;
                }
                const std::int64_t limit =
                    m_pair_limit > 0 ? 4 * m_pair_limit * (end - begin) : INT64_MAX;
                for (std::int64_t i = begin; i < end; ++i) {
                    const std::int32_t t = m_affected_triangles[static_cast<std::size_t>(i)];
                    const geometry::Triangle& tri = m_triangles[static_cast<std::size_t>(t)];
                    bvh::query_wide(nodes, m_triangle_boxes[static_cast<std::size_t>(t)], -1,
                                    [&](std::int32_t j, const AABB&) {
                                        const auto other = static_cast<std::int32_t>(prims[j]);
                                        if (other == t ||
                                            share_vertex(tri, m_triangles[prims[j]]) ||
                                            (m_triangle_marks[prims[j]] != 0 && other < t) ||
                                            !overlaps_exact_tt(t, other) ||
                                            (keep != nullptr && !(*keep)(t, other))) {
                                            return;
                                        }
                                        if (count >= limit) {
                                            exceeded.store(true, std::memory_order_relaxed);
                                            return;
                                        }
                                        ++count;
                                        emit_feature_pairs<true>(t, other, vf, ee);
                                    });
                }
                if (kept.fetch_add(count, std::memory_order_relaxed) + count > budget) {
                    exceeded.store(true, std::memory_order_relaxed);
                }
                return count;
            },
            [](std::int64_t a, std::int64_t b) { return a + b; }, TRIANGLE_GRAIN);
    }
    const auto num_orphan_vf = static_cast<std::int32_t>(m_orphans.vertex_face.size());
    parallel_for_chunks(
        num_orphans, PAIR_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            auto& vf = m_vf_chunks.chunk(triangle_chunks + c);
            auto& ee = m_ee_chunks.chunk(triangle_chunks + c);
            for (std::int64_t i = begin; i < end; ++i) {
                const std::int32_t k = m_affected_orphans[static_cast<std::size_t>(i)];
                if (k < num_orphan_vf) {
                    const VertexFacePair p = m_orphans.vertex_face[static_cast<std::size_t>(k)];
                    if (overlaps(m_vertex_boxes[static_cast<std::size_t>(p.vertex)],
                                 m_triangle_boxes[static_cast<std::size_t>(p.face)]) &&
                        overlaps_exact_vf(p.vertex, p.face)) {
                        vf.push_back(p);
                    }
                } else {
                    const EdgeEdgePair p =
                        m_orphans.edge_edge[static_cast<std::size_t>(k - num_orphan_vf)];
                    if (overlaps(m_edge_boxes[static_cast<std::size_t>(p.edge_a)],
                                 m_edge_boxes[static_cast<std::size_t>(p.edge_b)]) &&
                        overlaps_exact_ee(p.edge_a, p.edge_b)) {
                        ee.push_back(p);
                    }
                }
            }
        });
    m_pair_limit_exceeded = exceeded.load();
    m_vf_chunks.gather(m_partial_pairs.vertex_face);
    m_ee_chunks.gather(m_partial_pairs.edge_edge);
    m_stats.traverse_ms = watch.elapsed_ms();
    m_stats.triangle_pairs = triangle_pairs;
    // Unmark for the next partial update.
    for (const std::int32_t v : changed) {
        m_vertex_marks[static_cast<std::size_t>(v)] = 0;
    }
    for (const std::int32_t t : m_affected_triangles) {
        m_triangle_marks[static_cast<std::size_t>(t)] = 0;
    }
    return m_partial_pairs;
}

template <typename Real>
std::size_t SelfCollisionBroadPhase<Real>::memory_bytes() const {
    const auto bytes = [](const auto& v) {
        return v.capacity() * sizeof(v[0]);
    };
    return bytes(m_triangles) + bytes(m_topology.edges) + bytes(m_topology.triangle_edges) +
           bytes(m_topology.edge_triangle_offsets) + bytes(m_topology.edge_triangles) +
           bytes(m_topology.vertex_triangle_offsets) + bytes(m_topology.vertex_triangles) +
           bytes(m_owners.vertex_owner) + bytes(m_owners.edge_owner) + bytes(m_owners.owned) +
           bytes(m_orphans.vertex_face) + bytes(m_orphans.edge_edge) + bytes(m_exact_vertex_boxes) +
           bytes(m_vertex_boxes) + bytes(m_edge_boxes) + bytes(m_triangle_boxes) +
           bytes(m_triangle_pairs) + bytes(m_pairs.vertex_face) + bytes(m_pairs.edge_edge) +
           m_triangle_pair_chunks.memory_bytes() + m_vf_chunks.memory_bytes() +
           m_ee_chunks.memory_bytes() + m_bvh.memory_bytes() + bytes(m_vertex_marks) +
           bytes(m_triangle_marks) + bytes(m_affected_triangles) + bytes(m_affected_edges) +
           bytes(m_orphan_offsets) + bytes(m_orphan_indices) + bytes(m_affected_orphans) +
           bytes(m_partial_pairs.vertex_face) + bytes(m_partial_pairs.edge_edge);
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::save_state(ByteWriter& out) const {
    // Not the pairs of the last update (the caller has taken them) nor the partial update's
    // scratch; the orphan index is rebuilt on first use.
    out.put(static_cast<std::uint64_t>(m_num_vertices));
    out.put(static_cast<std::uint64_t>(m_triangles.size()));
    out.put_vector(m_exact_vertex_boxes);
    out.put_vector(m_vertex_boxes);
    out.put_vector(m_edge_boxes);
    out.put_vector(m_triangle_boxes);
    m_bvh.save_state(out);
    out.put(m_needs_build);
    out.put(m_has_boxes);
    out.put(m_confirm_exact);
    out.put(m_pair_limit);
    out.put(m_pair_limit_exceeded);
    out.put_vector(m_vertex_marks);
    out.put_vector(m_triangle_marks);
}

template <typename Real>
void SelfCollisionBroadPhase<Real>::load_state(ByteReader& in) {
    const auto num_vertices = in.get<std::uint64_t>("broad_phase.num_vertices");
    const auto num_triangles = in.get<std::uint64_t>("broad_phase.num_triangles");
    if (num_vertices != m_num_vertices || num_triangles != m_triangles.size()) {
        throw InvalidInput(fmt::format(
            "{}: broad phase: a state of {} vertices and {} triangles, the mesh has {} and {}",
            in.source(), num_vertices, num_triangles, m_num_vertices, m_triangles.size()));
    }
    in.get_vector("broad_phase.exact_vertex_boxes", m_exact_vertex_boxes);
    in.get_vector("broad_phase.vertex_boxes", m_vertex_boxes);
    in.get_vector("broad_phase.edge_boxes", m_edge_boxes);
    in.get_vector("broad_phase.triangle_boxes", m_triangle_boxes);
    m_bvh.load_state(in);
    m_needs_build = in.get_bool("broad_phase.needs_build");
    m_has_boxes = in.get_bool("broad_phase.has_boxes");
    m_confirm_exact = in.get_bool("broad_phase.confirm_exact");
    m_pair_limit = in.get<std::int64_t>("broad_phase.pair_limit");
    m_pair_limit_exceeded = in.get_bool("broad_phase.pair_limit_exceeded");
    in.get_vector("broad_phase.vertex_marks", m_vertex_marks);
    in.get_vector("broad_phase.triangle_marks", m_triangle_marks);
}

template class SelfCollisionBroadPhase<float>;
template class SelfCollisionBroadPhase<double>;

}  // namespace pliant::collision
