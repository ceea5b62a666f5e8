#include "pliant/collision/narrow_phase.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::collision {
namespace {

constexpr std::int64_t PAIR_GRAIN = 256;

NarrowPhaseResult combine(NarrowPhaseResult a, const NarrowPhaseResult& b) {
    a.vf_hits += b.vf_hits;
    a.ee_hits += b.ee_hits;
    a.earliest_toi = std::min(a.earliest_toi, b.earliest_toi);
    a.hits.vertex_face.insert(a.hits.vertex_face.end(), b.hits.vertex_face.begin(),
                              b.hits.vertex_face.end());
    a.hits.edge_edge.insert(a.hits.edge_edge.end(), b.hits.edge_edge.begin(),
                            b.hits.edge_edge.end());
    return a;
}

}  // namespace

template <typename Real>
NarrowPhaseResult continuous_narrow_phase(std::span<const Vec3<Real>> positions_t0,
                                          std::span<const Vec3<Real>> positions_t1,
                                          std::span<const geometry::Triangle> triangles,
                                          std::span<const geometry::Edge> edges,
                                          const FeaturePairs& pairs, const CcdOptions& options) {
    const std::size_t num_vertices = positions_t0.size();
    if (positions_t1.size() != num_vertices) {
        throw InvalidInput(fmt::format(
            "continuous_narrow_phase: positions_t0.size() ({}) != positions_t1.size() ({})",
            num_vertices, positions_t1.size()));
    }
    for (const VertexFacePair& p : pairs.vertex_face) {
        if (p.vertex < 0 || static_cast<std::size_t>(p.vertex) >= num_vertices || p.face < 0 ||
            static_cast<std::size_t>(p.face) >= triangles.size()) {
            throw InvalidInput(fmt::format(
                "continuous_narrow_phase: vertex-face pair ({}, {}) out of range ({} vertices, {} "
                "triangles)",
                p.vertex, p.face, num_vertices, triangles.size()));
        }
    }
    for (const EdgeEdgePair& p : pairs.edge_edge) {
        if (p.edge_a < 0 || static_cast<std::size_t>(p.edge_a) >= edges.size() || p.edge_b < 0 ||
            static_cast<std::size_t>(p.edge_b) >= edges.size()) {
            throw InvalidInput(fmt::format(
                "continuous_narrow_phase: edge-edge pair ({}, {}) out of range ({} edges)",
                p.edge_a, p.edge_b, edges.size()));
        }
    }
    const auto at = [](std::span<const Vec3<Real>> positions, std::int32_t v) {
        return vec3_cast<double>(positions[static_cast<std::size_t>(v)]);
    };
    const auto num_vf = static_cast<std::int64_t>(pairs.vertex_face.size());
    const auto num_ee = static_cast<std::int64_t>(pairs.edge_edge.size());
    // One index range over both kinds: [0, num_vf) vertex-face, then edge-edge.
    return parallel_reduce(
        num_vf + num_ee, NarrowPhaseResult{},
        [&](std::int64_t begin, std::int64_t end) {
            NarrowPhaseResult r;
            for (std::int64_t i = begin; i < end; ++i) {
                CcdResult hit;
                bool is_vertex_face = i < num_vf;
                if (is_vertex_face) {
                    const VertexFacePair p = pairs.vertex_face[static_cast<std::size_t>(i)];
                    const geometry::Triangle& f = triangles[static_cast<std::size_t>(p.face)];
                    hit = vertex_face_ccd(at(positions_t0, p.vertex), at(positions_t0, f[0]),
                                          at(positions_t0, f[1]), at(positions_t0, f[2]),
                                          at(positions_t1, p.vertex), at(positions_t1, f[0]),
                                          at(positions_t1, f[1]), at(positions_t1, f[2]), options);
                } else {
                    const EdgeEdgePair p = pairs.edge_edge[static_cast<std::size_t>(i - num_vf)];
                    const geometry::Edge& a = edges[static_cast<std::size_t>(p.edge_a)];
                    const geometry::Edge& b = edges[static_cast<std::size_t>(p.edge_b)];
                    hit = edge_edge_ccd(at(positions_t0, a[0]), at(positions_t0, a[1]),
                                        at(positions_t0, b[0]), at(positions_t0, b[1]),
                                        at(positions_t1, a[0]), at(positions_t1, a[1]),
                                        at(positions_t1, b[0]), at(positions_t1, b[1]), options);
                }
                if (hit.hit) {
                    if (is_vertex_face) {
                        ++r.vf_hits;
                        r.hits.vertex_face.push_back(
                            pairs.vertex_face[static_cast<std::size_t>(i)]);
                    } else {
                        ++r.ee_hits;
                        r.hits.edge_edge.push_back(
                            pairs.edge_edge[static_cast<std::size_t>(i - num_vf)]);
                    }
                    r.earliest_toi = std::min(r.earliest_toi, hit.toi);
                }
            }
            return r;
        },
        combine, PAIR_GRAIN);
}

template NarrowPhaseResult continuous_narrow_phase<float>(std::span<const Vec3f>,
                                                          std::span<const Vec3f>,
                                                          std::span<const geometry::Triangle>,
                                                          std::span<const geometry::Edge>,
                                                          const FeaturePairs&, const CcdOptions&);
template NarrowPhaseResult continuous_narrow_phase<double>(std::span<const Vec3d>,
                                                           std::span<const Vec3d>,
                                                           std::span<const geometry::Triangle>,
                                                           std::span<const geometry::Edge>,
                                                           const FeaturePairs&, const CcdOptions&);

}  // namespace pliant::collision
