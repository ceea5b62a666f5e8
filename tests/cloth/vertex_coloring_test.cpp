#include "pliant/cloth/vertex_coloring.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

TEST(VertexColoring, NoElementHasTwoVerticesOfOneColor) {
    const geometry::TriangleMeshD mesh = test::flat_sheet(9, 1.0, 0.0);
    std::vector<std::int32_t> vertices;
    std::vector<std::int32_t> offsets{0};
    for (const geometry::Triangle& t : mesh.triangles) {
        vertices.insert(vertices.end(), t.begin(), t.end());
        offsets.push_back(static_cast<std::int32_t>(vertices.size()));
    }
    const auto n = static_cast<std::int64_t>(mesh.positions.size());
    const VertexColoring coloring = color_vertices(n, vertices, offsets);
    ASSERT_EQ(coloring.color_of.size(), mesh.positions.size());
    for (const geometry::Triangle& t : mesh.triangles) {
        for (std::size_t a = 0; a < 3; ++a) {
            for (std::size_t b = a + 1; b < 3; ++b) {
                EXPECT_NE(coloring.color_of[static_cast<std::size_t>(t[a])],
                          coloring.color_of[static_cast<std::size_t>(t[b])]);
            }
        }
    }
    // Every vertex once, ascending within its colour, in the colour color_of says.
    std::vector<int> seen(mesh.positions.size(), 0);
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        std::int32_t last = -1;
        for (const std::int32_t v : coloring.color(c)) {
            EXPECT_GT(v, last);
            last = v;
            EXPECT_EQ(coloring.color_of[static_cast<std::size_t>(v)], c);
            ++seen[static_cast<std::size_t>(v)];
        }
    }
    for (const int s : seen) {
        EXPECT_EQ(s, 1);
    }
    // A grid's triangles need 3 colours at least; greedy in index order finds few.
    EXPECT_GE(coloring.num_colors(), 3);
    EXPECT_LE(coloring.num_colors(), 7);
}

TEST(VertexColoring, IsolatedVerticesTakeColorZero) {
    const std::vector<std::int32_t> vertices{0, 1};
    const std::vector<std::int32_t> offsets{0, 2};
    const VertexColoring coloring = color_vertices(4, vertices, offsets);
    EXPECT_EQ(coloring.color_of, (std::vector<std::int32_t>{0, 1, 0, 0}));
    EXPECT_EQ(coloring.num_colors(), 2);
}

TEST(VertexColoring, RejectsBadElements) {
    const std::vector<std::int32_t> vertices{0, 5};
    EXPECT_THROW(color_vertices(4, vertices, std::vector<std::int32_t>{0, 2}), InvalidInput);
    const std::vector<std::int32_t> ok{0, 1};
    EXPECT_THROW(color_vertices(4, ok, std::vector<std::int32_t>{0, 3}), InvalidInput);
    EXPECT_THROW(color_vertices(4, ok, std::vector<std::int32_t>{}), InvalidInput);
}

}  // namespace
}  // namespace pliant::cloth
