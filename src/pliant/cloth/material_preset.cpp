#include "pliant/cloth/material_preset.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::cloth {
namespace {

// Representative values of the published measurements cited in docs/formats.md ("Material
// presets"): areal density (kg/m²), tensile stiffness Y (N/m; Kawabata EMT, the strain at
// 500 gf/cm = 490 N/m, gives the secant Y ≈ 490 N/m / EMT) and bending rigidity B (N·m; Kawabata
// B in gf·cm²/cm × 9.81e-5). Leather and rubber from Young's modulus E and thickness t:
// Y = E t, B = E t³ / 12.
struct Preset {
    const char* name;
    FabricProperties fabric;
};

constexpr std::array<Preset, 5> PRESETS{{
    // Cotton shirting/poplin: 130 g/m², EMT ≈ 5 %, B ≈ 0.1 gf·cm²/cm.
    {"cotton", {0.13, 1.0e4, 1.0e-5}},
    // Silk (crêpe de chine, charmeuse): 60 g/m², EMT ≈ 10 %, B ≈ 0.02 gf·cm²/cm.
    {"silk", {0.06, 5.0e3, 2.0e-6}},
    // Denim (12 oz): 400 g/m², EMT ≈ 3 %, B ≈ 0.3 gf·cm²/cm.
    {"denim", {0.40, 1.5e4, 3.0e-5}},
    // Garment leather (nappa), t = 1 mm, E ≈ 20 MPa, 900 kg/m³.
    {"leather", {0.90, 2.0e4, 1.7e-3}},
    // Natural rubber sheet, t = 0.5 mm, E ≈ 1.5 MPa, 950 kg/m³.
    {"rubber", {0.475, 750.0, 1.6e-5}},
}};

void require_positive(double value, const char* what) {
    if (!(value > 0.0) || !std::isfinite(value)) {
        throw InvalidInput(
            fmt::format("cloth material: {}: expected a finite number > 0, got {}", what, value));
    }
}

double triangle_area(std::span<const Vec3d> x, const geometry::Triangle& t) {
    const auto at = [&](int k) {
        return x[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
    };
    return 0.5 * norm(cross(at(1) - at(0), at(2) - at(0)));
}

// Per edge of the mesh: (|e|², A1 + A2, number of triangles), in topology order.
struct EdgeMeasure {
    double length_squared;
    double area;
    std::size_t triangles;
};

std::vector<EdgeMeasure> edge_measures(std::span<const Vec3d> x,
                                       std::span<const geometry::Triangle> triangles) {
    geometry::validate_triangles(triangles, x.size(), "cloth mesh");
    const geometry::MeshTopology topology = geometry::build_topology(triangles, x.size());
    std::vector<EdgeMeasure> out;
    out.reserve(topology.num_edges());
    for (std::size_t e = 0; e < topology.num_edges(); ++e) {
        const geometry::Edge& edge = topology.edges[e];
        EdgeMeasure m{squared_norm(x[static_cast<std::size_t>(edge[1])] -
                                   x[static_cast<std::size_t>(edge[0])]),
                      0.0, 0};
        for (const std::int32_t t : topology.triangles_of_edge(static_cast<std::int32_t>(e))) {
            m.area += triangle_area(x, triangles[static_cast<std::size_t>(t)]);
            ++m.triangles;
        }
        out.push_back(m);
    }
    return out;
}

}  // namespace

const std::vector<std::string>& fabric_preset_names() {
    static const std::vector<std::string> NAMES = [] {
        std::vector<std::string> n;
        n.reserve(PRESETS.size());
        for (const Preset& p : PRESETS) {
            n.emplace_back(p.name);
        }
        return n;
    }();
    return NAMES;
}

std::optional<FabricProperties> fabric_preset(std::string_view name) {
    for (const Preset& p : PRESETS) {
        if (name == p.name) {
            return p.fabric;
        }
    }
    return std::nullopt;
}

double stretch_compliance_for(double stretch_stiffness, std::span<const Vec3d> rest_positions,
                              std::span<const geometry::Triangle> triangles) {
    require_positive(stretch_stiffness, "stretch_stiffness (N/m)");
    double sum = 0.0;
    std::size_t count = 0;
    for (const EdgeMeasure& m : edge_measures(rest_positions, triangles)) {
        if (m.area > 0.0 && m.length_squared > 0.0) {
            sum += m.length_squared / m.area;
            ++count;
        }
    }
    if (count == 0) {
        throw InvalidInput(
            "cloth material: stretch_stiffness: the mesh has no triangle of positive area");
    }
    return sum / static_cast<double>(count) / stretch_stiffness;
}

double bend_compliance_for(double bend_stiffness, std::span<const Vec3d> rest_positions,
                           std::span<const geometry::Triangle> triangles) {
    require_positive(bend_stiffness, "bend_stiffness (N·m)");
    double sum = 0.0;
    std::size_t count = 0;
    for (const EdgeMeasure& m : edge_measures(rest_positions, triangles)) {
        if (m.triangles == 2 && m.area > 0.0 && m.length_squared > 0.0) {
            sum += m.area / m.length_squared;
            ++count;
        }
    }
    if (count == 0) {
        return 1.0 / bend_stiffness;
    }
    return sum / static_cast<double>(count) / (BEND_HINGE_FACTOR * bend_stiffness);
}

ClothMaterial with_fabric(ClothMaterial material, const FabricProperties& fabric,
                          std::span<const Vec3d> rest_positions,
                          std::span<const geometry::Triangle> triangles) {
    require_positive(fabric.areal_density, "areal_density (kg/m²)");
    material.areal_density = fabric.areal_density;
    material.stretch_compliance =
        stretch_compliance_for(fabric.stretch_stiffness, rest_positions, triangles);
    material.bend_compliance =
        bend_compliance_for(fabric.bend_stiffness, rest_positions, triangles);
    return material;
}

}  // namespace pliant::cloth
