#include "pliant/geometry/topology.hpp"

#include "pliant/core/check.hpp"
#include "pliant/core/group_by_key.hpp"
#include "pliant/core/radix_sort.hpp"

namespace pliant::geometry {

MeshTopology build_topology(std::span<const Triangle> triangles, std::size_t num_vertices) {
    MeshTopology topo;
    const std::size_t num_triangles = triangles.size();
    const std::size_t num_corners = 3 * num_triangles;
    PLIANT_CHECK_LE(num_corners, static_cast<std::size_t>(INT32_MAX));

    // Step 1: half-edge keys (min << 32 | max), sorted with their corner ids.
    std::vector<std::uint64_t> keys(num_corners);
    std::vector<std::uint32_t> corners(num_corners);
    for (std::size_t t = 0; t < num_triangles; ++t) {
        for (std::size_t k = 0; k < 3; ++k) {
            auto a = static_cast<std::uint64_t>(triangles[t][k]);
            auto b = static_cast<std::uint64_t>(triangles[t][(k + 1) % 3]);
            if (a > b) {
                std::swap(a, b);
            }
            keys[3 * t + k] = (a << 32) | b;
            corners[3 * t + k] = static_cast<std::uint32_t>(3 * t + k);
        }
    }
    RadixSorter sorter;
    sorter.sort(keys, corners);

    // Step 2: unique edges, corner → edge, edge → triangles (corners ascend within a key, so the
    // triangles of an edge come out ascending).
    topo.triangle_edges.resize(num_triangles);
    topo.edge_triangle_offsets.push_back(0);
    topo.edge_triangles.reserve(num_corners);
    for (std::size_t i = 0; i < num_corners; ++i) {
        if (i == 0 || keys[i] != keys[i - 1]) {
            if (i != 0) {
                topo.edge_triangle_offsets.push_back(static_cast<std::int32_t>(i));
            }
            topo.edges.push_back({static_cast<std::int32_t>(keys[i] >> 32),
                                  static_cast<std::int32_t>(keys[i] & 0xffffffffu)});
        }
        const std::uint32_t corner = corners[i];
        topo.triangle_edges[corner / 3][corner % 3] =
            static_cast<std::int32_t>(topo.edges.size() - 1);
        topo.edge_triangles.push_back(static_cast<std::int32_t>(corner / 3));
    }
    topo.edge_triangle_offsets.push_back(static_cast<std::int32_t>(num_corners));
    if (num_corners == 0) {
        topo.edge_triangle_offsets.assign(1, 0);
    }

    // Step 3: vertex → triangles.
    std::vector<std::int32_t> corner_vertices(num_corners);
    for (std::size_t t = 0; t < num_triangles; ++t) {
        for (std::size_t k = 0; k < 3; ++k) {
            corner_vertices[3 * t + k] = triangles[t][k];
        }
    }
    group_by_key(corner_vertices, num_vertices, topo.vertex_triangle_offsets, topo.vertex_triangles,
                 3);
    return topo;
}

}  // namespace pliant::geometry
