#include "pliant/cloth/strain_hierarchy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <tuple>
#include <utility>

#include "pliant/core/host_device.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t LIMIT_GRAIN = 1024;
constexpr std::int64_t CHILD_GRAIN = 2048;
// The greedy colouring gives a limit p–q the smallest colour unused at p and q; with at most 32
// limits per vertex that is one of the first 63 (the colouring allows 64). A level with more
// ends the hierarchy instead (it happens only around vertices of huge valence).
constexpr std::int64_t MAX_LIMITS_PER_VERTEX = 32;
// A level that keeps more than this fraction of the finer level's vertices ends the hierarchy:
// it would cost a pass without carrying corrections much further.
constexpr double MAX_KEPT_FRACTION = 0.75;

struct Link {
    std::int32_t p;
    std::int32_t q;
    double rest;
};

// Neighbours of every vertex over `links`, as CSR on mesh indices.
struct Adjacency {
    std::vector<std::int32_t> offsets;
    std::vector<std::int32_t> neighbours;
    std::vector<double> lengths;

    Adjacency(std::int64_t num_vertices, const std::vector<Link>& links)
        : offsets(static_cast<std::size_t>(num_vertices) + 1, 0) {
        for (const Link& link : links) {
            ++offsets[static_cast<std::size_t>(link.p) + 1];
            ++offsets[static_cast<std::size_t>(link.q) + 1];
        }
        for (std::size_t v = 1; v < offsets.size(); ++v) {
            offsets[v] += offsets[v - 1];
        }
        neighbours.resize(static_cast<std::size_t>(offsets.back()));
        lengths.resize(neighbours.size());
        std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
        for (const Link& link : links) {
            const auto put = [&](std::int32_t from, std::int32_t to) {
                const auto slot = static_cast<std::size_t>(fill[static_cast<std::size_t>(from)]++);
                neighbours[slot] = to;
                lengths[slot] = link.rest;
            };
            put(link.p, link.q);
            put(link.q, link.p);
        }
    }

    std::size_t begin(std::int32_t v) const {
        return static_cast<std::size_t>(offsets[static_cast<std::size_t>(v)]);
    }
    std::size_t end(std::int32_t v) const {
        return static_cast<std::size_t>(offsets[static_cast<std::size_t>(v) + 1]);
    }
};

// Dijkstra over the rest mesh's edges, reusing its arrays between searches (only the vertices a
// search touched are reset).
class ShortestPaths {
public:
    explicit ShortestPaths(std::int64_t num_vertices)
        : m_distance(static_cast<std::size_t>(num_vertices),
                     std::numeric_limits<double>::infinity()) {}

    // Distances from source until `targets` vertices for which is_target(v) holds are settled
    // (or everything reachable is).
    template <typename IsTarget>
    void search(const Adjacency& mesh, std::int32_t source, IsTarget&& is_target,
                std::size_t targets) {
        for (const std::int32_t v : m_touched) {
            m_distance[static_cast<std::size_t>(v)] = std::numeric_limits<double>::infinity();
        }
        m_touched.clear();
        using Entry = std::pair<double, std::int32_t>;
        std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
        m_distance[static_cast<std::size_t>(source)] = 0.0;
        m_touched.push_back(source);
        queue.push({0.0, source});
        while (!queue.empty() && targets > 0) {
            const auto [d, v] = queue.top();
            queue.pop();
            if (d > m_distance[static_cast<std::size_t>(v)]) {
                continue;  // a stale entry
            }
            if (is_target(v)) {
                --targets;
            }
            for (std::size_t k = mesh.begin(v); k < mesh.end(v); ++k) {
                const std::int32_t w = mesh.neighbours[k];
                const double through = d + mesh.lengths[k];
                double& best = m_distance[static_cast<std::size_t>(w)];
                if (through < best) {
                    if (std::isinf(best)) {
                        m_touched.push_back(w);
                    }
                    best = through;
                    queue.push({through, w});
                }
            }
        }
    }

    double distance(std::int32_t v) const { return m_distance[static_cast<std::size_t>(v)]; }

private:
    std::vector<double> m_distance;
    std::vector<std::int32_t> m_touched;
};

}  // namespace

