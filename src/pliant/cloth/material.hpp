// ClothMaterial: the physical parameters of an XPBD cloth (SI units), with defaults for a light
// cotton-like fabric.
//
// Compliances are XPBD's α (Macklin, Müller, Chentanez, "XPBD: Position-Based Simulation of
// Compliant Constrained Dynamics", MIG 2016): the inverse stiffness of a constraint C with energy
// ½ C² / α. A constraint's step uses α̃ = α / h² for the substep h, so 0 means rigid (as far as
// the substeps converge) and larger values are softer.
#pragma once

#include <limits>

namespace pliant::cloth {

// The bending energy of a hinge (two triangles sharing an edge).
enum class BendingModel {
    // C = θ − θ_rest, θ the dihedral angle (dihedral.hpp): any rest shape.
    dihedral,
    // The quadratic isometric model (isometric_bending.hpp; Bergou et al. 2006) on hinges flat at
    // rest, the dihedral constraint on the others: as stiff as the dihedral one for small angles,
    // softer towards a full fold (2 sin(θ/2) instead of θ), and linear in the positions, so its
    // projection costs no square root or arctangent (faster than the dihedral kernel). Sharp
    // folds bend more easily, so cloth in heavy self-contact folds tighter, which costs the
    // twist scene more CCD work (docs/journal/2026-11-25-isometric-bending.md).
    isometric,
};

// How the stretch constraints are solved.
enum class StretchSolver {
    // One edge at a time, colour by colour (Gauss-Seidel, one iteration per substep): a
    // correction travels one edge per substep, so long paths under load (a hanging skirt)
    // stretch the more the fewer the substeps.
    edges,
    // Chains of edges, each solved as a whole (stretch_chains.hpp): a correction reaches the
    // whole chain at once, and the cloth keeps its length as its compliance asks (measured
    // against single edges in docs/performance.md, "Cloth"). The default. Where pins ask for more
    // length than the cloth has (the twist scene's two full
    // turns), the cloth, holding its length, is squeezed into far more self-contact; that scene
    // keeps single edges.
    chains,
};

struct ClothMaterial {
    // kg/m²: mass per unit of rest area; each vertex gets a third of its triangles' mass.
    double areal_density = 0.15;
    // m/N, per edge, for C = |x_i - x_j| - rest length (metres). 0: inextensible.
    double stretch_compliance = 1e-7;
    // rad²/J = 1/(N·m), per interior edge, for the bending constraint in radians: C = dihedral
    // angle - rest angle, or the isometric model's C (to first order the same angle).
    double bend_compliance = 1.0;
    BendingModel bending = BendingModel::dihedral;
    StretchSolver stretch_solver = StretchSolver::chains;
    // Unitless: multi-resolution strain limiting (strain_hierarchy.hpp). Coarse vertices farther
    // apart than (1 + strain_limit) times the shortest path between them along the rest mesh's
    // edges are pulled together every substep (by a fifth of the excess, at most a tenth of the
    // thickness per limit), however slowly the edges' own stretch constraints converge; single
    // edges can still stretch by their compliance. Infinity (the default): no limit (measured on
    // the built-in scenes: docs/journal/2026-11-25-strain-limiting.md).
    double strain_limit = std::numeric_limits<double>::infinity();
    // 1/s: velocities lose the fraction damping · h of themselves every substep h.
    double damping = 0.5;
    // m: the distance the cloth keeps from obstacles (and, with self-collision, from itself).
    double thickness = 0.005;
    // Coulomb friction against obstacles (unitless): static (sticks while the tangential move is
    // at most static_friction · penetration) and kinetic (slides, slowed by kinetic_friction ·
    // penetration).
    double static_friction = 0.4;
    double kinetic_friction = 0.3;
    // Coulomb friction of the cloth against itself (self-collision contacts), as above.
    double self_static_friction = 0.3;
    double self_kinetic_friction = 0.2;
};

}  // namespace pliant::cloth
