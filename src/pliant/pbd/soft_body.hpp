// SoftBody: an XPBD soft body on a tetrahedral mesh (Park & Kye 2022's deformable volume), with
// edge-distance and tet-volume constraints and the drivers of drivers.hpp.
//
// Method: extended position-based dynamics (Macklin, Müller, Chentanez, "XPBD", MIG 2016) run as
// n small substeps of one constraint iteration each (Macklin, Storey, Lu, Terdiman, Chentanez,
// Jeschke, Müller, "Small Steps in Physics Simulation", SCA 2019). Every substep h = dt / n:
//   1. predict: v += h g; x_previous = x; x += h v; driven vertices (kinematic drivers) are placed
//      at their targets for the substep's end and get inverse mass 0 for this substep; pinned
//      vertices have inverse mass 0 and stay bitwise put;
//   2. edges: C = |x_i − x_j| − L (world units) for every unique tet edge;
//   3. volumes: C = V(x) − V0 for every tet, V = (x1 − x0) · ((x2 − x0) × (x3 − x0)) / 6,
//      ∇_1 C = (x2 − x0) × (x3 − x0) / 6 (and cyclically), ∇_0 C = −Σ ∇_k C (Müller et al.,
//      "Position Based Dynamics", 2007, eq. 16);
//      each constraint: Δλ = −C / (Σ_k w_k |∇_k C|² + α̃), x_k += w_k ∇_k C Δλ (XPBD eq. 17–18,
//      λ starting at 0 in every substep; the kernels project a tet as C' = 6 C with 36 α̃, the
//      same motion without the products by 1/6, detail/projection.hpp);
//   3b. inversion guard (below): for the tets flagged at risk, C = V − 0.1 V0 ≥ 0, hard;
//   4. v = (x − x_previous) / h, then v *= max(0, 1 − damping · h).
//
// Inversion guard. One volume constraint per tet over-constrains the vertices, so under a large
// deformation the constraints cannot all hold, and one Gauss–Seidel sweep leaves the discrepancy
// to the constraints projected first. It is worst at a boundary vertex in few tets: on a TetGrid,
// a vertex with 5 of its 8 cells active lies in 5 corner tets, 5 constraints on its 3
// coordinates. A tet of such a vertex can end a sweep inverted although its own projection
// restores it (the gradient of C is fine through zero): the tets of the vertex projected after it
// push the vertex back through its opposite face and keep their own volume
// (docs/journal/2026-11-25-inversion-guard.md; the test
// TetOfALowValenceVertexDoesNotStayInverted). So the tet kernels flag a tet whose volume
// before its projection is below 0.75 V0 (AT_RISK_RATIO, detail/projection.hpp); after the sweep
// the flagged tets, in colour order on one thread, get the unilateral constraint
// C = V − 0.1 V0 ≥ 0 (GUARD_RATIO; V0 > 0 only) projected where violated, with no stiffness or
// compliance (like a contact, it is not traded against the volume constraints), in passes until
// one moves nothing, 16 at most; a tet still below 0.75 V0 after the guard stays flagged for the
// next substep. The guard keeps the orientation, not the volume: such a tet sits at 0.1 V0. It
// cannot undo an inversion that kinematic drivers impose, nor one whose flagged tets still
// conflict after 16 passes, and a tet that one sweep takes from above 0.75 V0 before its own
// projection to inverted after the sweep is guarded only from the substep whose sweep flags it
// (docs/journal/2026-11-25-inversion-guard.md lists the measured cases).
//
// Stiffness k ∈ (0, 1] (the paper's "stiffness 1.0 vs 0.8"): PBD's stiffness, the fraction of a
// constraint's violation that one projection removes (Müller et al. 2007, §3.3). As XPBD
// compliance, for a constraint j with w_j = Σ_k w_k |∇_k C_j|² at the projection:
//   α̃_j = α_j / h² = (1 − k) / k · w_j  + α_phys / h²,
// so that without α_phys (the default) Δλ = −k C / w_j: k = 1 is XPBD with α = 0 (as stiff as the
// substeps converge) and k = 0.8 removes 80 % of every violation per projection. Edges use
// k_edge = edge_share · k (default 0.05) and volumes k: the body keeps its volume first (a
// nearly incompressible tissue). k = 0.8 is a softer body that deforms more under the same load
// (tests/pbd/soft_body_test.cpp, StiffnessPointEightDeformsMoreThanOne: more edge strain under a
// drag, more sag when hung under gravity). The mapping is per substep, as PBD's stiffness is per
// iteration. The k part depends only on positions and mass ratios: results do not change with
// units or density. The physical route adds α_phys (edge_compliance, volume_compliance, in SI
// units below), the true XPBD compliance, independent of h.
//
// Iterations. `iterations` > 1 runs the constraint sweep (steps 2, 3, 3b) that many times per
// substep, λ starting at 0 in each (the stiffness k is PBD's, per projection: more iterations
// make a stiffer body per substep, as more substeps do). With chebyshev_rho > 0 the positions
// between the sweeps of a substep are extrapolated by Chebyshev's semi-iterative method (Wang,
// "A Chebyshev Semi-Iterative Approach for Accelerating Projective and Position-based
// Dynamics", SIGGRAPH Asia 2015). Per sweep they carry a driver's motion 20–45 % further into
// the body than plain iterations, but per unit of work not as far as more substeps of one sweep
// (docs/performance.md, "Soft-body solver"): the default stays 10 substeps of one plain sweep.
// The recurrence restarts in every substep: a step leaves no solver state beyond the body's
// (save_state is unchanged).
//
// Masses: each vertex gets a quarter of the rest volume of each of its tets times `density`;
// vertices of no tet get inverse mass 0.
//
// Parallelism: constraints are coloured so that no two of a colour share a vertex
// (constraint_coloring.hpp: analytically on a TetGrid — 18 edge colours, 40 tet colours — greedily
// otherwise); colours run one after the other (Gauss–Seidel across colours), the constraints of
// a colour in parallel, 4 (SSE) or 8 (AVX2, chosen at run time) at a time. On a TetGrid the sweep
// is blocked in slabs of lattice layers for cache reuse, with the results of the colour-by-colour
// order (two constraints sharing a vertex are projected in the order of their colours), and with
// AVX2 it runs on positions in float arrays in a solver order where a colour's constraints form
// runs of consecutive vertices (detail/lattice_sweep.hpp: plain vector loads, no transposes); on
// more than one thread that sweep runs as a pipeline of two lanes of lattice rows, one slab apart,
// instead of a parallel loop per colour and slab. The guard runs on one thread over the few
// flagged tets, flagged by index with the same float comparison in every kernel. Rest-state
// drivers recompute only what changes: bubbles alone rewrite the constraints they reach while
// they ramp in and nothing after; a wave is evaluated once per lattice plane. Results are bitwise
// identical for any number of threads and for either SIMD width (the same arithmetic, no FMA).
//
//   const TetGrid grid = build_tet_grid(volume, {.cell_voxels = 4});
//   SoftBody body(grid, {.stiffness = 0.8});
//   body.add_driver(TwistDriver{.axis = Axis::z, .angle = 90.0});
//   for (int frame = 0; frame < 48; ++frame) body.step(1.0 / 24.0);
//   resample(…, body.positions());
//
// Not thread safe (one body per thread); step() parallelises internally.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/constraint_coloring.hpp"
#include "pliant/pbd/drivers.hpp"
#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"

