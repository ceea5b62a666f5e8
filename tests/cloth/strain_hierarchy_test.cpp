#include "pliant/cloth/strain_hierarchy.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {
namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

struct Mesh {
    std::vector<Vec3d> positions;
    std::vector<geometry::Triangle> triangles;
    std::vector<geometry::Edge> edges;
    std::vector<double> rest;
};

// n × n quads over a side of `size` metres, optionally folded like an accordion (a rest shape
// that is not flat, so straight distances are shorter than paths along the cloth).
Mesh grid(int n, double size, bool folded = false) {
    const geometry::TriangleMesh flat =
        geometry::make_grid_sheet(n, n, static_cast<float>(size), static_cast<float>(size));
    Mesh m;
    for (const Vec3f& p : flat.positions) {
        Vec3d q = vec3_cast<double>(p);
        if (folded) {
            q.z = 0.2 * size * std::sin(12.0 * q.x / size);
        }
        m.positions.push_back(q);
    }
    m.triangles = flat.triangles;
    m.edges = geometry::build_topology(m.triangles, m.positions.size()).edges;
    for (const geometry::Edge& e : m.edges) {
        m.rest.push_back(norm(m.positions[static_cast<std::size_t>(e[1])] -
                              m.positions[static_cast<std::size_t>(e[0])]));
    }
    return m;
}

StrainHierarchy hierarchy_of(const Mesh& m) {
    return StrainHierarchy(static_cast<std::int64_t>(m.positions.size()), m.edges, m.rest);
}

std::vector<detail::PackedVertex> packed(const std::vector<Vec3d>& positions) {
    std::vector<detail::PackedVertex> x;
    for (const Vec3d& p : positions) {
        x.push_back({p.x, p.y, p.z, 1.0});
    }
    return x;
}

double length(const std::vector<detail::PackedVertex>& x, std::int32_t p, std::int32_t q) {
    const detail::PackedVertex& a = x[static_cast<std::size_t>(p)];
    const detail::PackedVertex& b = x[static_cast<std::size_t>(q)];
    return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                     (a.z - b.z) * (a.z - b.z));
}

// All-pairs shortest paths along the edges (Floyd-Warshall), for small meshes.
std::vector<std::vector<double>> shortest_paths(const Mesh& m) {
    const std::size_t n = m.positions.size();
    std::vector<std::vector<double>> d(n, std::vector<double>(n, INF));
    for (std::size_t v = 0; v < n; ++v) {
        d[v][v] = 0.0;
    }
    for (std::size_t e = 0; e < m.edges.size(); ++e) {
        const auto a = static_cast<std::size_t>(m.edges[e][0]);
        const auto b = static_cast<std::size_t>(m.edges[e][1]);
        d[a][b] = d[b][a] = std::min(d[a][b], m.rest[e]);
    }
    for (std::size_t k = 0; k < n; ++k) {
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t j = 0; j < n; ++j) {
                d[i][j] = std::min(d[i][j], d[i][k] + d[k][j]);
            }
        }
    }
    return d;
}