StrainHierarchy::StrainHierarchy(std::int64_t num_vertices, std::span<const geometry::Edge> edges,
                                 std::span<const double> rest_lengths) {
    std::vector<Link> links;
    links.reserve(edges.size());
    for (std::size_t e = 0; e < edges.size(); ++e) {
        links.push_back({std::min(edges[e][0], edges[e][1]), std::max(edges[e][0], edges[e][1]),
                         rest_lengths[e]});
    }
    const Adjacency mesh(num_vertices, links);
    ShortestPaths paths(num_vertices);
    // The finer level's vertices that have a link (isolated ones take no part).
    std::vector<std::int32_t> vertices;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(num_vertices); ++v) {
        if (mesh.end(v) > mesh.begin(v)) {
            vertices.push_back(v);
        }
    }
    enum : std::uint8_t { UNDECIDED, KEPT, DROPPED };
    std::vector<std::uint8_t> state(static_cast<std::size_t>(num_vertices));
    while (m_levels.size() < static_cast<std::size_t>(MAX_LEVELS) &&
           static_cast<std::int64_t>(vertices.size()) >= MIN_VERTICES) {
        const Adjacency adjacency(num_vertices, links);
        // Maximal independent set, greedy in ascending order.
        Level level;
        for (const std::int32_t v : vertices) {
            state[static_cast<std::size_t>(v)] = UNDECIDED;
        }
        for (const std::int32_t v : vertices) {
            if (state[static_cast<std::size_t>(v)] != UNDECIDED) {
                level.children.push_back(v);
                continue;
            }
            state[static_cast<std::size_t>(v)] = KEPT;
            level.vertices.push_back(v);
            for (std::size_t k = adjacency.begin(v); k < adjacency.end(v); ++k) {
                state[static_cast<std::size_t>(adjacency.neighbours[k])] = DROPPED;
            }
        }
        if (static_cast<double>(level.vertices.size()) >
            MAX_KEPT_FRACTION * static_cast<double>(vertices.size())) {
            break;
        }
        // Parents and weights; every two parents of a child become a coarse pair.
        std::vector<Link> coarse;
        level.parent_offsets.push_back(0);
        std::vector<double> lengths;  // rest length child–parent, per parent of the child
        for (const std::int32_t c : level.children) {
            const std::size_t first = level.parents.size();
            lengths.clear();
            for (std::size_t k = adjacency.begin(c); k < adjacency.end(c); ++k) {
                const std::int32_t p = adjacency.neighbours[k];
                if (state[static_cast<std::size_t>(p)] == KEPT) {
                    level.parents.push_back(p);
                    lengths.push_back(adjacency.lengths[k]);
                }
            }
            // Inverse rest distance weights; a parent on the child (rest distance 0) takes all.
            const bool coincident =
                std::any_of(lengths.begin(), lengths.end(), [](double l) { return !(l > 0.0); });
            const auto weight = [&](double l) {
                return coincident ? (l > 0.0 ? 0.0 : 1.0) : 1.0 / l;
            };
            double total = 0.0;
            for (const double l : lengths) {
                total += weight(l);
            }
            for (const double l : lengths) {
                level.weights.push_back(weight(l) / total);
            }
            for (std::size_t i = first; i < level.parents.size(); ++i) {
                for (std::size_t j = i + 1; j < level.parents.size(); ++j) {
                    coarse.push_back({std::min(level.parents[i], level.parents[j]),
                                      std::max(level.parents[i], level.parents[j]), 0.0});
                }
            }
            level.parent_offsets.push_back(static_cast<std::int32_t>(level.parents.size()));
        }
        std::sort(coarse.begin(), coarse.end(), [](const Link& a, const Link& b) {
            return std::tie(a.p, a.q) < std::tie(b.p, b.q);
        });
        coarse.erase(
            std::unique(coarse.begin(), coarse.end(),
                        [](const Link& a, const Link& b) { return a.p == b.p && a.q == b.q; }),
            coarse.end());
        if (coarse.empty()) {
            break;
        }
        const Adjacency coarse_adjacency(num_vertices, coarse);
        bool too_many = false;
        for (const std::int32_t v : level.vertices) {
            too_many = too_many ||
                       static_cast<std::int64_t>(coarse_adjacency.end(v) -
                                                 coarse_adjacency.begin(v)) > MAX_LIMITS_PER_VERTEX;
        }
        if (too_many) {
            break;
        }
        // Rest lengths: the shortest paths along the mesh's edges (pairs sorted by p: one search
        // from each p reaches all its q).
        for (std::size_t first = 0; first < coarse.size();) {
            std::size_t last = first;
            while (last < coarse.size() && coarse[last].p == coarse[first].p) {
                ++last;
            }
            paths.search(
                mesh, coarse[first].p,
                [&](std::int32_t v) {
                    return std::any_of(coarse.begin() + static_cast<std::ptrdiff_t>(first),
                                       coarse.begin() + static_cast<std::ptrdiff_t>(last),
                                       [&](const Link& l) { return l.q == v; });
                },
                last - first);
            for (std::size_t k = first; k < last; ++k) {
                coarse[k].rest = paths.distance(coarse[k].q);
            }
            first = last;
        }
        std::vector<std::array<std::int32_t, 2>> ends;
        std::vector<double> rest;
        for (const Link& link : coarse) {
            ends.push_back({link.p, link.q});
            rest.push_back(link.rest);
        }
        level.limits = color_edges(ends, rest, num_vertices);
        vertices.clear();
        for (const std::int32_t v : level.vertices) {
            if (coarse_adjacency.end(v) > coarse_adjacency.begin(v)) {
                vertices.push_back(v);
            }
        }
        links = std::move(coarse);
        m_levels.push_back(std::move(level));
    }
    if (!m_levels.empty()) {
        m_start.resize(static_cast<std::size_t>(num_vertices));
    }
}

