// io/vtu: the tet mesh written as VTK XML, read back independently by Python's xml/base64/struct
// (tests/io/vtu_readback.py; and by VTK when python3-vtk9 is installed): counts, connectivity,
// offsets, cell types, positions and the point and cell data.
#include "pliant/io/vtu.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stdio.h>

#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "support/python_readback.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::TempDir;

nlohmann::json read_with_python(const std::filesystem::path& path) {
    return pliant::test::run_python_readback("tests/io/vtu_readback.py", path);
}

// A unit cube's corner tet and its neighbour sharing a face; the deformed copy moves vertex 3.
struct TwoTets {
    std::vector<Vec3f> rest{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    std::vector<geometry::Tet> tets{{0, 1, 2, 3}, {1, 2, 3, 4}};
    std::vector<Vec3f> now = [this] {
        std::vector<Vec3f> p = rest;
        p[3] = {0.0F, 0.0F, 2.0F};  // doubles the first tet's volume
        return p;
    }();
};

TEST(Vtu, PythonReadsCountsCellsAndData) {
    TempDir dir;
    const TwoTets m;
    ASSERT_GT(geometry::signed_volume(m.rest[1], m.rest[2], m.rest[3], m.rest[4]), 0.0F);
    write_vtu(dir / "m.vtu", m.now, m.tets, m.rest);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"m.vtu"});
    const nlohmann::json j = read_with_python(dir / "m.vtu");
    EXPECT_EQ(j["points"], 5);
    EXPECT_EQ(j["cells"], 2);
    const auto& a = j["arrays"];
    EXPECT_EQ(a["Cells/connectivity"]["values"], (nlohmann::json{0, 1, 2, 3, 1, 2, 3, 4}));
    EXPECT_EQ(a["Cells/offsets"]["values"], (nlohmann::json{4, 8}));
    EXPECT_EQ(a["Cells/types"]["values"], (nlohmann::json{10, 10}));
    EXPECT_EQ(a["Points/Points"]["components"], 3);
    EXPECT_EQ(a["Points/Points"]["values"][11], 2.0);  // vertex 3's z
    EXPECT_EQ(a["PointData/displacement"]["values"][11], 1.0);
    EXPECT_EQ(a["PointData/displacement"]["values"][0], 0.0);
    EXPECT_EQ(a["PointData/rest_position"]["values"][14], 1.0);
    EXPECT_EQ(a["CellData/volume_ratio"]["values"][0], 2.0);
    if (j.contains("vtk")) {
        EXPECT_EQ(j["vtk"]["points"], 5);
        EXPECT_EQ(j["vtk"]["cells"], 2);
        EXPECT_EQ(j["vtk"]["cell_type"], 10);
    }
}

TEST(Vtu, WithoutRestPositionsAndEmptyMeshes) {
    TempDir dir;
    const TwoTets m;
    write_vtu(dir / "p.vtu", m.rest, m.tets);
    nlohmann::json j = read_with_python(dir / "p.vtu");
    EXPECT_FALSE(j["arrays"].contains("PointData/displacement"));
    EXPECT_EQ(j["arrays"]["Points/Points"]["values"].size(), 15U);
    write_vtu(dir / "e.vtu", {}, {});
    j = read_with_python(dir / "e.vtu");
    EXPECT_EQ(j["points"], 0);
    EXPECT_EQ(j["cells"], 0);
}

TEST(Vtu, RefusesBadIndicesAndMismatchedRestPositions) {
    TempDir dir;
    TwoTets m;
    m.tets[1][2] = 5;
    EXPECT_THROW(write_vtu(dir / "b.vtu", m.now, m.tets, m.rest), InvalidInput);
    const TwoTets ok;
    EXPECT_THROW(write_vtu(dir / "c.vtu", ok.now, ok.tets, std::span(ok.rest).first(4)),
                 InvalidInput);
    EXPECT_TRUE(dir.entries().empty());
    EXPECT_THROW(write_vtu(dir / "missing" / "d.vtu", ok.now, ok.tets), IoError);
}

}  // namespace
}  // namespace pliant::io