TEST(StrainHierarchy, LevelsAreMaximalIndependentSetsWithShortestPathRestLengths) {
    for (const bool folded : {false, true}) {
        const Mesh m = grid(12, 1.0, folded);
        const std::vector<std::vector<double>> shortest = shortest_paths(m);
        const StrainHierarchy h = hierarchy_of(m);
        ASSERT_GE(h.num_levels(), 2u);
        // The finer level's vertices and links (rest lengths by vertex pair), starting with the
        // mesh; checked against each coarse level by brute force.
        std::vector<std::int32_t> finer(m.positions.size());
        for (std::size_t v = 0; v < finer.size(); ++v) {
            finer[v] = static_cast<std::int32_t>(v);
        }
        std::map<std::pair<std::int32_t, std::int32_t>, double> links;
        for (std::size_t e = 0; e < m.edges.size(); ++e) {
            links[{std::min(m.edges[e][0], m.edges[e][1]),
                   std::max(m.edges[e][0], m.edges[e][1])}] = m.rest[e];
        }
        const auto rest_of = [&](std::int32_t a, std::int32_t b) {
            const auto it = links.find({std::min(a, b), std::max(a, b)});
            return it == links.end() ? -1.0 : it->second;
        };
        for (std::size_t l = 1; l <= h.num_levels(); ++l) {
            const StrainHierarchy::Level& level = h.level(l);
            const std::set<std::int32_t> kept(level.vertices.begin(), level.vertices.end());
            // Kept and children partition the finer level's linked vertices.
            std::vector<std::int32_t> all = level.vertices;
            all.insert(all.end(), level.children.begin(), level.children.end());
            std::sort(all.begin(), all.end());
            EXPECT_EQ(all, finer) << "level " << l;
            // Independent: no finer link joins two kept vertices.
            for (const auto& [pair, rest] : links) {
                EXPECT_FALSE(kept.count(pair.first) && kept.count(pair.second)) << "level " << l;
            }
            // Maximal: each child's parents are exactly its kept finer neighbours (at least one),
            // weighted by inverse rest distance.
            std::set<std::pair<std::int32_t, std::int32_t>> expected_limits;
            for (std::size_t k = 0; k < level.children.size(); ++k) {
                const std::int32_t c = level.children[k];
                std::map<std::int32_t, double> expected_weights;
                double total = 0.0;
                for (const std::int32_t p : level.vertices) {
                    if (rest_of(c, p) >= 0.0) {
                        expected_weights[p] = 1.0 / rest_of(c, p);
                        total += 1.0 / rest_of(c, p);
                    }
                }
                ASSERT_FALSE(expected_weights.empty()) << "child " << c << " at level " << l;
                std::map<std::int32_t, double> weights;
                for (auto i = level.parent_offsets[k]; i < level.parent_offsets[k + 1]; ++i) {
                    weights[level.parents[static_cast<std::size_t>(i)]] =
                        level.weights[static_cast<std::size_t>(i)];
                }
                ASSERT_EQ(weights.size(), expected_weights.size());
                for (const auto& [p, w] : expected_weights) {
                    ASSERT_TRUE(weights.count(p)) << "child " << c << " parent " << p;
                    EXPECT_NEAR(weights[p], w / total, 1e-12);
                    for (const auto& [q, unused] : expected_weights) {
                        if (p < q) {
                            expected_limits.insert({p, q});
                        }
                    }
                }
            }
            // The limits: every pair of parents of a common child once, at the shortest edge
            // path's length (never shorter than the straight rest distance).
            std::map<std::pair<std::int32_t, std::int32_t>, double> built;
            for (std::size_t k = 0; k < level.limits.p.size(); ++k) {
                built[{level.limits.p[k], level.limits.q[k]}] = level.limits.rest[k];
                const auto p = static_cast<std::size_t>(level.limits.p[k]);
                const auto q = static_cast<std::size_t>(level.limits.q[k]);
                EXPECT_NEAR(level.limits.rest[k], shortest[p][q], 1e-12);
                EXPECT_GE(level.limits.rest[k] * (1.0 + 1e-12),
                          norm(m.positions[p] - m.positions[q]));
            }
            ASSERT_EQ(built.size(), level.limits.p.size()) << "a limit twice at level " << l;
            std::set<std::pair<std::int32_t, std::int32_t>> pairs;
            for (const auto& [pair, rest] : built) {
                pairs.insert(pair);
            }
            EXPECT_EQ(pairs, expected_limits) << "level " << l;
            // No two limits of one colour share a vertex.
            for (std::int32_t colour = 0; colour < level.limits.colors.num_colors(); ++colour) {
                std::set<std::int32_t> used;
                for (auto k = level.limits.colors.offsets[static_cast<std::size_t>(colour)];
                     k < level.limits.colors.offsets[static_cast<std::size_t>(colour) + 1]; ++k) {
                    EXPECT_TRUE(used.insert(level.limits.p[static_cast<std::size_t>(k)]).second);
                    EXPECT_TRUE(used.insert(level.limits.q[static_cast<std::size_t>(k)]).second);
                }
            }
            finer.clear();
            for (const std::int32_t v : level.vertices) {
                if (std::any_of(built.begin(), built.end(), [&](const auto& limit) {
                        return limit.first.first == v || limit.first.second == v;
                    })) {
                    finer.push_back(v);
                }
            }
            links = built;
        }
    }
}

