#include "pliant/cloth/edge_strain.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {

EdgeStrain::EdgeStrain(std::span<const Vec3d> rest_positions,
                       std::span<const geometry::Triangle> triangles)
    : m_num_vertices(rest_positions.size()) {
    const geometry::MeshTopology topology =
        geometry::build_topology(triangles, rest_positions.size());
    m_edges.reserve(topology.num_edges());
    m_rest_lengths.reserve(topology.num_edges());
    for (const geometry::Edge& e : topology.edges) {
        const double length = norm(rest_positions[static_cast<std::size_t>(e[1])] -
                                   rest_positions[static_cast<std::size_t>(e[0])]);
        if (length > 0.0) {
            m_edges.push_back(e);
            m_rest_lengths.push_back(length);
        }
    }
}

StrainStats EdgeStrain::measure(std::span<const Vec3d> positions) const {
    if (positions.size() != m_num_vertices) {
        throw InvalidInput(fmt::format("edge strain: {} positions, expected {} (the rest shape's)",
                                       positions.size(), m_num_vertices));
    }
    StrainStats stats;
    if (m_edges.empty()) {
        return stats;
    }
    std::vector<double> strain(m_edges.size());
    for (std::size_t i = 0; i < m_edges.size(); ++i) {
        const geometry::Edge& e = m_edges[i];
        const double length = norm(positions[static_cast<std::size_t>(e[1])] -
                                   positions[static_cast<std::size_t>(e[0])]);
        strain[i] = length / m_rest_lengths[i] - 1.0;
        stats.over_10_percent += strain[i] > 0.1 ? 1 : 0;
        stats.over_100_percent += strain[i] > 1.0 ? 1 : 0;
    }
    // Nearest-rank percentiles: the value at index ceil(q·n) - 1 of the sorted strains.
    const auto percentile = [&](double q) {
        const auto rank = static_cast<std::ptrdiff_t>(
            std::max<double>(0.0, std::ceil(q * static_cast<double>(strain.size())) - 1.0));
        std::nth_element(strain.begin(), strain.begin() + rank, strain.end());
        return strain[static_cast<std::size_t>(rank)];
    };
    stats.max = *std::max_element(strain.begin(), strain.end());
    stats.p99 = percentile(0.99);
    stats.p90 = percentile(0.90);
    // Compression is not stretch: report 0 when the edges are at most at rest.
    stats.p90 = std::max(stats.p90, 0.0);
    stats.p99 = std::max(stats.p99, 0.0);
    stats.max = std::max(stats.max, 0.0);
    return stats;
}

}  // namespace pliant::cloth
