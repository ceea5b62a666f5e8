// Loading garments: the cloth mesh's units, the size and thickness warnings, and physical
// stiffnesses turned into the solver's compliances for the mesh.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "pliant/cloth/material_preset.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/obj.hpp"
#include "pliant/io/ply_polygons.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "support/test_files.hpp"

namespace pliant::pipeline {
namespace {

// Collects the warnings logged while it lives.
class Warnings {
public:
    Warnings() {
        m_previous = set_log_sink([this](LogLevel level, std::string_view message) {
            if (level == LogLevel::warning) {
                m_messages.emplace_back(message);
            }
        });
    }
    Warnings(const Warnings&) = delete;
    Warnings& operator=(const Warnings&) = delete;
    ~Warnings() { set_log_sink(m_previous); }

    // The number of warnings containing `part`.
    int count(const std::string& part) const {
        int n = 0;
        for (const std::string& m : m_messages) {
            n += m.find(part) != std::string::npos ? 1 : 0;
        }
        return n;
    }
    std::string all() const {
        std::string out;
        for (const std::string& m : m_messages) {
            out += m + "\n";
        }
        return out;
    }

private:
    LogSink m_previous;
    std::vector<std::string> m_messages;
};

// A 0.8 m square garment panel of 16 × 16 quads written in `unit_scale` units per metre.
std::filesystem::path write_panel(const io::test::TempDir& dir, double units_per_metre) {
    geometry::TriangleMeshD mesh =
        geometry::convert_precision<double>(geometry::make_grid_sheet(16, 16, 0.8F, 0.8F));
    for (Vec3d& p : mesh.positions) {
        p = p * units_per_metre;
    }
    const std::filesystem::path path = dir / "panel.obj";
    io::write_obj(path, mesh);
    return path;
}

ClothSetup load(const std::string& cloth, const std::string& material = "{}") {
    const cloth::ClothScene scene = parse_cloth_scene(
        R"({"cloth": )" + cloth + R"(, "material": )" + material + "}", "g.json", "/");
    return load_cloth_setup(scene, "g.json");
}

TEST(GarmentSetup, UnitsScaleTheMeshAndSilenceTheSizeWarning) {
    const io::test::TempDir dir;
    const std::string file = write_panel(dir, 100.0).string();  // centimetres
    {
        const Warnings warnings;
        const ClothSetup setup = load(R"({"mesh": ")" + file + R"("})");
        EXPECT_NEAR(setup.mesh.positions.back().x, 40.0, 1e-6);  // read as metres
        EXPECT_EQ(warnings.count("implausible for cloth"), 1) << warnings.all();
        EXPECT_EQ(warnings.count("cloth.units"), 2) << warnings.all();  // size and thickness
    }
    {
        const Warnings warnings;
        const ClothSetup setup = load(R"({"mesh": ")" + file + R"(", "units": "cm"})");
        EXPECT_NEAR(setup.mesh.positions.back().x, 0.4, 1e-6);
        EXPECT_EQ(warnings.all(), "");
    }
    {
        const Warnings warnings;
        const ClothSetup setup = load(R"({"mesh": ")" + file + R"(", "scale": 0.01})");
        EXPECT_NEAR(setup.mesh.positions.back().x, 0.4, 1e-6);
        EXPECT_EQ(warnings.all(), "");
    }
    {  // millimetres read as centimetres: 8 cm across, fine, but 5 mm is 1 edge of 5 mm
        const Warnings warnings;
        load(R"({"mesh": ")" + file + R"(", "units": "mm"})");
        EXPECT_EQ(warnings.count("implausible for cloth"), 0) << warnings.all();
        EXPECT_EQ(warnings.count("times the mean edge length"), 1) << warnings.all();
    }
}

TEST(GarmentSetup, ThicknessFarFromTheEdgeLengthWarns) {
    const Warnings warnings;
    load(R"({"grid": {"size": [1, 1], "quads": [10, 10]}})", R"({"thickness": 0.0005})");
    EXPECT_EQ(warnings.count("times the mean edge length"), 1) << warnings.all();
    EXPECT_EQ(warnings.count("CCD fail-safe alone"), 1) << warnings.all();
    load(R"({"grid": {"size": [1, 1], "quads": [100, 100]}})", R"({"thickness": 0.01})");
    EXPECT_EQ(warnings.count("holds the cloth stiff"), 1) << warnings.all();
    load(R"({"grid": {"size": [30, 30], "quads": [10, 10]}})", R"({"thickness": 0.5})");
    EXPECT_EQ(warnings.count("check cloth.grid.size"), 1) << warnings.all();
    EXPECT_EQ(warnings.count("check material.thickness and cloth.grid"), 2) << warnings.all();
}

TEST(GarmentSetup, PresetsBecomeCompliancesForTheMesh) {
    const ClothSetup denim = load(R"({"grid": {"size": [1, 1], "quads": [20, 20]}})", R"("denim")");
    const cloth::FabricProperties d = *cloth::fabric_preset("denim");
    EXPECT_DOUBLE_EQ(denim.material.areal_density, d.areal_density);
    EXPECT_DOUBLE_EQ(denim.material.stretch_compliance,
                     cloth::stretch_compliance_for(d.stretch_stiffness, denim.mesh.positions,
                                                   denim.mesh.triangles));
    EXPECT_DOUBLE_EQ(
        denim.material.bend_compliance,
        cloth::bend_compliance_for(d.bend_stiffness, denim.mesh.positions, denim.mesh.triangles));
    const ClothSetup plain =
        load(R"({"grid": {"size": [1, 1], "quads": [20, 20]}})", R"({"stretch_compliance": 2e-6})");
    EXPECT_DOUBLE_EQ(plain.material.stretch_compliance, 2e-6);
    EXPECT_DOUBLE_EQ(plain.material.bend_compliance, cloth::ClothMaterial{}.bend_compliance);
}

TEST(GarmentSetup, SeamVerticesOutsideTheClothAreRefused) {
    const std::string grid = R"({"cloth": {"grid": {"size": [1, 1], "quads": [2, 2]}}, "seams": )";
    const auto expect = [&](const std::string& seams, std::initializer_list<std::string> parts) {
        const cloth::ClothScene scene = parse_cloth_scene(grid + seams + "}", "g.json", "/");
        try {
            load_cloth_setup(scene, "g.json");
            ADD_FAILURE() << "no error for " << seams;
        } catch (const InvalidInput& e) {
            for (const std::string& part : parts) {
                EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
            }
        }
    };
    expect(R"([{"a": [0, 1], "b": [2, 9]}])",
           {"g.json", "seams[0].b[1]", "vertex 9 out of range", "[0, 9)"});
    expect(R"([{"a": [0], "b": [2]}, {"a": [4, 5], "b": [6, 5]}])",
           {"seams[1]", "pair 1", "vertex 5 is sewn to itself"});
    const cloth::ClothScene ok =
        parse_cloth_scene(grid + R"([{"a": [0], "b": [8]}]})", "g.json", "/");
    const ClothSetup setup = load_cloth_setup(ok, "g.json");
    EXPECT_EQ(make_solver(ok, setup)->model().seams().num_pairs(), 1u);
}

// A PLY garment is read as polygons with its UVs and properties; instances repeat its faces,
// UVs and properties per copy, so that frames of all copies can be written as PLY.
TEST(GarmentSetup, PlyGarmentWithInstancesKeepsFacesUvsAndProperties) {
    const io::test::TempDir dir;
    io::test::write_bytes(
        dir / "quad.ply",
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
        "property float z\nproperty float u\nproperty float v\nproperty uchar red\n"
        "element face 2\nproperty list uchar int vertex_indices\nproperty short id\n"
        "end_header\n0 0 0 0 0 1\n0.2 0 0 1 0 2\n0.2 0.2 0 1 1 3\n0 0.2 0 0 1 4\n"
        "0.3 0.1 0 1 0.5 5\n4 0 1 2 3 7\n3 1 4 2 8\n");
    const ClothSetup setup = load(R"({"mesh": ")" + (dir / "quad.ply").string() +
                                  R"(", "instances": [{}, {"translate": [0, 0, 0.5]}]})");
    EXPECT_EQ(setup.mesh.triangles.size(), 6u);  // (2 + 1) per copy
    ASSERT_TRUE(setup.garment);
    const io::PolygonMesh& g = *setup.garment;
    ASSERT_EQ(g.num_faces(), 4u);
    EXPECT_EQ(g.corner_vertices,
              (std::vector<std::int32_t>{0, 1, 2, 3, 1, 4, 2, 5, 6, 7, 8, 6, 9, 7}));
    EXPECT_EQ(g.corner_uvs, (std::vector<std::int32_t>{0, 1, 2, 3, 1, 4, 2, 0, 1, 2, 3, 1, 4, 2}));
    ASSERT_EQ(g.vertex_attributes.size(), 1u);
    EXPECT_EQ(g.vertex_attributes[0].values, (std::vector<double>{1, 2, 3, 4, 5, 1, 2, 3, 4, 5}));
    ASSERT_EQ(g.face_attributes.size(), 1u);
    EXPECT_EQ(g.face_attributes[0].values, (std::vector<double>{7, 8, 7, 8}));
    EXPECT_EQ(g.positions, setup.mesh.positions);
    io::write_ply_polygons(dir / "frame.ply", g, setup.mesh.positions);
    EXPECT_EQ(io::read_ply_polygons(dir / "frame.ply").face_attributes[0].values,
              g.face_attributes[0].values);
}

}  // namespace
}  // namespace pliant::pipeline
