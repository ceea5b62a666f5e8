// SoftBody: validation, setup, the public API and the order of a step's stages. The stages of
// the method (soft_body.hpp) live in detail/: integration.hpp (steps 1 and 4: prediction,
// velocities), driver_apply.hpp (the drivers: driven vertices, targets, rest state),
// constraint_sweep.hpp (steps 2 and 3: the colour sweep) over the layout of
// constraint_layout.hpp, inversion_guard.hpp (step 3b), projection.hpp (the kernels).
#include "pliant/pbd/soft_body.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/pbd/detail/chebyshev.hpp"
#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/detail/constraint_sweep.hpp"
#include "pliant/pbd/detail/driver_apply.hpp"
#include "pliant/pbd/detail/driver_eval.hpp"
#include "pliant/pbd/detail/integration.hpp"
#include "pliant/pbd/detail/inversion_guard.hpp"
#include "pliant/pbd/detail/lattice_sweep.hpp"
#include "pliant/pbd/detail/projection.hpp"

namespace pliant::pbd {

using detail::Float4;

namespace {

void validate_options(const SoftBodyOptions& o) {
    const auto fail = [](const char* field, double value, const char* rule) {
        throw InvalidInput(std::string("pbd::SoftBody: options.") + field + " (" +
                           std::to_string(value) + ") must be " + rule);
    };
    if (!(o.stiffness > 0.0 && o.stiffness <= 1.0)) {
        fail("stiffness", o.stiffness, "in (0, 1]");
    }
    if (!(o.edge_share > 0.0 && o.edge_share <= 1.0)) {
        fail("edge_share", o.edge_share, "in (0, 1]");
    }
    if (!(o.density > 0.0) || !std::isfinite(o.density)) {
        fail("density", o.density, "finite and > 0");
    }
    if (!(o.damping >= 0.0) || !std::isfinite(o.damping)) {
        fail("damping", o.damping, "finite and >= 0");
    }
    if (o.substeps < 1) {
        fail("substeps", o.substeps, ">= 1");
    }
    if (o.iterations < 1) {
        fail("iterations", o.iterations, ">= 1");
    }
    if (!(o.chebyshev_rho >= 0.0 && o.chebyshev_rho < 1.0)) {
        fail("chebyshev_rho", o.chebyshev_rho, "in [0, 1)");
    }
    if (!(o.chebyshev_gamma > 0.0 && o.chebyshev_gamma <= 1.0)) {
        fail("chebyshev_gamma", o.chebyshev_gamma, "in (0, 1]");
    }
    if (!is_finite(o.gravity)) {
        throw InvalidInput("pbd::SoftBody: options.gravity must be finite");
    }
    if (!(o.edge_compliance >= 0.0) || !std::isfinite(o.edge_compliance)) {
        fail("edge_compliance", o.edge_compliance, "finite and >= 0");
    }
    if (!(o.volume_compliance >= 0.0) || !std::isfinite(o.volume_compliance)) {
        fail("volume_compliance", o.volume_compliance, "finite and >= 0");
    }
}

double tet_volume(std::span<const Vec3f> p, const geometry::Tet& t) {
    return geometry::signed_volume(vec3_cast<double>(p[static_cast<std::size_t>(t[0])]),
                                   vec3_cast<double>(p[static_cast<std::size_t>(t[1])]),
                                   vec3_cast<double>(p[static_cast<std::size_t>(t[2])]),
                                   vec3_cast<double>(p[static_cast<std::size_t>(t[3])]));
}

// InvalidInput naming the problem: more than 2³¹ − 1 vertices, non-finite positions, tet indices
// out of range or repeated within a tet, rest volume ≤ 0, a grid whose lattice does not match.
void validate_rest_mesh(const geometry::TetMesh& rest, const TetGrid* grid) {
    const auto nv = static_cast<std::int64_t>(rest.positions.size());
    const auto nt = static_cast<std::int64_t>(rest.tets.size());
    if (nv > std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput("pbd::SoftBody: too many vertices (" + std::to_string(nv) + ")");
    }
    for (std::int64_t v = 0; v < nv; ++v) {
        if (!is_finite(rest.positions[static_cast<std::size_t>(v)])) {
            throw InvalidInput("pbd::SoftBody: rest position " + std::to_string(v) +
                               " is not finite");
        }
    }
    for (std::int64_t t = 0; t < nt; ++t) {
        const geometry::Tet& tet = rest.tets[static_cast<std::size_t>(t)];
        for (int i = 0; i < 4; ++i) {
            if (tet[static_cast<std::size_t>(i)] < 0 || tet[static_cast<std::size_t>(i)] >= nv) {
                throw InvalidInput("pbd::SoftBody: tet " + std::to_string(t) + " vertex " +
                                   std::to_string(tet[static_cast<std::size_t>(i)]) +
                                   " out of range [0, " + std::to_string(nv) + ")");
            }
            for (int j = 0; j < i; ++j) {
                if (tet[static_cast<std::size_t>(i)] == tet[static_cast<std::size_t>(j)]) {
                    throw InvalidInput("pbd::SoftBody: tet " + std::to_string(t) +
                                       " repeats vertex " +
                                       std::to_string(tet[static_cast<std::size_t>(i)]));
                }
            }
        }
        const double volume = tet_volume(rest.positions, tet);
        if (!(volume > 0.0)) {
            throw InvalidInput("pbd::SoftBody: tet " + std::to_string(t) + " has rest volume " +
                               std::to_string(volume) +
                               " (must be > 0: degenerate or negatively oriented)");
        }
    }
    if (grid != nullptr && (grid->vertex_lattice.size() != rest.positions.size() ||
                            grid->tet_cell.size() != rest.tets.size())) {
        throw InvalidInput("pbd::SoftBody: the grid's lattice does not match its mesh");
    }
}

// The axis-aligned box of rest (#V, world units); size 1 for a degenerate box, the default box
// for no vertex.
detail::BodyBox body_box(std::span<const Vec3f> rest) {
    detail::BodyBox box;
    if (!rest.empty()) {
        Vec3d lo = vec3_cast<double>(rest[0]);
        Vec3d hi = lo;
        for (const Vec3f& p : rest) {
            lo = min(lo, vec3_cast<double>(p));
            hi = max(hi, vec3_cast<double>(p));
        }
        box.lo = lo;
        box.hi = hi;
        box.centre = (lo + hi) * 0.5;
        const double size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        box.size = size > 0.0 ? size : 1.0;
    }
    return box;
}

// The float constants of a substep h (s) under options o: computed in double, rounded once.
struct SubstepConstants {
    detail::SubstepMotion motion;
    detail::ConstraintStiffness edges;    // k β (soft_body.hpp, "Stiffness"), α_edge / h²
    detail::ConstraintStiffness volumes;  // k, α_volume / h²
};

SubstepConstants substep_constants(const SoftBodyOptions& o, double h) {
    SubstepConstants c;
    c.motion.h = static_cast<float>(h);
    c.motion.inv_h = 1.0f / c.motion.h;
    c.motion.keep = static_cast<float>(std::max(0.0, 1.0 - o.damping * h));
    c.motion.gravity_h = vec3_cast<float>(o.gravity * h);
    c.edges.inv_k = static_cast<float>(1.0 / (o.stiffness * o.edge_share));
    c.edges.alpha = static_cast<float>(o.edge_compliance / (h * h));
    c.volumes.inv_k = static_cast<float>(1.0 / o.stiffness);
    c.volumes.alpha = static_cast<float>(o.volume_compliance / (h * h));
    return c;
}

}  // namespace

struct SoftBody::State {
    detail::BodyBox box;                             // of rest, for the drivers
    std::vector<Vec3f> rest;                         // #V, world units
    std::vector<geometry::Tet> tets;                 // #T, input order
    std::vector<std::array<std::int32_t, 2>> edges;  // #E, sorted
    double total_rest_volume = 0.0;                  // world units³, at construction
    // Constraint data in colour order: the projection loops stream through them.
    detail::EdgeConstraints edge_constraints;
    detail::TetConstraints tet_constraints;
    detail::InversionFlags inversion;  // tets flagged for the inversion guard (step 3b)
    // On a TetGrid: the AVX2 sweep over the solver order (lattice_sweep.hpp); no vertex otherwise.
    detail::LatticeSweep lattice;

