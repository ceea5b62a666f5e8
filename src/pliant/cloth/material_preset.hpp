// Fabric presets and physical stiffnesses: a fabric described the way textile labs measure it
// (areal density, tensile stiffness per unit width, bending rigidity per unit width) turned into
// the solver's XPBD compliances (material.hpp) for a given mesh, so that the same fabric drapes
// the same at any mesh resolution.
//
//   const FabricProperties denim = *fabric_preset("denim");
//   material = with_fabric(material, denim, mesh.positions, mesh.triangles);
//
// Conversion (docs/formats.md, "Material presets", has the derivation and the sources):
//   stretch: an edge e with adjacent rest triangle areas A1 (+ A2) and rest length l_e stores
//     the energy ½ Y (A1 + A2) (Δl / l_e)², Y the tensile stiffness (N/m = Young's modulus ×
//     thickness), i.e. spring stiffness k_e = Y (A1 + A2) / l_e² and compliance α_e = 1 / k_e
//     (m/N). On an equilateral mesh that network has Young's modulus Y exactly; on a grid of
//     right triangles (geometry::make_grid_sheet) with one α for all edges, Y along the grid
//     lines exactly.
//   bending: a hinge e stores ½ k_e θ² with k_e = BEND_HINGE_FACTOR · B |e|² / (A1 + A2), B the
//     bending rigidity (N·m, moment per unit width per unit curvature): the discrete-shell energy
//     (Grinspun et al. 2003) with the factor between the equilateral-mesh value (2) and the
//     value exact for a grid bent along its lines (1); compliance 1 / k_e (rad²/J).
//   The solver takes one compliance per kind, so the mean over the mesh's edges (hinges) is
//   used: for a uniform mesh α = c / Y with c independent of the edge length, so refining the
//   mesh keeps the fabric's stiffness.
// Units: SI.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/cloth/material.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

struct FabricProperties {
    double areal_density = 0.15;     // kg/m²
    double stretch_stiffness = 1e4;  // N/m: tensile force per unit width per unit strain
    double bend_stiffness = 1e-5;    // N·m: bending moment per unit width per unit curvature
};

inline constexpr double BEND_HINGE_FACTOR = 1.5;

// The presets' names, in the order docs/formats.md lists them: cotton, silk, denim, leather,
// rubber.
const std::vector<std::string>& fabric_preset_names();

// A preset by name, or nothing for an unknown name.
std::optional<FabricProperties> fabric_preset(std::string_view name);

// Stretch compliance (m/N) for tensile stiffness Y (N/m) on this mesh: the mean over its edges of
// l_e² / (Y (A1 + A2)). InvalidInput for Y not finite and > 0 or a mesh without triangles of
// positive area.
double stretch_compliance_for(double stretch_stiffness, std::span<const Vec3d> rest_positions,
                              std::span<const geometry::Triangle> triangles);

// Bend compliance (rad²/J) for bending rigidity B (N·m): the mean over interior edges of
// (A1 + A2) / (BEND_HINGE_FACTOR · B |e|²); a mesh without interior edges gives 1 / B.
// InvalidInput for B not finite and > 0.
double bend_compliance_for(double bend_stiffness, std::span<const Vec3d> rest_positions,
                           std::span<const geometry::Triangle> triangles);

// `material` with the fabric's areal density and the compliances above for this mesh.
ClothMaterial with_fabric(ClothMaterial material, const FabricProperties& fabric,
                          std::span<const Vec3d> rest_positions,
                          std::span<const geometry::Triangle> triangles);

}  // namespace pliant::cloth