namespace pliant::pbd {

struct SoftBodyOptions {
    double stiffness = 1.0;  // k ∈ (0, 1]: PBD stiffness (see above)
    // β ∈ (0, 1]: edges get the PBD stiffness β · k, volumes k. Below 1 the body keeps its
    // volume first and its edge lengths second, as a nearly incompressible tissue does: at the
    // default a 90° twist of a cube keeps its volume within 1 % (soft_body_test.cpp); at β = 1
    // the edges, which cannot all keep their lengths, pull volume away.
    double edge_share = 0.05;
    // kg per world unit cubed (1000: water, when world units are metres).
    double density = 1000.0;
    double damping = 1.0;  // 1/s: velocities lose the fraction damping · h every substep h
    int substeps = 10;     // per step (≥ 1)
    // Constraint iterations per substep (≥ 1; see "Iterations" above): sweeps of edges, tets and
    // guard, with the Chebyshev acceleration below between them.
    int iterations = 1;
    // Chebyshev acceleration of the iterations (Wang 2015; detail/chebyshev.hpp): the spectral
    // radius ρ ∈ [0, 1) of the plain iteration and the under-relaxation γ ∈ (0, 1]. ρ = 0 and
    // γ = 1 (the default): no acceleration, the plain iterations bit for bit.
    double chebyshev_rho = 0.0;
    double chebyshev_gamma = 1.0;
    Vec3d gravity{0.0, 0.0, 0.0};  // world units / s²; off by default for volumes
    // Physical compliance added to the stiffness mapping (≥ 0; 0 = none): edges in m/N (C in
    // m), volumes in m⁵/N (C in m³, energy ½ C² / α in J).
    double edge_compliance = 0.0;
    double volume_compliance = 0.0;
};

struct SoftBodyStats {
    double volume_ratio = 1.0;  // Σ signed tet volume now / Σ rest tet volume at construction
    std::int64_t inverted_tets = 0;  // tets with signed volume ≤ 0 now
    double ms_per_substep = 0.0;     // wall clock, mean over the last step's substeps
    double step_ms = 0.0;            // wall clock of the last step (incl. rest-state drivers)
};

class SoftBody {
public:
    // rest: the body at rest, also its initial state (world units). Constraints are coloured
    // greedily (arbitrary meshes, e.g. from TetGen). InvalidInput naming the problem for:
    // non-finite positions, tet indices out of range or repeated within a tet, tets of rest
    // volume ≤ 0 (negative: wrongly oriented), options out of range (stiffness ∉ (0, 1],
    // density ≤ 0, damping < 0, substeps < 1, non-finite gravity, negative compliance).
    explicit SoftBody(const geometry::TetMesh& rest, const SoftBodyOptions& options = {});
    // The same on a TetGrid's mesh, coloured analytically from its lattice (fewer colours,
    // no colouring pass).
    explicit SoftBody(const TetGrid& grid, const SoftBodyOptions& options = {});
    ~SoftBody();
    SoftBody(SoftBody&&) noexcept;
    SoftBody& operator=(SoftBody&&) noexcept;

