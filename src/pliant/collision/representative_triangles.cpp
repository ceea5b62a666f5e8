#include "pliant/collision/representative_triangles.hpp"

#include "pliant/core/check.hpp"

namespace pliant::collision {
namespace {

// The incident triangle with the fewest owned features (lowest index on ties), or -1.
std::int32_t least_loaded(std::span<const std::int32_t> candidates, const std::vector<int>& load) {
    std::int32_t best = -1;
    for (const std::int32_t t : candidates) {
        if (best < 0 || load[static_cast<std::size_t>(t)] < load[static_cast<std::size_t>(best)]) {
            best = t;
        }
    }
    return best;
}

}  // namespace

RepresentativeTriangles assign_representative_triangles(
    std::span<const geometry::Triangle> triangles, const geometry::MeshTopology& topology) {
    const std::size_t num_vertices = topology.vertex_triangle_offsets.size() - 1;
    RepresentativeTriangles r;
    r.vertex_owner.assign(num_vertices, -1);
    r.edge_owner.assign(topology.num_edges(), -1);
    r.owned.assign(triangles.size(), OwnedFeatures{});
    std::vector<int> load(triangles.size(), 0);

    for (std::size_t e = 0; e < topology.num_edges(); ++e) {
        const std::int32_t t =
            least_loaded(topology.triangles_of_edge(static_cast<std::int32_t>(e)), load);
        PLIANT_CHECK_GE(t, 0);
        r.edge_owner[e] = t;
        ++load[static_cast<std::size_t>(t)];
        OwnedFeatures& owned = r.owned[static_cast<std::size_t>(t)];
        owned.edges[owned.num_edges++] = static_cast<std::int32_t>(e);
    }
    for (std::size_t v = 0; v < num_vertices; ++v) {
        const std::int32_t t =
            least_loaded(topology.triangles_of_vertex(static_cast<std::int32_t>(v)), load);
        if (t < 0) {
            continue;
        }
        r.vertex_owner[v] = t;
        ++load[static_cast<std::size_t>(t)];
        OwnedFeatures& owned = r.owned[static_cast<std::size_t>(t)];
        owned.vertices[owned.num_vertices++] = static_cast<std::int32_t>(v);
    }
    return r;
}

}  // namespace pliant::collision
