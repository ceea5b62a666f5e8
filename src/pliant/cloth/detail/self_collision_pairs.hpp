// What the self-collision's parts (self_collision_candidates.hpp, ccd_fail_safe.hpp,
// self_collision.hpp) share about feature pairs: their four vertices, their exact distance, the
// cheap lower bounds of pair_bounds.hpp on a positions span, the rounding margins' scale, and
// the deterministic filter of indices they all run.
//
// A feature pair's vertices: v[0 .. num_first) the first feature, v[num_first .. 4) the second
// (vertex-face: the vertex, then the face's three; edge-edge: edge a's two, then edge b's).
// Positions are indexed by vertex (#V). Inline, no allocation except IndexFilter's buffers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/detail/pair_bounds.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

inline constexpr std::int64_t PAIR_GRAIN = 512;
inline constexpr std::int64_t SELF_VERTEX_GRAIN = 4096;

struct FeatureVertices {
    std::int32_t v[4];
    std::size_t num_first;  // 1: vertex-face, 2: edge-edge
};

// The exact distance between the pair's features at x.
inline double features_distance(const FeatureVertices& f, std::span<const Vec3d> x) {
    const auto at = [&](int k) {
        return x[static_cast<std::size_t>(f.v[k])];
    };
    if (f.num_first == 1) {
        return collision::point_triangle_proximity(at(0), at(1), at(2), at(3)).distance;
    }
    return collision::segment_segment_proximity(at(0), at(1), at(2), at(3)).distance;
}

// The largest |coordinate| of x and y: the scale of the rounding margins.
inline double largest_coordinate(std::span<const Vec3d> x, std::span<const Vec3d> y) {
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
        [](double a, double b) { return std::max(a, b); }, SELF_VERTEX_GRAIN);
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

// box_gap of pair_bounds.hpp at x.
inline double pair_box_gap(const std::int32_t (&v)[4], std::size_t num_first,
                           std::span<const Vec3d> x) {
    return on_pair(
        v, num_first, [&](std::size_t i) { return x[i]; },
        []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
            return box_gap<EE>(a, b, c, d);
        });
}

// centroid_axis_gap of pair_bounds.hpp at x.
inline double pair_centroid_axis_gap(const std::int32_t (&v)[4], std::size_t num_first,
                                     std::span<const Vec3d> x) {
    return on_pair(
        v, num_first, [&](std::size_t i) { return x[i]; },
        []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
            return centroid_axis_gap<EE>(a, b, c, d);
        });
}

// The largest |d_i − d_j| over the pairs (i in the first feature, j in the second) of the
// vertices' values d = value(vertex): displacements or velocities.
template <typename Value>
inline double pair_largest_difference(const std::int32_t (&v)[4], std::size_t num_first,
                                      Value&& value) {
    return on_pair(v, num_first, value,
                   []<bool EE>(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
                       return largest_pair_difference<EE>(a, b, c, d);
                   });
}

// The largest difference of the vertices' displacements Δ = end − start: for linear motion the
// features' distance never falls below their distance at the start minus this (nor, for any
// motion, their distance at the end below their distance at the start minus this).
inline double relative_sweep(std::span<const Vec3d> start, std::span<const Vec3d> end,
                             const std::int32_t (&v)[4], std::size_t num_first) {
    return pair_largest_difference(v, num_first, [&](std::size_t i) { return end[i] - start[i]; });
}

// The i in [0, n) with keep(i), ascending: kept per chunk of PAIR_GRAIN in parallel, merged in
// chunk order (the same for any number of threads). The result is valid until the next call.
class IndexFilter {
public:
    template <typename Keep>
    const std::vector<std::int64_t>& where(std::int64_t n, Keep&& keep) {
        m_chunks.reset(num_chunks(n, PAIR_GRAIN));
        parallel_for_chunks(n, PAIR_GRAIN,
                            [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                                AppendBuffer<std::int64_t>& out = m_chunks.chunk(c);
                                for (std::int64_t i = begin; i < end; ++i) {
                                    if (keep(i)) {
                                        out.push_back(i);
                                    }
                                }
                            });
        m_chunks.gather(m_indices);
        return m_indices;
    }

private:
    ChunkedBuffer<std::int64_t> m_chunks;
    std::vector<std::int64_t> m_indices;
};

}  // namespace pliant::cloth::detail