std::size_t StrainHierarchy::num_limits() const {
    std::size_t count = 0;
    for (const Level& level : m_levels) {
        count += level.limits.p.size();
    }
    return count;
}

void StrainHierarchy::project(detail::PackedVertex* x, double max_strain, double max_move) {
    if (m_levels.empty()) {
        return;
    }
    const std::vector<std::int32_t>& kept = m_levels.front().vertices;
    parallel_for(
        static_cast<std::int64_t>(kept.size()),
        [&](std::int64_t k) {
            const auto v = static_cast<std::size_t>(kept[static_cast<std::size_t>(k)]);
            m_start[v] = {x[v].x, x[v].y, x[v].z};
        },
        CHILD_GRAIN);
    const double scale = 1.0 + max_strain;
    // Levels in reverse order. (A reverse_view range loop does not compile under clang 14's view
    // of libstdc++ 12's ranges, which clang-tidy uses.)
    // NOLINTNEXTLINE(modernize-loop-convert)
    for (auto level = m_levels.rbegin(); level != m_levels.rend(); ++level) {
        const Level& l = *level;
        const ColoredEdges& limits = l.limits;
        for (std::int32_t c = 0; c < limits.colors.num_colors(); ++c) {
            const std::int64_t offset = limits.colors.offsets[static_cast<std::size_t>(c)];
            parallel_for_chunks(
                static_cast<std::int64_t>(limits.colors.color(c).size()), LIMIT_GRAIN,
                [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                    for (std::int64_t k = offset + begin; k < offset + end; ++k) {
                        const auto i = static_cast<std::size_t>(k);
                        detail::limit_stretch(x, limits.p[i], limits.q[i], scale * limits.rest[i],
                                              RELAXATION, max_move);
                    }
                });
        }
        parallel_for(
            static_cast<std::int64_t>(l.children.size()),
            [&](std::int64_t k) {
                const auto child =
                    static_cast<std::size_t>(l.children[static_cast<std::size_t>(k)]);
                if (!(x[child].inverse_mass > 0.0)) {
                    return;
                }
                Vec3d move{0.0, 0.0, 0.0};
                for (auto i =
                         static_cast<std::size_t>(l.parent_offsets[static_cast<std::size_t>(k)]);
                     i <
                     static_cast<std::size_t>(l.parent_offsets[static_cast<std::size_t>(k) + 1]);
                     ++i) {
                    const auto p = static_cast<std::size_t>(l.parents[i]);
                    move += (Vec3d{x[p].x, x[p].y, x[p].z} - m_start[p]) * l.weights[i];
                }
                x[child].x += move.x;
                x[child].y += move.y;
                x[child].z += move.z;
            },
            CHILD_GRAIN);
    }
}

}  // namespace pliant::cloth
