#include "pliant/io/tetgen.hpp"

#include <gtest/gtest.h>

#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using test::write_bytes;

// Two tets sharing a face, 1-based as TetGen writes by default, with comments, attributes and
// markers; the second is given negatively oriented.
constexpr std::string_view NODE = R"(# two tets
5 3 1 1
1 0 0 0   7.5 1
2 1 0 0   7.5 1
3 0 1 0   7.5 0   # a comment
4 0 0 1   7.5 1

5 1 1 1   7.5 1
)";
constexpr std::string_view ELE = R"(2 4 1
1  1 2 3 4  3
2  2 4 3 5  3
)";

TEST(TetGen, ReadsNodesAndTetsOrientingThemPositively) {
    TempDir dir;
    write_bytes(dir.path() / "m.node", NODE);
    write_bytes(dir.path() / "m.ele", ELE);
    for (const char* name : {"m", "m.node", "m.ele"}) {
        const geometry::TetMesh mesh = read_tetgen(dir.path() / name);
        ASSERT_EQ(mesh.num_vertices(), 5u);
        ASSERT_EQ(mesh.num_tets(), 2u);
        EXPECT_EQ(mesh.positions[4], (Vec3f{1, 1, 1}));
        EXPECT_EQ(mesh.tets[0], (geometry::Tet{0, 1, 2, 3}));
        EXPECT_EQ(mesh.tets[1], (geometry::Tet{1, 3, 4, 2}));  // last two swapped
        for (const geometry::Tet& t : mesh.tets) {
            EXPECT_GT(geometry::signed_volume(mesh.positions[t[0]], mesh.positions[t[1]],
                                              mesh.positions[t[2]], mesh.positions[t[3]]),
                      0.0f);
        }
    }
}

TEST(TetGen, RoundTripsBitForBit) {
    TempDir dir;
    geometry::TetMesh mesh;
    mesh.positions = {{0.1f, 0.2f, 0.3f}, {1.0f / 3.0f, 0, 0}, {0, 1e-7f, 2.5f}, {-3, 1, 7}};
    mesh.tets = {{0, 1, 2, 3}};
    if (geometry::signed_volume(mesh.positions[0], mesh.positions[1], mesh.positions[2],
                                mesh.positions[3]) < 0) {
        std::swap(mesh.tets[0][2], mesh.tets[0][3]);
    }
    write_tetgen(dir.path() / "out", mesh);
    const geometry::TetMesh back = read_tetgen(dir.path() / "out");
    EXPECT_EQ(back.positions, mesh.positions);
    EXPECT_EQ(back.tets, mesh.tets);
}

TEST(TetGen, RefusesWritingBadMeshesWithoutTouchingFiles) {
    TempDir dir;
    geometry::TetMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    mesh.tets = {{0, 1, 2, 4}};
    EXPECT_THROW(write_tetgen(dir.path() / "bad", mesh), InvalidInput);
    mesh.tets = {{0, 1, 2, 3}};
    mesh.positions[1].x = std::nanf("");
    EXPECT_THROW(write_tetgen(dir.path() / "bad", mesh), InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "bad.node"));
}

struct BrokenCase {
    const char* name;
    std::string_view node;
    std::string_view ele;
    std::initializer_list<std::string_view> fragments;
};

TEST(TetGen, BrokenFilesGiveClearErrors) {
    const std::string_view good_node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
    const std::string_view good_ele = "1 4 0\n0 0 1 2 3\n";
    const BrokenCase cases[] = {
        {"empty node", "", good_ele, {"m.node", "empty file"}},
        {"2d", "4 2 0 0\n", good_ele, {"line 1", "dimension is 2, expected 3"}},
        {"huge count", "99999999999 3 0 0\n0 0 0 0\n", good_ele, {"point count", "expected 0 to"}},
        {"truncated", "4 3 0 0\n0 0 0 0\n1 1 0 0\n", good_ele, {"ends after 2 points, expected 4"}},
        {"nan",
         "4 3 0 0\n0 0 0 0\n1 nan 0 0\n2 0 1 0\n3 0 0 1\n",
         good_ele,
         {"line 3", "x is 'nan', expected a finite number"}},
        {"short point",
         "4 3 0 0\n0 0 0 0\n1 1 0\n2 0 1 0\n3 0 0 1\n",
         good_ele,
         {"line 3", "point has 3 numbers, expected 4"}},
        {"index gap",
         "4 3 0 0\n0 0 0 0\n2 1 0 0\n2 0 1 0\n3 0 0 1\n",
         good_ele,
         {"line 3", "point index is 2, expected 1"}},
        {"garbage", "four 3 0 0\n", good_ele, {"point count is 'four', expected an integer"}},
        {"extra points",
         "1 3 0 0\n0 0 0 0\n1 1 0 0\n",
         good_ele,
         {"data after the 1 declared points"}},
        {"bad node",
         good_node,
         "1 4 0\n0 0 1 2 4\n",
         {"m.ele", "line 2", "node index is 4, expected 0 to 3"}},
        {"negative node", good_node, "1 4 0\n0 0 1 -2 3\n", {"node index is -2"}},
        {"repeated node", good_node, "1 4 0\n0 0 1 1 3\n", {"repeats node 1"}},
        {"flat tet", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 1 1 0\n", good_ele, {"zero volume"}},
        {"5 nodes", good_node, "1 5 0\n0 0 1 2 3 3\n", {"nodes per tet is 5, expected 4 or 10"}},
        {"ele truncated", good_node, "2 4 0\n0 0 1 2 3\n", {"ends after 1 tets, expected 2"}},
        {"empty ele", good_node, "# nothing\n", {"m.ele", "empty file"}},
    };
    for (const BrokenCase& c : cases) {
        SCOPED_TRACE(c.name);
        TempDir dir;
        write_bytes(dir.path() / "m.node", c.node);
        write_bytes(dir.path() / "m.ele", c.ele);
        expect_io_error([&] { read_tetgen(dir.path() / "m"); }, c.fragments);
    }
    TempDir dir;
    expect_io_error([&] { read_tetgen(dir.path() / "missing.node"); }, {"missing.node"});
}

TEST(TetGen, QuadraticTetsKeepTheirCorners) {
    TempDir dir;
    write_bytes(dir.path() / "q.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    write_bytes(dir.path() / "q.ele", "1 10 0\n0 0 1 2 3 0 1 2 3 0 1\n");
    EXPECT_EQ(read_tetgen(dir.path() / "q").tets.at(0), (geometry::Tet{0, 1, 2, 3}));
}

}  // namespace
}  // namespace pliant::io
