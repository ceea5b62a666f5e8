#include "pliant/cloth/material_preset.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

constexpr double GRAVITY = 9.81;

// A strip `width` × `length` m of nx × ny quads hanging in the x-z plane from its top row (z = 0),
// its rest shape vertical.
struct HangingStrip {
    geometry::TriangleMeshD mesh;
    std::vector<std::int32_t> top;
    std::vector<std::int32_t> bottom;
};

HangingStrip hanging_strip(int nx, int ny, double width, double length) {
    const geometry::TriangleMesh grid =
        geometry::make_grid_sheet(nx, ny, static_cast<float>(width), static_cast<float>(length));
    HangingStrip strip;
    strip.mesh.triangles = grid.triangles;
    for (std::size_t v = 0; v < grid.positions.size(); ++v) {
        const Vec3f& p = grid.positions[v];
        strip.mesh.positions.push_back({p.x, 0.0, p.y - 0.5 * length});
        if (v / static_cast<std::size_t>(nx + 1) == static_cast<std::size_t>(ny)) {
            strip.top.push_back(static_cast<std::int32_t>(v));
        }
        if (v / static_cast<std::size_t>(nx + 1) == 0) {
            strip.bottom.push_back(static_cast<std::int32_t>(v));
        }
    }
    return strip;
}

// How far the strip's bottom row hangs below its rest height after settling (m).
double elongation(const HangingStrip& strip, const ClothMaterial& material, int frames) {
    ClothSolver solver(strip.mesh, material, strip.top);
    solver.set_gravity({0.0, 0.0, -GRAVITY});
    for (int f = 0; f < frames; ++f) {
        solver.step(1.0 / 24.0, 40);
    }
    double sum = 0.0;
    for (const std::int32_t v : strip.bottom) {
        sum += strip.mesh.positions[static_cast<std::size_t>(v)].z -
               solver.positions()[static_cast<std::size_t>(v)].z;
    }
    return sum / static_cast<double>(strip.bottom.size());
}

ClothMaterial settled_material(const FabricProperties& fabric, const HangingStrip& strip) {
    ClothMaterial material;
    material.damping = 20.0;  // settle within a few seconds
    return with_fabric(material, fabric, strip.mesh.positions, strip.mesh.triangles);
}

TEST(MaterialPreset, AllPresetsExistWithPositiveValues) {
    const std::vector<std::string> expected{"cotton", "silk", "denim", "leather", "rubber"};
    EXPECT_EQ(fabric_preset_names(), expected);
    for (const std::string& name : expected) {
        const std::optional<FabricProperties> f = fabric_preset(name);
        ASSERT_TRUE(f) << name;
        EXPECT_GT(f->areal_density, 0.0);
        EXPECT_GT(f->stretch_stiffness, 0.0);
        EXPECT_GT(f->bend_stiffness, 0.0);
    }
    EXPECT_FALSE(fabric_preset("wool"));
    // Orders the measurements agree on: silk is the lightest and most pliable, leather the
    // stiffest in bending, rubber the most extensible.
    EXPECT_LT(fabric_preset("silk")->bend_stiffness, fabric_preset("cotton")->bend_stiffness);
    EXPECT_LT(fabric_preset("cotton")->bend_stiffness, fabric_preset("denim")->bend_stiffness);
    EXPECT_LT(fabric_preset("denim")->bend_stiffness, fabric_preset("leather")->bend_stiffness);
    EXPECT_LT(fabric_preset("rubber")->stretch_stiffness, fabric_preset("silk")->stretch_stiffness);
    EXPECT_LT(fabric_preset("silk")->areal_density, fabric_preset("denim")->areal_density);
}

