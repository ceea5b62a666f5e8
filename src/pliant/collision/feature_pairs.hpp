// Feature pairs: the output of the self-collision broad phase and the input of the narrow phase.
#pragma once

#include <cstdint>
#include <vector>

namespace pliant::collision {

// A vertex against a triangle that does not contain it.
struct VertexFacePair {
    std::int32_t vertex;
    std::int32_t face;
    // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 flags the synthesized `<=> 0`.
    friend constexpr auto operator<=>(const VertexFacePair&, const VertexFacePair&) = default;
};

// Two edges (indices into MeshTopology::edges) that share no vertex.
struct EdgeEdgePair {
    std::int32_t edge_a;
    std::int32_t edge_b;
    // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 flags the synthesized `<=> 0`.
    friend constexpr auto operator<=>(const EdgeEdgePair&, const EdgeEdgePair&) = default;
};

struct FeaturePairs {
    std::vector<VertexFacePair> vertex_face;
    std::vector<EdgeEdgePair> edge_edge;
};

}  // namespace pliant::collision
