#include "pliant/collision/orphan_set.hpp"

#include <algorithm>

#include "pliant/collision/incidence.hpp"

namespace pliant::collision {

FeaturePairs build_orphan_set(std::span<const geometry::Triangle> triangles,
                              const geometry::MeshTopology& topology,
                              const RepresentativeTriangles& owners) {
    FeaturePairs orphans;
    std::vector<std::int32_t> neighbours;
    // Owned VF candidates of `from` against face `to`, owned EE candidates between the two.
    const auto add_pair = [&](std::int32_t a, std::int32_t b) {
        const geometry::Triangle& ta = triangles[static_cast<std::size_t>(a)];
        const geometry::Triangle& tb = triangles[static_cast<std::size_t>(b)];
        const OwnedFeatures& owned_a = owners.owned[static_cast<std::size_t>(a)];
        const OwnedFeatures& owned_b = owners.owned[static_cast<std::size_t>(b)];
        for (int k = 0; k < owned_a.num_vertices; ++k) {
            if (!contains_vertex(tb, owned_a.vertices[k])) {
                orphans.vertex_face.push_back({owned_a.vertices[k], b});
            }
        }
        for (int k = 0; k < owned_b.num_vertices; ++k) {
            if (!contains_vertex(ta, owned_b.vertices[k])) {
                orphans.vertex_face.push_back({owned_b.vertices[k], a});
            }
        }
        for (int i = 0; i < owned_a.num_edges; ++i) {
            for (int j = 0; j < owned_b.num_edges; ++j) {
                const std::int32_t ea = owned_a.edges[i];
                const std::int32_t eb = owned_b.edges[j];
                if (!share_vertex(topology.edges[static_cast<std::size_t>(ea)],
                                  topology.edges[static_cast<std::size_t>(eb)])) {
                    orphans.edge_edge.push_back({std::min(ea, eb), std::max(ea, eb)});
                }
            }
        }
    };
    for (std::size_t a = 0; a < triangles.size(); ++a) {
        neighbours.clear();
        for (const std::int32_t v : triangles[a]) {
            for (const std::int32_t b : topology.triangles_of_vertex(v)) {
                if (b > static_cast<std::int32_t>(a)) {
                    neighbours.push_back(b);
                }
            }
        }
        std::sort(neighbours.begin(), neighbours.end());
        neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
        for (const std::int32_t b : neighbours) {
            add_pair(static_cast<std::int32_t>(a), b);
        }
    }
    std::sort(orphans.vertex_face.begin(), orphans.vertex_face.end());
    std::sort(orphans.edge_edge.begin(), orphans.edge_edge.end());
    return orphans;
}

}  // namespace pliant::collision