TEST(MaterialPreset, CompliancesDoNotDependOnTheResolution) {
    const double y = 1e4;
    const double b = 1e-5;
    std::vector<double> stretch;
    std::vector<double> bend;
    for (const int n : {10, 20, 80}) {
        const geometry::TriangleMeshD m =
            geometry::convert_precision<double>(geometry::make_grid_sheet(n, n, 1.0F, 1.0F));
        stretch.push_back(stretch_compliance_for(y, m.positions, m.triangles));
        bend.push_back(bend_compliance_for(b, m.positions, m.triangles));
    }
    // Interior grid edges: l² / (A1 + A2) is 1 along the grid lines and 2 on the diagonals
    // (twice as many line edges): 4/3 per Y; boundary edges shift the mean by O(1/n).
    EXPECT_NEAR(stretch[2] * y, 4.0 / 3.0, 0.05);
    EXPECT_NEAR(stretch[0] / stretch[2], 1.0, 0.1);
    EXPECT_NEAR(stretch[1] / stretch[2], 1.0, 0.05);
    // Interior hinges: (A1 + A2) / |e|² is 1 on line edges, 1/2 on diagonals.
    EXPECT_NEAR(bend[2] * BEND_HINGE_FACTOR * b, (2.0 * 1.0 + 0.5) / 3.0, 0.05);
    EXPECT_NEAR(bend[0] / bend[2], 1.0, 0.1);
    EXPECT_NEAR(bend[1] / bend[2], 1.0, 0.05);
    // Uniform scaling of the mesh leaves them unchanged.
    geometry::TriangleMeshD big =
        geometry::convert_precision<double>(geometry::make_grid_sheet(20, 20, 1.0F, 1.0F));
    for (Vec3d& p : big.positions) {
        p = p * 7.0;
    }
    EXPECT_NEAR(stretch_compliance_for(y, big.positions, big.triangles) / stretch[1], 1.0, 1e-9);
}

TEST(MaterialPreset, RejectsInvalidStiffness) {
    const geometry::TriangleMeshD m =
        geometry::convert_precision<double>(geometry::make_grid_sheet(2, 2, 1.0F, 1.0F));
    EXPECT_THROW(stretch_compliance_for(0.0, m.positions, m.triangles), InvalidInput);
    EXPECT_THROW(stretch_compliance_for(-1.0, m.positions, m.triangles), InvalidInput);
    EXPECT_THROW(bend_compliance_for(std::nan(""), m.positions, m.triangles), InvalidInput);
    EXPECT_THROW(stretch_compliance_for(1.0, {}, {}), InvalidInput);
}

// A strip hanging under its own weight stretches by ΔL = ρ g L² / (2 Y) (the tension at height
// s below the top is ρ g (L - s) per unit width): the soft fabric as the formula says, the stiff
// one less, and about the same at twice the resolution.
TEST(MaterialPreset, HangingStripStretchesAsTheStiffnessSays) {
    const double length = 1.0;
    FabricProperties soft{0.2, 100.0, 1e-6};
    const double expected =
        soft.areal_density * GRAVITY * length * length / (2.0 * soft.stretch_stiffness);  // 9.8 mm
    const HangingStrip coarse = hanging_strip(4, 20, 0.2, length);
    const HangingStrip fine = hanging_strip(8, 40, 0.2, length);
    const double soft_coarse = elongation(coarse, settled_material(soft, coarse), 72);
    const double soft_fine = elongation(fine, settled_material(soft, fine), 72);
    EXPECT_NEAR(soft_coarse / expected, 1.0, 0.1) << soft_coarse << " m";
    EXPECT_NEAR(soft_fine / soft_coarse, 1.0, 0.1) << soft_fine << " vs " << soft_coarse;

    const double rubber =
        elongation(coarse, settled_material(*fabric_preset("rubber"), coarse), 72);
    const double denim = elongation(coarse, settled_material(*fabric_preset("denim"), coarse), 72);
    const FabricProperties r = *fabric_preset("rubber");
    EXPECT_NEAR(rubber / (r.areal_density * GRAVITY / (2.0 * r.stretch_stiffness)), 1.0, 0.15);
    EXPECT_LT(denim, 0.5 * rubber) << denim << " vs " << rubber;
    EXPECT_LT(rubber, soft_coarse);
    std::printf(
        "elongation (mm): expected %.2f, soft coarse %.2f, fine %.2f, rubber %.3f, denim %.3f\n",
        expected * 1e3, soft_coarse * 1e3, soft_fine * 1e3, rubber * 1e3, denim * 1e3);
}

}  // namespace
}  // namespace pliant::cloth
