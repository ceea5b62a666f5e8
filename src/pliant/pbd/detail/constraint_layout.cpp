#include "pliant/pbd/detail/constraint_layout.hpp"

#include <algorithm>
#include <cstddef>
#include <utility>

namespace pliant::pbd::detail {

std::vector<std::int32_t> vertex_lattice_axis(const TetGrid& grid, int axis) {
    std::vector<std::int32_t> level;
    level.reserve(grid.vertex_lattice.size());
    for (const auto& lattice : grid.vertex_lattice) {
        level.push_back(lattice[static_cast<std::size_t>(axis)]);
    }
    return level;
}

template <std::size_t K>
std::vector<std::int64_t> colour_skews(const ConstraintColoring& coloring,
                                       const std::vector<std::array<std::int32_t, K>>& constraints,
                                       const std::vector<std::int32_t>& keys,
                                       const std::vector<std::int32_t>& vertex_level) {
    const std::int32_t num_colors = coloring.num_colors();
    if (num_colors > 64) {
        return {};
    }
    // Per vertex: bit c of `below` when colour c holds it in a constraint of key level_v − 1, of
    // `level` of key level_v.
    std::vector<std::pair<std::uint64_t, std::uint64_t>> masks(vertex_level.size(), {0, 0});
    for (std::int32_t c = 0; c < num_colors; ++c) {
        const std::uint64_t bit = std::uint64_t{1} << c;
        for (std::int64_t q = coloring.offsets[static_cast<std::size_t>(c)];
             q < coloring.offsets[static_cast<std::size_t>(c) + 1]; ++q) {
            for (const std::int32_t v : constraints[static_cast<std::size_t>(q)]) {
                const std::int32_t offset =
                    keys[static_cast<std::size_t>(q)] - vertex_level[static_cast<std::size_t>(v)];
                if (offset == -1) {
                    masks[static_cast<std::size_t>(v)].first |= bit;
                } else if (offset == 0) {
                    masks[static_cast<std::size_t>(v)].second |= bit;
                } else {
                    return {};
                }
            }
        }
    }
    std::sort(masks.begin(), masks.end());
    masks.erase(std::unique(masks.begin(), masks.end()), masks.end());
    // Colours in order: every bound on skew[c'] comes from colours c < c', already final.
    std::vector<std::int64_t> skew(static_cast<std::size_t>(num_colors), 0);
    for (std::int32_t later = 0; later < num_colors; ++later) {
        for (const auto& [below, level] : masks) {
            if (((below | level) >> later & 1) == 0) {
                continue;
            }
            const std::int64_t later_offset = (below >> later & 1) != 0 ? -1 : 0;
            for (std::int32_t c = 0; c < later; ++c) {
                if (((below | level) >> c & 1) != 0) {
                    const std::int64_t offset = (below >> c & 1) != 0 ? -1 : 0;
                    skew[static_cast<std::size_t>(later)] =
                        std::max(skew[static_cast<std::size_t>(later)],
                                 skew[static_cast<std::size_t>(c)] + offset - later_offset);
                }
            }
        }
    }
    return skew;
}

template std::vector<std::int64_t> colour_skews<2>(const ConstraintColoring&,
                                                   const std::vector<std::array<std::int32_t, 2>>&,
                                                   const std::vector<std::int32_t>&,
                                                   const std::vector<std::int32_t>&);
template std::vector<std::int64_t> colour_skews<4>(const ConstraintColoring&,
                                                   const std::vector<std::array<std::int32_t, 4>>&,
                                                   const std::vector<std::int32_t>&,
                                                   const std::vector<std::int32_t>&);

namespace {

// The blocking of constraints (in colour order, sorted by key within each colour; vertex_z:
// lattice z per vertex); none when a key is out of order or a vertex lies outside layers z, z + 1
// of a constraint holding it, or for more than 64 colours.
template <std::size_t K>
LayerBlocking block_layers(const ConstraintColoring& coloring,
                           const std::vector<std::array<std::int32_t, K>>& constraints,
                           const std::vector<std::int32_t>& keys, std::int64_t num_layers,
                           const std::vector<std::int32_t>& vertex_z) {
    const std::int32_t num_colors = coloring.num_colors();
    if (num_colors > 64 || num_layers <= 0) {
        return {};
    }
    LayerBlocking blocking;
    blocking.num_layers = num_layers;
    blocking.layer_begin.resize(static_cast<std::size_t>(num_colors * (num_layers + 1)));
    for (std::int32_t c = 0; c < num_colors; ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        const auto* first = keys.data() + begin;
        const auto* last = keys.data() + end;
        if (!std::is_sorted(first, last) || *first < 0 || *(last - 1) >= num_layers) {
            return {};
        }
        for (std::int64_t z = 0; z <= num_layers; ++z) {
            blocking.layer_begin[static_cast<std::size_t>(c * (num_layers + 1) + z)] =
                std::lower_bound(first, last, z) - first;
        }
    }
    blocking.skew = colour_skews(coloring, constraints, keys, vertex_z);
    if (std::ssize(blocking.skew) != num_colors) {
        return {};
    }
    for (const std::int64_t skew : blocking.skew) {
        blocking.max_skew = std::max(blocking.max_skew, skew);
    }
    return blocking;
}

// Within each colour, orders the edges (and their rest lengths) by layer (the lower lattice z of
// their vertices), stably (the order within a colour does not change a result: its edges share no
// vertex).
void sort_edges_by_layer(const ConstraintColoring& coloring,
                         const std::vector<std::int32_t>& vertex_z,
                         std::vector<std::array<std::int32_t, 2>>& edges,
                         std::vector<float>& rest_lengths) {
    std::vector<std::int64_t> perm;
    std::vector<std::array<std::int32_t, 2>> sorted_edges;
    std::vector<float> sorted_lengths;
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        perm.resize(static_cast<std::size_t>(end - begin));
        for (std::int64_t q = begin; q < end; ++q) {
            perm[static_cast<std::size_t>(q - begin)] = q;
        }
        const auto layer = [&](std::int64_t q) {
            const auto& e = edges[static_cast<std::size_t>(q)];
            return std::min(vertex_z[static_cast<std::size_t>(e[0])],
                            vertex_z[static_cast<std::size_t>(e[1])]);
        };
        std::stable_sort(perm.begin(), perm.end(),
                         [&](std::int64_t p, std::int64_t q) { return layer(p) < layer(q); });
        sorted_edges.clear();
        sorted_lengths.clear();
        for (const std::int64_t q : perm) {
            sorted_edges.push_back(edges[static_cast<std::size_t>(q)]);
            sorted_lengths.push_back(rest_lengths[static_cast<std::size_t>(q)]);
        }
        std::copy(sorted_edges.begin(), sorted_edges.end(),
                  edges.begin() + static_cast<std::ptrdiff_t>(begin));
        std::copy(sorted_lengths.begin(), sorted_lengths.end(),
                  rest_lengths.begin() + static_cast<std::ptrdiff_t>(begin));
    }
}
}  // namespace

