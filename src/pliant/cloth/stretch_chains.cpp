#include "pliant/cloth/stretch_chains.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <tuple>

#include "pliant/cloth/constraint_coloring.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/group_by_key.hpp"

namespace pliant::cloth {

namespace {

// Edges at least this far from straight ahead (cos of the angle between the directions away
// from the vertex at most -1/2: 120°) continue each other.
constexpr double MAX_PAIR_COSINE = -0.5;

// A chain: its vertices in order, and the edge (index into the edge list) between each two.
struct Chain {
    std::vector<std::int32_t> vertices;
    std::vector<std::int32_t> edges;
};

// Pairs the edges at every vertex and follows the pairs into chains, in index order.
std::vector<Chain> follow_chains(std::span<const std::array<std::int32_t, 2>> edges,
                                 std::span<const Vec3d> positions) {
    const std::size_t num_edges = edges.size();
    const std::size_t num_vertices = positions.size();
    // Incident edges per vertex, ascending.
    std::vector<std::int32_t> ends(2 * num_edges);
    for (std::size_t e = 0; e < num_edges; ++e) {
        ends[2 * e] = edges[e][0];
        ends[2 * e + 1] = edges[e][1];
    }
    std::vector<std::int32_t> offsets;
    std::vector<std::int32_t> incident;
    group_by_key(ends, num_vertices, offsets, incident, 2);
    const auto other_end = [&](std::int32_t e, std::int32_t v) {
        const auto& edge = edges[static_cast<std::size_t>(e)];
        return edge[0] == v ? edge[1] : edge[0];
    };
    const auto side_of = [&](std::int32_t e, std::int32_t v) {
        return edges[static_cast<std::size_t>(e)][0] == v ? 0 : 1;
    };

    // partner[2 e + s]: the edge that continues e through its end s, or -1.
    std::vector<std::int32_t> partner(2 * num_edges, -1);
    std::vector<std::tuple<double, std::int32_t, std::int32_t>> pairs;
    std::vector<Vec3d> directions;
    for (std::size_t v = 0; v < num_vertices; ++v) {
        const auto first = static_cast<std::size_t>(offsets[v]);
        const auto count = static_cast<std::size_t>(offsets[v + 1]) - first;
        directions.assign(count, Vec3d{0.0, 0.0, 0.0});
        for (std::size_t i = 0; i < count; ++i) {
            const std::int32_t e = incident[first + i];
            const Vec3d d =
                positions[static_cast<std::size_t>(other_end(e, static_cast<std::int32_t>(v)))] -
                positions[v];
            const double length = norm(d);
            if (length > 0.0) {
                directions[i] = d * (1.0 / length);
            }
        }
        pairs.clear();
        for (std::size_t i = 0; i < count; ++i) {
            for (std::size_t j = i + 1; j < count; ++j) {
                const double cosine = dot(directions[i], directions[j]);
                if (cosine <= MAX_PAIR_COSINE) {
                    pairs.emplace_back(cosine, incident[first + i], incident[first + j]);
                }
            }
        }
        std::sort(pairs.begin(), pairs.end());
        for (const auto& [cosine, a, b] : pairs) {
            const auto vi = static_cast<std::int32_t>(v);
            const std::size_t slot_a = 2 * static_cast<std::size_t>(a) + side_of(a, vi);
            const std::size_t slot_b = 2 * static_cast<std::size_t>(b) + side_of(b, vi);
            if (partner[slot_a] < 0 && partner[slot_b] < 0) {
                partner[slot_a] = b;
                partner[slot_b] = a;
            }
        }
    }

    // Follow the chains from their ends: an edge end without a partner, or whose partner is
    // already in a chain.
    std::vector<Chain> chains;
    std::vector<std::uint8_t> visited(num_edges, 0);
    std::vector<std::int32_t> stamp(num_vertices, -1);  // the chain a vertex is in
    std::vector<std::int32_t> cut;                      // edges whose chain was cut before them
    const auto is_end = [&](std::int32_t e, int side) {
        const std::int32_t p =
            partner[2 * static_cast<std::size_t>(e) + static_cast<std::size_t>(side)];
        return p < 0 || visited[static_cast<std::size_t>(p)] != 0;
    };
    const auto walk = [&](std::int32_t e, int start_side) {
        const auto id = static_cast<std::int32_t>(chains.size());
        Chain chain;
        std::int32_t v = edges[static_cast<std::size_t>(e)][static_cast<std::size_t>(start_side)];
        chain.vertices.push_back(v);
        stamp[static_cast<std::size_t>(v)] = id;
        while (true) {
            visited[static_cast<std::size_t>(e)] = 1;
            chain.edges.push_back(e);
            v = other_end(e, v);
            chain.vertices.push_back(v);
            stamp[static_cast<std::size_t>(v)] = id;
            const std::int32_t next =
                partner[2 * static_cast<std::size_t>(e) + static_cast<std::size_t>(side_of(e, v))];
            if (next < 0 || visited[static_cast<std::size_t>(next)] != 0) {
                break;
            }
            if (stamp[static_cast<std::size_t>(other_end(next, v))] == id) {
                cut.push_back(next);  // it would visit a vertex twice: next starts a chain
                break;
            }
            e = next;
        }
        chains.push_back(std::move(chain));
    };
    const auto walk_cut = [&]() {
        // walk() may append to cut: an index loop (a range loop's iterators would dangle).
        for (std::size_t i = 0; i < cut.size(); ++i) {  // NOLINT(modernize-loop-convert)
            const std::int32_t e = cut[i];
            if (visited[static_cast<std::size_t>(e)] == 0) {
                walk(e, is_end(e, 0) ? 0 : 1);
            }
        }
        cut.clear();
    };
    for (std::size_t e = 0; e < num_edges; ++e) {
        const auto ei = static_cast<std::int32_t>(e);
        if (visited[e] == 0 && (is_end(ei, 0) || is_end(ei, 1))) {
            walk(ei, is_end(ei, 0) ? 0 : 1);
            walk_cut();
        }
    }
    for (std::size_t e = 0; e < num_edges; ++e) {  // the edges left lie on cycles: cut at e
        if (visited[e] == 0) {
            walk(static_cast<std::int32_t>(e), 0);
            walk_cut();
        }
    }
    return chains;
}

}  // namespace

StretchChains::StretchChains(std::span<const std::array<std::int32_t, 2>> edges,
                             std::span<const double> rest, std::span<const Vec3d> positions)
    : m_padding_vertex(static_cast<std::int32_t>(positions.size())) {
    const std::size_t num_vertices = positions.size();
    std::vector<Chain> chains = follow_chains(edges, positions);
    // Colour the chains, longest first (ties in the order they were followed): colour_constraints
    // visits its constraints in index order, so constraint i is chain by_length[i].
    std::vector<std::int32_t> by_length(chains.size());
    for (std::size_t c = 0; c < chains.size(); ++c) {
        by_length[c] = static_cast<std::int32_t>(c);
    }
    std::stable_sort(by_length.begin(), by_length.end(), [&](std::int32_t a, std::int32_t b) {
        return chains[static_cast<std::size_t>(a)].edges.size() >
               chains[static_cast<std::size_t>(b)].edges.size();
    });
    const auto chain_of = [&](std::int64_t i) -> const Chain& {
        return chains[static_cast<std::size_t>(by_length[static_cast<std::size_t>(i)])];
    };
    ConstraintColoring coloring;
    try {
        coloring = color_constraints(
            static_cast<std::int64_t>(chains.size()), static_cast<std::int64_t>(num_vertices),
            [&](std::int64_t i) { return std::span<const std::int32_t>(chain_of(i).vertices); });
    } catch (const InvalidInput& e) {
        throw InvalidInput(fmt::format(
            "cloth: stretch chains: a chain meets chains of 64 families, expected at most 63 "
            "(vertices with fewer edges, or material.stretch_solver \"edges\"): {}",
            e.what()));
    }

    // Families, and their chains four by four as packets.
    for (std::int32_t color = 0; color < coloring.num_colors(); ++color) {
        // The colour's chains, longest first (ascending constraint index).
        const std::span<const std::int32_t> family = coloring.color(color);
        for (std::size_t first = 0; first < family.size(); first += 4) {
            const auto edge_rows = static_cast<std::int32_t>(chain_of(family[first]).edges.size());
            for (std::int32_t row = 0; row <= edge_rows; ++row) {
                for (std::size_t lane = 0; lane < 4; ++lane) {
                    std::int32_t v = m_padding_vertex;
                    double length = -1.0;
                    std::int32_t edge = -1;
                    if (first + lane < family.size()) {
                        const Chain& chain = chain_of(family[first + lane]);
                        const auto last = static_cast<std::int32_t>(chain.edges.size());
                        v = chain.vertices[static_cast<std::size_t>(std::min(row, last))];
                        if (row < last) {
                            edge = chain.edges[static_cast<std::size_t>(row)];
                            length = rest[static_cast<std::size_t>(edge)];
                        }
                    }
                    m_vertex_rows.push_back(v);
                    if (row < edge_rows) {
                        m_rest_rows.push_back(length);
                        m_edge_index_rows.push_back(edge);
                    }
                }
            }
            m_edge_rows.push_back(m_edge_rows.back() + edge_rows);
        }
        for (const std::int32_t i : family) {  // laid out: its vertices move to m_chains
            m_chains.push_back(std::move(
                chains[static_cast<std::size_t>(by_length[static_cast<std::size_t>(i)])].vertices));
        }
        m_family_packets.push_back(num_packets());
    }
}

detail::ChainPacket StretchChains::packet(std::int32_t p) const {
    const auto rows = static_cast<std::size_t>(m_edge_rows[static_cast<std::size_t>(p)]);
    return {
        m_vertex_rows.data() + 4 * (rows + static_cast<std::size_t>(p)),
        m_rest_rows.data() + 4 * rows, m_edge_index_rows.data() + 4 * rows,
        m_edge_rows[static_cast<std::size_t>(p) + 1] - m_edge_rows[static_cast<std::size_t>(p)]};
}

}  // namespace pliant::cloth
