// Untangling cloth that starts out intersecting itself, by intersection contour minimization
// (P. Volino, N. Magnenat-Thalmann, "Resolving Surface Collisions through Intersection Contour
// Minimization", SIGGRAPH 2006): where two parts of the cloth pass through each other, their
// intersection is a set of curves (contours); moving the vertices down the gradient of the
// contours' total length shrinks each closed contour until it vanishes, and the two parts come
// apart without having to decide which side of the other each region belongs to.
//
// The self-collision fail-safe (self_collision.hpp) keeps cloth that starts intersection-free
// intersection-free, but cannot undo an intersection it is given; untangle() runs before the
// simulation, on positions only.
//
// Per iteration:
//   1. the intersecting pairs of triangles that share no vertex, exactly
//      (collision/intersecting_pairs.hpp); none: done;
//   2. for each pair, its intersection segment: its two ends are where an edge of one triangle
//      crosses the other (exact orient3d signs decide which edges cross); the segment's length L
//      moves with the vertices as follows (X an end, where edge p → q, d = q − p, crosses the plane
//      of triangle t with unit normal n, at edge parameter s and barycentric weights b_k in t):
//      moving the edge's points by δ_E = (1 − s) δ_p + s δ_q and the triangle's by
//      δ_T = Σ b_k δ_tk moves X by δX = δ_E + d (n · (δ_T − δ_E)) / (n · d) (X stays on both),
//      so with c = ∂L/∂X (the segment's unit direction, signed) and k = (c · d) / (n · d):
//        ∂L/∂x_p = (1 − s)(c − k n),  ∂L/∂x_q = s (c − k n),  ∂L/∂x_tk = b_k k n.
//      |n · d| is clamped below at a tenth of |d| (an edge grazing the plane would otherwise get
//      an unbounded push). Pairs whose intersection is not a segment with two distinct ends
//      (touching at a point or an edge, coplanar overlap) get a push along the line between the
//      triangles' centroids instead (along the second's normal when those coincide);
//   3. the gradient, zero at pinned vertices (inverse mass 0), is spread over `smoothing` rings
//      of mesh neighbours (Jacobi averaging) so that regions move rather than single vertices,
//      then scaled so that the largest move is `step`; the positions move down it;
//   4. `shape_iterations` Gauss-Seidel sweeps over the edges pull each back towards its length at
//      the start (a distance constraint, weighted by the inverse masses), so the cloth moves
//      rather than shrinks.
// The positions with the fewest intersecting pairs seen are the result (a failed run does not
// leave the cloth worse than it found it).
//
// A closed contour (a fold pushed through another layer, a sheet poking through another) shrinks
// and vanishes. A contour that runs from boundary to boundary (two sheets crossing like an X)
// only slides towards a boundary, and contour minimization stalls on it
// (docs/journal/2026-11-25-untangling-crossing-sheets.md has the scene, the command and the
// numbers). When the fewest pairs seen has not improved for 40 iterations, the best state so far
// gets one region move, decided globally as in Baraff, Witkin and Kass's global intersection
// analysis ("Untangling Cloth", SIGGRAPH 2003), and minimization goes on from the moved state:
//   - pieces first: for every connected piece of cloth (triangles joined by vertices) with no
//     pinned vertex and every other piece it intersects, the plane of the other's intersected
//     triangles (area-weighted centroid and normal); the piece's vertices within those
//     triangles' radius of their centroid must all end on one side, `step` beyond the plane:
//     the two rigid moves along the normal that do it. The shortest of all pieces' moves that
//     enters no obstacle (below) is made (no deformation);
//   - regions, when no piece can move: the triangles of intersecting pairs are walls; the
//     connected regions of the other triangles (over edges) that walls cut off from the largest
//     region of their piece are reflected, smallest first, through the plane of the triangles
//     their walls intersect (a fold along the contour, `step` beyond it), when they have no
//     pinned vertex; once per contour (the other layer's regions along it are left alone).
// A plane is taken only from triangles whose normals agree (|Σ n| at least half of Σ |n|; two
// layers wound against each other, as a fold's, give none). A move counts as an iteration;
// the next move waits for a new best state (a move that leads to none is not repeated), and
// when no move applies minimization simply goes on. Moves are as long as the crossing is deep
// (a piece may move by half its size: a 1 m sheet standing through another moves 0.5 m). Given
// the obstacles (UntangleOptions::obstacle_distance), no move puts a vertex that was outside an
// obstacle inside it: a piece takes the shortest move that keeps out, possibly the other
// direction or another piece, and a region that would fold into an obstacle stays (when no other
// applies, the cloth stays tangled and the pairs left are reported). Only where the vertices end
// is checked, not the way there: a move may pass through an obstacle thinner than itself, and
// may end closer to a surface than the cloth's thickness (the first substep pushes those
// vertices out). (Two 1 m sheets of
// 12 x 12 quads crossing above the ground, one flat at 0.22 m, the other tilted by 20 degrees
// with its lowest edge 1 cm up: without this the tilted one sinks to 0.23 m under the ground,
// where the simulation keeps it trapped below the other, 5,000 CCD hits a frame; with it the
// flat one is lifted. tests/cloth/untangle_test.cpp.) Gradient steps are small (`step`) and
// take no notice of obstacles: vertices a step leaves inside an obstacle are put back on it by
// the first substep without an intersection, whereas putting them back at every step leaves a
// layer pressed against an obstacle no room to give way, and pairs stay
// (docs/journal/2026-11-25-untangling-crossing-sheets.md). The best state is chosen on pairs alone.
// Not untangled: a sheet through itself along a contour that cuts no region off (it ends inside the
// sheet on both sides, e.g. where a wider part of the sheet crosses a narrower one), and pinned
// pieces whose contour cuts off no free region.
//
// Units: metres. Deterministic (pairs in sorted order, sequential accumulation; the intersection
// search is identical for any number of threads).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

// Signed distance of a point to the obstacles' surfaces (m, negative inside).
using ObstacleDistance = std::function<double(const Vec3d&)>;

struct UntangleOptions {
    int max_iterations = 400;
    double step = 0.0;  // largest vertex move per iteration, m; 0: an eighth of the mean edge
    int smoothing = 3;  // rings of neighbours each push is spread over
    // Gauss-Seidel sweeps per iteration that pull every edge back towards its starting length
    // (the cloth keeps its shape; a contour that only squeezing would remove stays).
    int shape_iterations = 4;
    // The obstacles region moves keep out of (see the header); empty: none. ClothSolver::untangle
    // gives its own when this is empty.
    ObstacleDistance obstacle_distance;
};

struct UntangleResult {
    std::int64_t initial_pairs = 0;  // intersecting pairs before
    std::int64_t final_pairs = 0;    // after (0: untangled)
    int iterations = 0;              // gradient steps and region moves taken
    int region_moves = 0;            // region moves that led to the result (see above)
    double max_displacement = 0.0;   // largest distance of a vertex from its start, m
    double ms = 0.0;                 // wall-clock time
};

// Moves `positions` (#V, finite) towards a state without intersecting pairs of triangles that
// share no vertex. inverse_masses: #V, vertices with 0 do not move. Throws InvalidInput for
// sizes that do not match, indices out of range, non-finite positions or negative options.
UntangleResult untangle(std::span<Vec3d> positions, std::span<const geometry::Triangle> triangles,
                        std::span<const double> inverse_masses,
                        const UntangleOptions& options = {});

}  // namespace pliant::cloth