EdgeConstraints layout_edge_constraints(ConstraintColoring coloring,
                                        std::span<const std::array<std::int32_t, 2>> edges,
                                        std::span<const Vec3f> rest, const TetGrid* grid) {
    EdgeConstraints out;
    out.coloring = std::move(coloring);
    out.vertices.resize(edges.size());
    out.rest_lengths0.resize(edges.size());
    for (std::size_t k = 0; k < out.coloring.order.size(); ++k) {
        const auto& e = edges[static_cast<std::size_t>(out.coloring.order[k])];
        out.vertices[k] = e;
        out.rest_lengths0[k] =
            static_cast<float>(norm(vec3_cast<double>(rest[static_cast<std::size_t>(e[0])]) -
                                    vec3_cast<double>(rest[static_cast<std::size_t>(e[1])])));
    }
    if (grid == nullptr) {
        out.rest_lengths = out.rest_lengths0;
        return out;
    }
    const std::vector<std::int32_t> vertex_z = vertex_lattice_axis(*grid, 2);
    sort_edges_by_layer(out.coloring, vertex_z, out.vertices, out.rest_lengths0);
    out.rest_lengths = out.rest_lengths0;
    std::vector<std::int32_t> keys(out.vertices.size());
    for (std::size_t k = 0; k < keys.size(); ++k) {
        keys[k] = std::min(vertex_z[static_cast<std::size_t>(out.vertices[k][0])],
                           vertex_z[static_cast<std::size_t>(out.vertices[k][1])]);
    }
    out.blocking =
        block_layers(out.coloring, out.vertices, keys, std::int64_t{grid->cells[2]} + 1, vertex_z);
    return out;
}

TetConstraints layout_tet_constraints(ConstraintColoring coloring,
                                      std::span<const geometry::Tet> tets,
                                      std::span<const double> rest_volumes, const TetGrid* grid) {
    TetConstraints out;
    out.coloring = std::move(coloring);
    out.vertices.resize(tets.size());
    out.rest_volumes0.resize(tets.size());
    for (std::size_t k = 0; k < out.coloring.order.size(); ++k) {
        const auto t = static_cast<std::size_t>(out.coloring.order[k]);
        out.vertices[k] = tets[t];
        out.rest_volumes0[k] = static_cast<float>(rest_volumes[t]);
    }
    out.rest_volumes = out.rest_volumes0;
    if (grid == nullptr) {
        return out;
    }
    const std::vector<std::int32_t> vertex_z = vertex_lattice_axis(*grid, 2);
    std::vector<std::int32_t> keys(out.vertices.size());
    const std::int64_t cells_xy = std::int64_t{grid->cells[0]} * grid->cells[1];
    for (std::size_t k = 0; k < keys.size(); ++k) {
        keys[k] = static_cast<std::int32_t>(
            grid->tet_cell[static_cast<std::size_t>(out.coloring.order[k])] / cells_xy);
    }
    out.blocking = block_layers(out.coloring, out.vertices, keys, grid->cells[2], vertex_z);
    return out;
}

}  // namespace pliant::pbd::detail
