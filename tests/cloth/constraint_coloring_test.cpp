#include "pliant/cloth/constraint_coloring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <set>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::cloth {
namespace {

TEST(ConstraintColoring, ColoursShareNoVertexAndCoverEveryConstraintOnce) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::int32_t> vertex(0, 999);
    std::vector<std::array<std::int32_t, 4>> constraints(3000);
    for (auto& c : constraints) {
        // Four distinct vertices.
        std::set<std::int32_t> distinct;
        while (distinct.size() < 4) {
            distinct.insert(vertex(rng));
        }
        std::copy(distinct.begin(), distinct.end(), c.begin());
    }
    const auto vertices_of = [&](std::int64_t i) {
        return std::span<const std::int32_t>(constraints[static_cast<std::size_t>(i)]);
    };
    const ConstraintColoring coloring = color_constraints(3000, 1000, vertices_of);
    std::vector<int> seen(3000, 0);
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        std::set<std::int32_t> used;
        std::int32_t previous = -1;
        for (const std::int32_t i : coloring.color(c)) {
            EXPECT_GT(i, previous);  // ascending within a colour
            previous = i;
            ++seen[static_cast<std::size_t>(i)];
            for (const std::int32_t v : constraints[static_cast<std::size_t>(i)]) {
                EXPECT_TRUE(used.insert(v).second) << "colour " << c << " vertex " << v;
            }
        }
    }
    for (const int count : seen) {
        EXPECT_EQ(count, 1);
    }
    // Deterministic.
    const ConstraintColoring again = color_constraints(3000, 1000, vertices_of);
    EXPECT_EQ(again.order, coloring.order);
    EXPECT_EQ(again.offsets, coloring.offsets);
}

TEST(ConstraintColoring, ColumnsLayOutEachConstraintInColourOrder) {
    // color_edges and color_hinges: column j holds constraint order[j] (vertices and, for edges,
    // the rest length), and the constraints of a colour share no vertex.
    std::mt19937 rng(12);
    std::uniform_int_distribution<std::int32_t> vertex(0, 199);
    std::vector<std::array<std::int32_t, 4>> hinges(500);
    std::vector<std::array<std::int32_t, 2>> edges(500);
    std::vector<double> rest(500);
    for (std::size_t i = 0; i < hinges.size(); ++i) {
        std::set<std::int32_t> distinct;
        while (distinct.size() < 4) {
            distinct.insert(vertex(rng));
        }
        std::copy(distinct.begin(), distinct.end(), hinges[i].begin());
        edges[i] = {hinges[i][0], hinges[i][3]};
        rest[i] = 0.5 + static_cast<double>(i);
    }
    const ColoredHinges h = color_hinges(hinges, 200);
    const ColoredEdges e = color_edges(edges, rest, 200);
    ASSERT_EQ(h.size(), hinges.size());
    ASSERT_EQ(e.p.size(), edges.size());
    for (std::size_t j = 0; j < hinges.size(); ++j) {
        const auto i = static_cast<std::size_t>(h.colors.order[j]);
        for (std::size_t k = 0; k < 4; ++k) {
            ASSERT_EQ(h.v[k][j], hinges[i][k]);
        }
        const auto ie = static_cast<std::size_t>(e.colors.order[j]);
        ASSERT_EQ(e.p[j], edges[ie][0]);
        ASSERT_EQ(e.q[j], edges[ie][1]);
        ASSERT_EQ(e.rest[j], rest[ie]);
    }
    for (std::int32_t c = 0; c < h.colors.num_colors(); ++c) {
        std::set<std::int32_t> used;
        for (auto j = h.colors.offsets[static_cast<std::size_t>(c)];
             j < h.colors.offsets[static_cast<std::size_t>(c) + 1]; ++j) {
            for (std::size_t k = 0; k < 4; ++k) {
                ASSERT_TRUE(used.insert(h.v[k][static_cast<std::size_t>(j)]).second);
            }
        }
    }
}

TEST(ConstraintColoring, EmptyAndTooManyColours) {
    const ConstraintColoring empty =
        color_constraints(0, 5, [](std::int64_t) { return std::span<const std::int32_t>(); });
    EXPECT_EQ(empty.num_colors(), 0);
    // 65 constraints on the same vertex pair need 65 colours.
    const std::array<std::int32_t, 2> pair{0, 1};
    EXPECT_THROW(color_constraints(65, 2, [&](std::int64_t) { return std::span(pair); }),
                 InvalidInput);
}

}  // namespace
}  // namespace pliant::cloth