TEST(StrainHierarchy, EngagesInAnyVertexOrderAndIgnoresIsolatedVertices) {
    // The same grid with its vertices numbered at random, and with 3,000 isolated vertices
    // added: as many levels as the row-by-row grid (within one), and limits about as tight
    // (median rest length within 10 % of the straight distance on every level).
    const Mesh ordered = grid(60, 1.0);
    const std::size_t ordered_levels = hierarchy_of(ordered).num_levels();
    ASSERT_GE(ordered_levels, 5u);
    std::vector<std::int32_t> relabel(ordered.positions.size());
    for (std::size_t v = 0; v < relabel.size(); ++v) {
        relabel[v] = static_cast<std::int32_t>(v);
    }
    std::shuffle(relabel.begin(), relabel.end(), std::mt19937(11));
    Mesh shuffled = ordered;
    for (std::size_t v = 0; v < relabel.size(); ++v) {
        shuffled.positions[static_cast<std::size_t>(relabel[v])] = ordered.positions[v];
    }
    for (geometry::Edge& e : shuffled.edges) {
        e = {relabel[static_cast<std::size_t>(e[0])], relabel[static_cast<std::size_t>(e[1])]};
    }
    Mesh isolated = ordered;
    for (int k = 0; k < 3000; ++k) {
        isolated.positions.push_back({5.0 + k, 0.0, 0.0});
    }
    for (const Mesh* m : {&shuffled, &isolated}) {
        const StrainHierarchy h = hierarchy_of(*m);
        EXPECT_GE(h.num_levels() + 1, ordered_levels);
        for (std::size_t l = 1; l <= h.num_levels(); ++l) {
            const auto& level = h.level(l);
            std::vector<double> ratios;
            for (std::size_t k = 0; k < level.limits.p.size(); ++k) {
                ratios.push_back(level.limits.rest[k] /
                                 norm(m->positions[static_cast<std::size_t>(level.limits.p[k])] -
                                      m->positions[static_cast<std::size_t>(level.limits.q[k])]));
            }
            std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
            EXPECT_LT(ratios[ratios.size() / 2], 1.1) << "level " << l;
        }
    }
}

TEST(StrainHierarchy, ACoincidentParentCarriesItsChildAlone) {
    // Rest length 0 on the edge 0-1 (vertex 0 is kept, 1 is its child): 1 follows 0 only.
    Mesh m = grid(8, 1.0);
    for (std::size_t e = 0; e < m.edges.size(); ++e) {
        if (m.edges[e] == geometry::Edge{0, 1}) {
            m.rest[e] = 0.0;
        }
    }
    const StrainHierarchy h = hierarchy_of(m);
    ASSERT_GE(h.num_levels(), 1u);
    const auto& level = h.level(1);
    const auto it = std::find(level.children.begin(), level.children.end(), 1);
    ASSERT_NE(it, level.children.end());
    const auto k = static_cast<std::size_t>(it - level.children.begin());
    ASSERT_GE(level.parent_offsets[k + 1] - level.parent_offsets[k], 2);
    for (auto i = level.parent_offsets[k]; i < level.parent_offsets[k + 1]; ++i) {
        EXPECT_EQ(level.weights[static_cast<std::size_t>(i)],
                  level.parents[static_cast<std::size_t>(i)] == 0 ? 1.0 : 0.0);
    }
}

TEST(StrainHierarchy, ALimitClosesAFifthOfItsExcessUpToTheCapSplitByInverseMass) {
    // p at the origin (inverse mass 1), q at x = 2 (inverse mass 3), limit 1: excess 1.
    const auto pulled = [](double relaxation, double max_move, double wp, double wq) {
        std::vector<detail::PackedVertex> x{{0.0, 0.0, 0.0, wp}, {2.0, 0.0, 0.0, wq}};
        detail::limit_stretch(x.data(), 0, 1, 1.0, relaxation, max_move);
        return std::pair{x[0].x, x[1].x};
    };
    EXPECT_EQ(pulled(0.2, INF, 1.0, 3.0), (std::pair{0.05, 2.0 - 0.15}));
    EXPECT_EQ(pulled(1.0, INF, 1.0, 1.0), (std::pair{0.5, 1.5}));
    EXPECT_EQ(pulled(0.2, 0.1, 1.0, 1.0), (std::pair{0.05, 1.95}));  // capped at 0.1 in all
    EXPECT_EQ(pulled(0.2, INF, 0.0, 1.0), (std::pair{0.0, 1.8}));    // p pinned
    EXPECT_EQ(pulled(0.2, INF, 0.0, 0.0), (std::pair{0.0, 2.0}));    // both pinned
    std::vector<detail::PackedVertex> close{{0.0, 0.0, 0.0, 1.0}, {0.9, 0.0, 0.0, 1.0}};
    detail::limit_stretch(close.data(), 0, 1, 1.0, 0.2, INF);
    EXPECT_EQ(close[1].x, 0.9);  // within the limit: untouched
    EXPECT_EQ(StrainHierarchy::RELAXATION, 0.2);
}