    // #V each. x: positions and this substep's inverse mass (0 for pinned and driven vertices);
    // previous: x's positions at the substep's start; velocities: world units / s, those of the
    // last substep; positions: x's positions after the last step.
    std::vector<Float4> x;
    std::vector<Vec3f> previous;
    std::vector<Vec3f> velocities;
    std::vector<Vec3f> positions;
    std::vector<float> inv_masses;     // 1/kg; 0 = pinned or in no tet
    std::vector<std::uint8_t> pinned;  // 1 = pinned
    // #V each, within a substep only (detail/chebyshev.hpp): q^k and q^(k-1) of the iterations.
    std::vector<Vec3f> chebyshev_current;
    std::vector<Vec3f> chebyshev_previous;

    std::vector<Driver> drivers;
    bool has_rest_drivers = false;
    bool rest_modified = false;          // rest lengths and volumes differ from the construction's
    detail::RestDriverCache rest_cache;  // reset whenever drivers or the rest state change
    detail::DrivenVertices driven;
    bool kinematics_dirty = false;  // `driven` is to be assigned again
    detail::DragGrab grab;

    double last_step_ms = 0.0;
    double last_substep_ms = 0.0;
};

SoftBody::SoftBody(const geometry::TetMesh& rest, const SoftBodyOptions& options)
    : SoftBody(rest, options, nullptr) {}

SoftBody::SoftBody(const TetGrid& grid, const SoftBodyOptions& options)
    : SoftBody(grid.mesh, options, &grid) {}

SoftBody::~SoftBody() = default;
SoftBody::SoftBody(SoftBody&&) noexcept = default;
SoftBody& SoftBody::operator=(SoftBody&&) noexcept = default;

SoftBody::SoftBody(const geometry::TetMesh& rest, const SoftBodyOptions& options,
                   const TetGrid* grid)
    : m_options(options), m_state(std::make_unique<State>()) {
    validate_options(options);
    State& s = *m_state;
    const auto nv = static_cast<std::int64_t>(rest.positions.size());
    const auto nt = static_cast<std::int64_t>(rest.tets.size());
    // Step 1: validate the mesh.
    validate_rest_mesh(rest, grid);
    s.rest = rest.positions;
    s.tets = rest.tets;

    // Step 2: the box drivers work in.
    s.box = body_box(s.rest);

    // Step 3: masses: a quarter of each tet's rest mass to each of its vertices.
    std::vector<double> mass(static_cast<std::size_t>(nv), 0.0);
    std::vector<double> rest_volume(static_cast<std::size_t>(nt));
    for (std::int64_t t = 0; t < nt; ++t) {
        const geometry::Tet& tet = s.tets[static_cast<std::size_t>(t)];
        const double volume = tet_volume(s.rest, tet);
        rest_volume[static_cast<std::size_t>(t)] = volume;
        s.total_rest_volume += volume;
        for (const std::int32_t v : tet) {
            mass[static_cast<std::size_t>(v)] += 0.25 * options.density * volume;
        }
    }
    s.inv_masses.resize(static_cast<std::size_t>(nv));
    for (std::size_t v = 0; v < mass.size(); ++v) {
        s.inv_masses[v] = mass[v] > 0.0 ? static_cast<float>(1.0 / mass[v]) : 0.0f;
    }
    s.pinned.assign(static_cast<std::size_t>(nv), 0);

    // Step 4: edges, colourings (analytic on a grid, greedy otherwise), constraint data in colour
    // order.
    s.edges = tet_edges(s.tets, nv);
    ConstraintColoring edge_coloring;
    ConstraintColoring tet_coloring;
    if (grid != nullptr) {
        edge_coloring = color_grid_edges(*grid, s.edges);
        tet_coloring = color_grid_tets(*grid);
    } else {
        edge_coloring =
            color_greedy(static_cast<std::int64_t>(s.edges.size()), nv, [&](std::int64_t e) {
                return std::span<const std::int32_t>(s.edges[static_cast<std::size_t>(e)]);
            });
        tet_coloring = color_greedy(nt, nv, [&](std::int64_t t) {
            return std::span<const std::int32_t>(s.tets[static_cast<std::size_t>(t)]);
        });
    }
    s.edge_constraints =
        detail::layout_edge_constraints(std::move(edge_coloring), s.edges, s.rest, grid);
    s.tet_constraints =
        detail::layout_tet_constraints(std::move(tet_coloring), s.tets, rest_volume, grid);
    if (grid != nullptr) {
        s.lattice = detail::build_lattice_sweep(*grid, s.edge_constraints, s.tet_constraints);
    }
    s.inversion = detail::unflagged(s.tet_constraints);

    // Step 5: state.
    s.x.resize(static_cast<std::size_t>(nv));
    for (std::size_t v = 0; v < s.x.size(); ++v) {
        s.x[v] = {s.rest[v].x, s.rest[v].y, s.rest[v].z, s.inv_masses[v]};
    }
    s.previous = s.rest;
    s.positions = s.rest;
    s.velocities.assign(static_cast<std::size_t>(nv), Vec3f{});
}

void SoftBody::add_driver(const Driver& driver) {
    detail::validate_driver(driver);
    State& s = *m_state;
    s.drivers.push_back(driver);
    s.has_rest_drivers = s.has_rest_drivers || std::holds_alternative<WaveDriver>(driver) ||
                         std::holds_alternative<BubbleDriver>(driver);
    s.rest_cache = {};
    s.kinematics_dirty = true;
}

void SoftBody::clear_drivers() {
    State& s = *m_state;
    s.drivers.clear();
    s.has_rest_drivers = false;
    s.rest_cache = {};
    s.kinematics_dirty = true;
}

void SoftBody::set_drag(std::int32_t vertex, const Vec3f& target, float radius) {
    State& s = *m_state;
    const auto nv = static_cast<std::int64_t>(s.rest.size());
    if (vertex < 0 || vertex >= nv) {
        throw InvalidInput("pbd::SoftBody::set_drag: vertex " + std::to_string(vertex) +
                           " out of range [0, " + std::to_string(nv) + ")");
    }
    if (!is_finite(target)) {
        throw InvalidInput("pbd::SoftBody::set_drag: target is not finite");
    }
    if (!(radius >= 0.0f) || !std::isfinite(radius)) {
        throw InvalidInput("pbd::SoftBody::set_drag: radius (" + std::to_string(radius) +
                           ") must be finite and >= 0");
    }
    if (s.grab.drag && s.grab.drag->vertex == vertex) {
        s.grab.drag->target = target;
        return;
    }
    detail::grab_vertices(DragDriver{vertex, target, radius}, s.positions, s.grab);
    s.kinematics_dirty = true;
}

void SoftBody::release_drag() {
    State& s = *m_state;
    s.grab.drag.reset();
    s.grab.vertices.clear();
    s.grab.offsets.clear();
    s.kinematics_dirty = true;
}

void SoftBody::set_stiffness(double stiffness) {
    SoftBodyOptions options = m_options;
    options.stiffness = stiffness;
    validate_options(options);
    m_options.stiffness = stiffness;
}

std::optional<DragDriver> SoftBody::drag() const {
    return m_state->grab.drag;
}

void SoftBody::pin(std::span<const std::int32_t> vertices) {
    State& s = *m_state;
    const auto nv = static_cast<std::int64_t>(s.rest.size());
    for (const std::int32_t v : vertices) {
        if (v < 0 || v >= nv) {
            throw InvalidInput("pbd::SoftBody::pin: vertex " + std::to_string(v) +
                               " out of range [0, " + std::to_string(nv) + ")");
        }
    }
    for (const std::int32_t v : vertices) {
        const auto i = static_cast<std::size_t>(v);
        s.pinned[i] = 1;
        s.inv_masses[i] = 0.0f;
        s.x[i].w = 0.0f;
        s.velocities[i] = {};
    }
    s.kinematics_dirty = true;
}

void SoftBody::set_positions(std::span<const Vec3f> positions) {
    State& s = *m_state;
    if (positions.size() != s.rest.size()) {
        throw InvalidInput("pbd::SoftBody::set_positions: positions.size() (" +
                           std::to_string(positions.size()) + ") != vertices (" +
                           std::to_string(s.rest.size()) + ")");
    }
    for (std::size_t v = 0; v < positions.size(); ++v) {
        if (!is_finite(positions[v])) {
            throw InvalidInput("pbd::SoftBody::set_positions: position " + std::to_string(v) +
                               " is not finite");
        }
    }
    for (std::size_t v = 0; v < positions.size(); ++v) {
        s.x[v] = {positions[v].x, positions[v].y, positions[v].z, s.x[v].w};
        s.positions[v] = positions[v];
    }
}

void SoftBody::set_velocities(std::span<const Vec3f> velocities) {
    State& s = *m_state;
    if (velocities.size() != s.rest.size()) {
        throw InvalidInput("pbd::SoftBody::set_velocities: velocities.size() (" +
                           std::to_string(velocities.size()) + ") != vertices (" +
                           std::to_string(s.rest.size()) + ")");
    }
    for (std::size_t v = 0; v < velocities.size(); ++v) {
        if (!is_finite(velocities[v])) {
            throw InvalidInput("pbd::SoftBody::set_velocities: velocity " + std::to_string(v) +
                               " is not finite");
        }
    }
    std::copy(velocities.begin(), velocities.end(), s.velocities.begin());
}

void SoftBody::prepare_drivers(double t_end) {
    State& s = *m_state;
    if (s.kinematics_dirty) {
        detail::assign_driven_vertices(s.drivers, s.box, s.rest, s.pinned, s.grab.vertices,
                                       s.driven);
        s.kinematics_dirty = false;
    }
    if (s.has_rest_drivers) {
        detail::apply_rest_drivers(s.drivers, s.box, s.rest, t_end, s.edge_constraints,
                                   s.tet_constraints, s.rest_cache, &s.lattice);
        s.rest_modified = true;
    } else if (s.rest_modified) {
        s.edge_constraints.rest_lengths = s.edge_constraints.rest_lengths0;
        s.tet_constraints.rest_volumes = s.tet_constraints.rest_volumes0;
        s.rest_modified = false;
        s.rest_cache = {};
    }
    if (s.grab.drag && !s.grab.vertices.empty()) {
        s.grab.from = s.positions[static_cast<std::size_t>(s.grab.drag->vertex)];
    }
}

void SoftBody::step(double dt) {
    if (!(dt > 0.0) || !std::isfinite(dt)) {
        throw InvalidInput("pbd::SoftBody::step: dt (" + std::to_string(dt) +
                           ") must be finite and > 0");
    }
    Stopwatch step_watch;
    State& s = *m_state;
    prepare_drivers(m_time + dt);
    const int n = m_options.substeps;
    const double h = dt / n;
    const SubstepConstants k = substep_constants(m_options, h);
    // The kernels give the same bits (projection_avx2.hpp): the choice is for speed only.
    const bool use_avx2 = pliant::has_avx2();
    const bool use_lattice = use_avx2 && !s.lattice.vertex_of.empty();
    Float4* x = s.x.data();
    // Iterations (soft_body.hpp): ω of each iteration, rounded once; no pass when plain.
    const bool accelerate = m_options.chebyshev_rho > 0.0 || m_options.chebyshev_gamma < 1.0;
    std::vector<float> omegas(static_cast<std::size_t>(m_options.iterations));
    for (int it = 0; it < m_options.iterations; ++it) {
        omegas[static_cast<std::size_t>(it)] =
            static_cast<float>(detail::chebyshev_omega(it, m_options.chebyshev_rho));
    }
    const auto gamma = static_cast<float>(m_options.chebyshev_gamma);
    if (accelerate && s.chebyshev_current.size() != s.x.size()) {
        s.chebyshev_current.resize(s.x.size());
        s.chebyshev_previous.resize(s.x.size());
    }
    // One plain iteration on a grid with AVX2: the whole step on the lattice sweep's arrays, x
    // copied into them once (lattice_sweep.hpp; the same bits as the general loop below).
    const bool in_solver_order = use_lattice && m_options.iterations == 1 && !accelerate;
    Stopwatch substeps_watch;
    for (int sub = 0; sub < n; ++sub) {
        // Step 1 (soft_body.hpp): predict; after the first substep, fused into the previous
        // substep's step 4. Driven vertices at their targets for the substep's end, w = 0.
        if (sub == 0) {
            detail::predict(x, s.previous, s.velocities, s.inv_masses, k.motion);
        }
        if (!s.driven.vertices.empty()) {
            detail::place_driven_vertices(x, s.drivers, s.box, s.rest, s.driven, s.grab,
                                          m_time + h * (sub + 1),
                                          static_cast<float>(sub + 1) / static_cast<float>(n));
            if (in_solver_order && sub > 0) {
                detail::load_lattice_vertices(x, s.driven.vertices, s.lattice);
            }
        }
        if (in_solver_order) {
            if (sub == 0) {
                detail::load_lattice(x, s.previous, s.inv_masses, s.pinned, s.lattice);
            }
            detail::sweep_lattice(s.lattice, s.edge_constraints, s.tet_constraints, k.edges,
                                  k.volumes, s.inversion.tet_at_risk, s.inversion.colour_at_risk);
            detail::guard_lattice(s.lattice, s.tet_constraints, s.inversion);
            if (sub + 1 < n) {
                detail::finish_lattice_substep(s.lattice, k.motion);
            } else {
                detail::finish_lattice_step(s.lattice, k.motion, x, s.previous, s.velocities,
                                            s.positions);
            }
            continue;
        }
        if (accelerate) {
            detail::chebyshev_begin(x, s.chebyshev_current, s.chebyshev_previous);
        }
        for (int it = 0; it < m_options.iterations; ++it) {
            // Step 2: edge lengths, colour by colour; step 3: tet volumes, colour by colour,
            // flagging the tets at risk of inversion (on a grid with AVX2 both in the solver
            // order, the same bits); 3b: the inversion guard on them.
            if (use_lattice) {
                detail::project_lattice(x, s.lattice, s.edge_constraints, s.tet_constraints,
                                        k.edges, k.volumes, s.inversion.tet_at_risk,
                                        s.inversion.colour_at_risk);
            } else {
                detail::project_edges(x, s.edge_constraints, k.edges, use_avx2);
                detail::project_tets(x, s.tet_constraints, k.volumes, use_avx2,
                                     s.inversion.tet_at_risk, s.inversion.colour_at_risk);
            }
            detail::guard_flagged_tets(x, s.tet_constraints, s.inversion);
            // Iterations: Chebyshev's extrapolation of the free vertices, between sweeps (the
            // last sweep and its guard have the last word, so no extrapolation inverts a tet).
            if (accelerate && it + 1 < m_options.iterations) {
                detail::chebyshev_update(x, s.chebyshev_current, s.chebyshev_previous,
                                         omegas[static_cast<std::size_t>(it)], gamma);
            }
        }
        // Step 4: velocities from the motion, damped; with the next substep's prediction, or
        // after the last substep stored with the positions.
        if (sub + 1 < n) {
            detail::update_velocities_and_predict(x, s.previous, s.inv_masses, s.pinned, k.motion);
        } else {
            detail::update_velocities(x, s.previous, s.pinned, k.motion, s.velocities, s.positions);
        }
    }
    // The step's wall clock, for stats().
    const double substeps_ms = substeps_watch.elapsed_ms();
    m_time += dt;
    s.last_substep_ms = substeps_ms / n;
    s.last_step_ms = step_watch.elapsed_ms();
}

std::span<const Vec3f> SoftBody::positions() const {
    return m_state->positions;
}
std::span<const Vec3f> SoftBody::velocities() const {
    return m_state->velocities;
}
std::span<const Vec3f> SoftBody::rest_positions() const {
    return m_state->rest;
}
std::span<const float> SoftBody::inv_masses() const {
    return m_state->inv_masses;
}
std::span<const geometry::Tet> SoftBody::tets() const {
    return m_state->tets;
}
std::span<const std::array<std::int32_t, 2>> SoftBody::edges() const {
    return m_state->edges;
}
const ConstraintColoring& SoftBody::edge_coloring() const {
    return m_state->edge_constraints.coloring;
}
const ConstraintColoring& SoftBody::tet_coloring() const {
    return m_state->tet_constraints.coloring;
}

SoftBodyStats SoftBody::stats() const {
    const State& s = *m_state;
    struct Sums {
        double volume = 0.0;
        std::int64_t inverted = 0;
    };
    const Sums sums = parallel_reduce(
        static_cast<std::int64_t>(s.tets.size()), Sums{},
        [&](std::int64_t begin, std::int64_t end) {
            Sums part;
            for (std::int64_t t = begin; t < end; ++t) {
                const double v = tet_volume(s.positions, s.tets[static_cast<std::size_t>(t)]);
                part.volume += v;
                part.inverted += v <= 0.0 ? 1 : 0;
            }
            return part;
        },
        [](Sums a, const Sums& b) {
            a.volume += b.volume;
            a.inverted += b.inverted;
            return a;
        });
    SoftBodyStats stats;
    stats.volume_ratio = s.total_rest_volume > 0.0 ? sums.volume / s.total_rest_volume : 1.0;
    stats.inverted_tets = sums.inverted;
    stats.ms_per_substep = s.last_substep_ms;
    stats.step_ms = s.last_step_ms;
    return stats;
}

void SoftBody::save_state(ByteWriter& out) const {
    const State& s = *m_state;
    out.put(static_cast<std::uint64_t>(s.positions.size()));
    out.put(static_cast<std::uint64_t>(s.tets.size()));
    out.put(m_time);
    out.put_vector(s.x);
    out.put_vector(s.previous);
    out.put_vector(s.velocities);
    out.put_vector(s.positions);
    out.put_vector(s.inv_masses);
    out.put_vector(s.pinned);
    out.put_vector(s.edge_constraints.rest_lengths);
    out.put_vector(s.tet_constraints.rest_volumes);
    out.put_vector(s.inversion.tet_at_risk);
    out.put_vector(s.inversion.colour_at_risk);
    out.put(s.rest_modified);
    out.put(s.kinematics_dirty);
    out.put_vector(s.driven.vertices);
    out.put_vector(s.driven.driver);
    out.put(s.grab.drag.has_value());
    if (s.grab.drag) {
        out.put(s.grab.drag->vertex);
        out.put(s.grab.drag->target);
        out.put(s.grab.drag->radius);
    }
    out.put_vector(s.grab.vertices);
    out.put_vector(s.grab.offsets);
    out.put(s.grab.from);
}

void SoftBody::load_state(ByteReader& in) {
    State& s = *m_state;
    const auto num_vertices = in.get<std::uint64_t>("soft_body.num_vertices");
    const auto num_tets = in.get<std::uint64_t>("soft_body.num_tets");
    if (num_vertices != s.positions.size() || num_tets != s.tets.size()) {
        throw InvalidInput(
            fmt::format("{}: soft body: a state of {} vertices and {} tets, the body has {} and {}",
                        in.source(), num_vertices, num_tets, s.positions.size(), s.tets.size()));
    }
    const auto n = static_cast<std::int64_t>(num_vertices);
    const double time = in.get<double>("soft_body.time");
    in.get_vector("soft_body.x", s.x, n);
    in.get_vector("soft_body.previous", s.previous, n);
    in.get_vector("soft_body.velocities", s.velocities, n);
    in.get_vector("soft_body.positions", s.positions, n);
    in.get_vector("soft_body.inv_masses", s.inv_masses, n);
    in.get_vector("soft_body.pinned", s.pinned, n);
    in.get_vector("soft_body.rest_lengths", s.edge_constraints.rest_lengths,
                  static_cast<std::int64_t>(s.edge_constraints.rest_lengths0.size()));
    in.get_vector("soft_body.rest_volumes", s.tet_constraints.rest_volumes,
                  static_cast<std::int64_t>(s.tet_constraints.rest_volumes0.size()));
    in.get_vector("soft_body.tet_at_risk", s.inversion.tet_at_risk,
                  static_cast<std::int64_t>(s.inversion.tet_at_risk.size()));
    in.get_vector("soft_body.colour_at_risk", s.inversion.colour_at_risk,
                  static_cast<std::int64_t>(s.inversion.colour_at_risk.size()));
    s.rest_modified = in.get_bool("soft_body.rest_modified");
    s.rest_cache = {};
    s.kinematics_dirty = in.get_bool("soft_body.kinematics_dirty");
    in.get_vector("soft_body.driven.vertices", s.driven.vertices);
    in.get_vector("soft_body.driven.driver", s.driven.driver,
                  static_cast<std::int64_t>(s.driven.vertices.size()));
    const auto num_drivers = static_cast<std::int32_t>(s.drivers.size());
    for (std::size_t i = 0; i < s.driven.vertices.size(); ++i) {
        const std::int32_t v = s.driven.vertices[i];
        const std::int32_t d = s.driven.driver[i];
        if (v < 0 || v >= n || (d != detail::DRAG && (d < 0 || d >= num_drivers))) {
            throw InvalidInput(
                fmt::format("{}: soft body: driven vertex {} by driver {}", in.source(), v, d));
        }
    }
    s.grab.drag.reset();
    if (in.get_bool("soft_body.has_drag")) {
        DragDriver drag;
        drag.vertex = in.get<std::int32_t>("soft_body.drag.vertex");
        drag.target = in.get<Vec3f>("soft_body.drag.target");
        drag.radius = in.get<float>("soft_body.drag.radius");
        if (drag.vertex < 0 || drag.vertex >= n) {
            throw InvalidInput(
                fmt::format("{}: soft body: drag vertex {} of {}", in.source(), drag.vertex, n));
        }
        s.grab.drag = drag;
    }
    in.get_vector("soft_body.grab.vertices", s.grab.vertices);
    in.get_vector("soft_body.grab.offsets", s.grab.offsets,
                  static_cast<std::int64_t>(s.grab.vertices.size()));
    for (const std::int32_t v : s.grab.vertices) {
        if (v < 0 || v >= n) {
            throw InvalidInput(
                fmt::format("{}: soft body: grabbed vertex {} of {}", in.source(), v, n));
        }
    }
    s.grab.from = in.get<Vec3f>("soft_body.grab.from");
    m_time = time;
}

}  // namespace pliant::pbd