    // Adds a driver (drivers.hpp); InvalidInput for invalid parameters. A vertex driven by
    // several kinematic drivers follows the last added; rest-state drivers compose (waves add
    // displacements, bubbles multiply).
    void add_driver(const Driver& driver);
    void clear_drivers();
    // Drag: grabs `vertex` (with the vertices within `radius` world units of it) and pulls it to
    // `target` (world units) over the next step; calling again with the same vertex moves the
    // target, with another vertex grabs anew. InvalidInput: vertex out of range, target not
    // finite, radius < 0.
    void set_drag(std::int32_t vertex, const Vec3f& target, float radius = 0.0f);
    void release_drag();
    std::optional<DragDriver> drag() const;

    // Changes the PBD stiffness k ∈ (0, 1] (else InvalidInput) from the next step on, as if the
    // body had been built with it (interactive stiffness controls; the state is kept).
    void set_stiffness(double stiffness);

    // Pins vertices: inverse mass 0, never moved (InvalidInput when out of range).
    void pin(std::span<const std::int32_t> vertices);
    // Replaces the current positions / velocities (#V, finite; else InvalidInput); rest state
    // unchanged. For perturbations and restarts.
    void set_positions(std::span<const Vec3f> positions);
    void set_velocities(std::span<const Vec3f> velocities);

    // Advances the body by dt seconds (finite, > 0; else InvalidInput) in options.substeps
    // substeps.
    void step(double dt);

    double time() const { return m_time; }  // s since the start
    std::span<const Vec3f> positions() const;
    std::span<const Vec3f> velocities() const;
    std::span<const Vec3f> rest_positions() const;
    std::span<const float> inv_masses() const;  // 0 = pinned
    std::span<const geometry::Tet> tets() const;
    std::span<const std::array<std::int32_t, 2>> edges() const;  // #E unique, a < b, sorted
    const ConstraintColoring& edge_coloring() const;
    const ConstraintColoring& tet_coloring() const;
    const SoftBodyOptions& options() const { return m_options; }
    // Volume ratio and inverted tets of the current positions (O(#T), parallel, deterministic),
    // with the last step's timings.
    SoftBodyStats stats() const;

    // The state that changes as the body runs (core/bytes.hpp): time, positions, velocities,
    // inverse masses and pins, the current rest lengths and volumes, the inversion guard's flags,
    // the driven vertices and the drag; not the mesh, constraints and drivers the constructor
    // and add_driver set up. A body built and driven the same way that loads it continues bit
    // for bit (checkpoints, pipeline/deform_run.hpp). load_state: InvalidInput for a state of
    // another mesh or a truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    struct State;
    SoftBody(const geometry::TetMesh& rest, const SoftBodyOptions& options, const TetGrid* grid);
    // The drivers for a step ending at t_end (s): driven vertices assigned again when drivers, drag
    // or pins changed; rest lengths and volumes for t_end (back to the construction's once the
    // rest-state drivers are gone); the drag's start.
    void prepare_drivers(double t_end);

    SoftBodyOptions m_options;
    double m_time = 0.0;
    std::unique_ptr<State> m_state;
};

}  // namespace pliant::pbd