TEST(StrainHierarchy, LeavesUnstretchedClothBitwiseAlone) {
    // At rest, compressed, or folded without stretching, no limit is active: nothing moves.
    const Mesh m = grid(16, 1.0, true);
    StrainHierarchy h = hierarchy_of(m);
    std::vector<Vec3d> squeezed = m.positions;
    for (Vec3d& p : squeezed) {
        p = p * 0.7;
    }
    for (const std::vector<Vec3d>& shape : {m.positions, squeezed}) {
        std::vector<detail::PackedVertex> x = packed(shape);
        const std::vector<detail::PackedVertex> before = x;
        h.project(x.data(), 0.0, INF);
        EXPECT_EQ(std::memcmp(x.data(), before.data(), x.size() * sizeof(x[0])), 0);
    }
}

TEST(StrainHierarchy, RepeatedProjectionsBringEveryLimitWithinTheStrainAndKeepPinsFixed) {
    const Mesh m = grid(20, 1.0);
    StrainHierarchy h = hierarchy_of(m);
    // Stretched to 1.6 × along x and 1.3 × along y, plus noise; one corner pinned.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(-0.01, 0.01);
    std::vector<Vec3d> stretched = m.positions;
    for (Vec3d& p : stretched) {
        p = {1.6 * p.x + noise(rng), 1.3 * p.y + noise(rng), noise(rng)};
    }
    std::vector<detail::PackedVertex> x = packed(stretched);
    // One pinned vertex kept on every level, one that is a child on level 1.
    const auto child = static_cast<std::size_t>(h.level(1).children[0]);
    x[0].inverse_mass = 0.0;
    x[child].inverse_mass = 0.0;
    const detail::PackedVertex pinned = x[0];
    const detail::PackedVertex pinned_child = x[child];
    const double max_strain = 0.05;
    double worst_before = 0.0;
    for (std::size_t l = 1; l <= h.num_levels(); ++l) {
        const auto& level = h.level(l);
        for (std::size_t k = 0; k < level.limits.p.size(); ++k) {
            worst_before = std::max(worst_before, length(x, level.limits.p[k], level.limits.q[k]) /
                                                      level.limits.rest[k]);
        }
    }
    EXPECT_GT(worst_before, 1.25);
    for (int i = 0; i < 400; ++i) {
        h.project(x.data(), max_strain, INF);
    }
    for (std::size_t l = 1; l <= h.num_levels(); ++l) {
        const auto& level = h.level(l);
        for (std::size_t k = 0; k < level.limits.p.size(); ++k) {
            EXPECT_LE(length(x, level.limits.p[k], level.limits.q[k]),
                      (1.0 + max_strain) * level.limits.rest[k] * 1.01)
                << "level " << l << " limit " << k;
        }
    }
    EXPECT_EQ(std::memcmp(&x[0], &pinned, sizeof(pinned)), 0);
    EXPECT_EQ(std::memcmp(&x[child], &pinned_child, sizeof(pinned_child)), 0);
}

TEST(StrainHierarchy, CappedMovesStayWithinTheCapPerLimit) {
    // A limit moves its vertices by at most max_move per call; a vertex moves by its own limits at
    // its coarsest level and below, plus the parents' mean it follows: at most the sum over the
    // levels of (limits per vertex) × max_move. Uncapped, the same call moves much further.
    const Mesh m = grid(20, 1.0);
    std::vector<Vec3d> stretched = m.positions;
    for (Vec3d& p : stretched) {
        p = {2.0 * p.x, 2.0 * p.y, 0.0};
    }
    StrainHierarchy h = hierarchy_of(m);
    double bound = 0.0;
    const double cap = 1e-4;
    for (std::size_t l = 1; l <= h.num_levels(); ++l) {
        const auto& level = h.level(l);
        std::map<std::int32_t, int> degree;
        int most = 0;
        for (std::size_t k = 0; k < level.limits.p.size(); ++k) {
            most = std::max({most, ++degree[level.limits.p[k]], ++degree[level.limits.q[k]]});
        }
        bound += most * cap;
    }
    const auto largest_move = [&](double max_move) {
        std::vector<detail::PackedVertex> x = packed(stretched);
        h.project(x.data(), 0.0, max_move);
        double largest = 0.0;
        for (std::size_t v = 0; v < x.size(); ++v) {
            largest = std::max(largest, norm(Vec3d{x[v].x, x[v].y, x[v].z} - stretched[v]));
        }
        return largest;
    };
    const double capped = largest_move(cap);
    EXPECT_GT(capped, 0.0);
    EXPECT_LE(capped, bound * (1.0 + 1e-9));
    EXPECT_GT(largest_move(INF), 10.0 * bound);
}

