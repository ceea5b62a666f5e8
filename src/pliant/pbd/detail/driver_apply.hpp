// The drivers of drivers.hpp applied to the soft body (their formulas: driver_eval.hpp): which
// vertices follow which kinematic driver (twist, rotate, drag), where those vertices are at the end
// of each substep, and the rest lengths and volumes the rest-state drivers (wave, bubble) ask for.
// Internal to SoftBody. Lengths in world units; times in seconds since the body's start.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/detail/driver_eval.hpp"
#include "pliant/pbd/detail/lattice_sweep.hpp"
#include "pliant/pbd/detail/projection.hpp"
#include "pliant/pbd/drivers.hpp"

namespace pliant::pbd::detail {

// DrivenVertices::driver of a vertex the drag holds.
inline constexpr std::int32_t DRAG = -2;

// The drag (SoftBody::set_drag) and the vertices it holds.
struct DragGrab {
    std::optional<DragDriver> drag;
    std::vector<std::int32_t> vertices;  // ascending; the drag's vertex among them
    std::vector<Vec3f> offsets;          // per grabbed vertex: from the drag's vertex when grabbed
    Vec3f from{};                        // the drag's vertex at the start of the current step
};

// The vertices that follow a kinematic driver, ascending, none pinned.
struct DrivenVertices {
    std::vector<std::int32_t> vertices;
    std::vector<std::int32_t> driver;  // per driven vertex: index into the drivers, or DRAG
};

// Grabs for `drag`: the drag's vertex and the vertices within drag.radius of it in `positions`
// (#V), with their offsets from it; replaces what `grab` held (its `from` is left as it is).
void grab_vertices(const DragDriver& drag, std::span<const Vec3f> positions, DragGrab& grab);

// Which vertex follows which kinematic driver: a twist holds the vertices of rest (#V) within
// grip · L (+ 1e-6 L) of its axis's two faces of `box`, a rotate holds every vertex; a vertex held
// by several follows the last driver added, the drag (grabbed: ascending) overrides them, and
// pinned vertices (#V, 1 = pinned) follow none. Writes `driven`, reusing its storage;
// O(#V · drivers).
void assign_driven_vertices(std::span<const Driver> drivers, const BodyBox& box,
                            std::span<const Vec3f> rest, std::span<const std::uint8_t> pinned,
                            std::span<const std::int32_t> grabbed, DrivenVertices& driven);

// Places every driven vertex of x (#V, packed with the substep's inverse masses) at its target for
// time t_end with inverse mass 0: a rotate's or twist's rest position turned by the driver's
// ramped angle about its centre (the box's, or a rotate's own; a twist turns only the vertices
// beyond the centre along its axis, the others stay at rest), computed in double and rounded to
// float; a dragged vertex at from + (target − from) · drag_fraction + its offset, in float.
// Parallel over the driven vertices, deterministic.
void place_driven_vertices(Float4* x, std::span<const Driver> drivers, const BodyBox& box,
                           std::span<const Vec3f> rest, const DrivenVertices& driven,
                           const DragGrab& grab, double t_end, float drag_fraction);

// What apply_rest_drivers keeps from one call to the next: per wave the distinct rest coordinates
// along its direction and each vertex's among them; when only bubbles run (no wave), the
// constraints some bubble reaches (bubble_reaches at the rest midpoint or centroid; every other
// one keeps its construction's value) and the bubbles' ramps s(t) of the last call. Valid only
// while the drivers and the rest state it wrote stay: reset it (= {}) when drivers are added or
// cleared, or the rest state is replaced (load_state, back to the construction's).
struct RestDriverCache {
    bool is_valid = false;
    std::vector<std::vector<double>> wave_coordinates;  // per wave: ascending, distinct
    std::vector<std::vector<std::int32_t>> wave_plane;  // per wave, #V: index into the above
    std::vector<std::int64_t> edges;                    // colour-order indices, ascending
    std::vector<std::int64_t> tets;
    std::vector<double> ramps;  // per bubble, in the drivers' order
    // With a lattice sweep and waves: the rest positions in its solver order, and the
    // displacements' arrays (rewritten by every call; kept for their storage).
    std::vector<float> solver_rest_x, solver_rest_y, solver_rest_z;
    std::vector<float> solver_u_x, solver_u_y, solver_u_z;
};

// The rest state the rest-state drivers ask for at time t: rest positions r (#V) displaced by u,
// the sum of the waves (in double, rounded to float per vertex), edge lengths and tet volumes of
// the displaced positions in float (wave_rest.hpp: differences as (r_a − r_b) + (u_a − u_b); the
// construction's values when no wave runs), then scaled in double by the product of the bubbles'
// factors f at the rest midpoint (edges: f^(1/3)) or rest centroid (tets). Writes
// edges.rest_lengths and tets.rest_volumes (float, colour order); parallel, deterministic. With
// `lattice` (the constraints' lattice sweep, or nullptr) and AVX2 the waves' values are computed
// over its runs 8 at a time, the same bits. With bubbles alone and a valid cache it writes only
// the constraints the bubbles reach, and nothing when the bubbles' ramps are those of the last
// call (a bubble that has ramped in is a constant rest state): the same values as a full pass,
// bit for bit, at O(constraints reached) or O(1).
void apply_rest_drivers(std::span<const Driver> drivers, const BodyBox& box,
                        std::span<const Vec3f> rest, double t, EdgeConstraints& edges,
                        TetConstraints& tets, RestDriverCache& cache,
                        const LatticeSweep* lattice = nullptr);

}  // namespace pliant::pbd::detail