TEST(StrainHierarchy, BitwiseIdenticalForOneAndTwoThreads) {
    const Mesh m = grid(134, 1.0);
    // Level 1's colours span several of the kernel's fixed chunks (LIMIT_GRAIN = 1,024 limits).
    ASSERT_GT(hierarchy_of(m).level(1).limits.colors.color(0).size(), 2048u);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> noise(-0.02, 0.02);
    std::vector<Vec3d> stretched = m.positions;
    for (Vec3d& p : stretched) {
        p = {1.4 * p.x + noise(rng), 1.2 * p.y + noise(rng), noise(rng)};
    }
    std::vector<std::vector<detail::PackedVertex>> results;
    for (const int threads : {1, 2}) {
        set_num_threads(threads);
        StrainHierarchy h = hierarchy_of(m);
        std::vector<detail::PackedVertex> x = packed(stretched);
        for (int i = 0; i < 5; ++i) {
            h.project(x.data(), 0.02, INF);
        }
        results.push_back(x);
    }
    set_num_threads(0);
    EXPECT_EQ(std::memcmp(results[0].data(), results[1].data(),
                          results[0].size() * sizeof(results[0][0])),
              0);
}

TEST(StrainHierarchy, AHangingStripStretchesLessWithALimit) {
    // A 0.1 m × 1 m strip of 2 × 40 quads hanging from its top row, 12 substeps per frame: one
    // Gauss-Seidel sweep per substep leaves the 40-edge chains stretched; with strain_limit
    // 0.03 the strip's hanging length stays within 3 % (plus what single edges add).
    geometry::TriangleMeshD strip =
        geometry::convert_precision<double>(geometry::make_grid_sheet(2, 40, 0.1f, 1.0f));
    std::vector<std::int32_t> top;
    double top_y = -std::numeric_limits<double>::infinity();
    for (const Vec3d& p : strip.positions) {
        top_y = std::max(top_y, p.y);
    }
    for (std::size_t v = 0; v < strip.positions.size(); ++v) {
        // Stand the strip up: y becomes height.
        strip.positions[v] = {strip.positions[v].x, 0.0, strip.positions[v].y};
        if (strip.positions[v].z == top_y) {
            top.push_back(static_cast<std::int32_t>(v));
        }
    }
    ASSERT_EQ(top.size(), 3u);
    double rest_bottom = std::numeric_limits<double>::infinity();
    for (const Vec3d& p : strip.positions) {
        rest_bottom = std::min(rest_bottom, p.z);
    }
    const auto hanging_length = [&](double strain_limit) {
        ClothMaterial material;
        material.strain_limit = strain_limit;
        material.areal_density = 2.0;                    // heavy: a long chain under its own weight
        material.stretch_solver = StretchSolver::edges;  // chains would hold it anyway
        ClothSolver solver(strip, material, top);
        for (int frame = 0; frame < 48; ++frame) {
            solver.step(1.0 / 24.0, 12);
        }
        double bottom = std::numeric_limits<double>::infinity();
        for (const Vec3d& p : solver.positions()) {
            bottom = std::min(bottom, p.z);
        }
        return (top_y - bottom) / (top_y - rest_bottom);
    };
    const double free = hanging_length(std::numeric_limits<double>::infinity());
    const double limited = hanging_length(0.03);
    EXPECT_GT(free, 1.06);
    EXPECT_LT(limited, 1.045);
    EXPECT_GE(limited, 0.99);
}

}  // namespace
}  // namespace pliant::cloth
