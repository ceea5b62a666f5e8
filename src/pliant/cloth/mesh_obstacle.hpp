// Triangle-mesh obstacles for the cloth solver: a static or keyframed (deforming) triangle mesh,
// e.g. read from OBJ/PLY, that cloth vertices are kept `thickness` away from.
//
//   MeshObstacle body(std::move(mesh));                    // validates, builds the LBVH
//   body.set_positions(next_frame_positions);              // keyframed: same vertex count, refit
//   if (const auto s = body.surface_distance(x, 0.01)) {   // signed distance within 1 cm
//       ... s->distance, s->normal ...
//   }
//
// Queries are closest-point queries through an LBVH over the triangles' boxes (bvh::LBVH,
// bvh::query_wide_nearest): the box [x - r, x + r] starts at r = max_distance and shrinks to the
// best distance found so far, nearest subtrees first. A point farther than max_distance from
// every triangle's box is rejected at the root. The sign comes from the angle-weighted
// pseudo-normal of the closest feature (J. A. Bærentzen, H. Aanæs, "Signed distance computation
// using the angle weighted pseudonormal", IEEE TVCG 11(3), 2005): with n_t the unit normal of
// triangle t (counter-clockwise winding),
//   face t:   n_t
//   edge e:   Σ n_t over the triangles incident to e (two on a manifold edge, one on a boundary)
//   vertex v: Σ α_t n_t over the triangles incident to v, α_t the angle of t at v,
// and x is inside when (x - closest point) · pseudo-normal < 0. This is exact inside/outside for a
// closed, consistently oriented (outward counter-clockwise) manifold mesh; for an open mesh the
// side the triangles' normals point to is outside (beyond a boundary edge, the side of its
// triangle's plane). Non-manifold edges sum all their triangles' normals. Degenerate (zero-area)
// triangles are data: they have no face normal and add nothing to the pseudo-normals.
//
// Choosing max_distance: a point deeper than max_distance inside a closed mesh finds no surface
// (std::nullopt), like a point farther than max_distance outside. The caller chooses the radius
// of interest: the solver passes thickness plus a margin for the deepest penetration it repairs.
// Cost: O(log T + k) per query for k triangles whose boxes come within the radius; a query whose
// point is farther than max_distance from the mesh's bounds costs one 4-box SIMD test. A query
// near the surface visits about 12 wide nodes and 3 point-triangle tests; set_positions refits
// in O(T).
//
// Rigid motion (a keyframed pose) needs no set_positions: query x in the obstacle's rest frame
// (pose.apply_inverse) and rotate the normal back; set_positions is for deforming meshes.
//
// Deforming meshes over a time step (a substep of the cloth solver): move_to(next) moves the
// vertices on straight lines from where they are to `next`; the LBVH's leaf boxes then cover each
// triangle's whole sweep, so that sweep() finds the first time a point moving on a straight line
// meets a moving triangle (continuous collision detection, collision/ccd.hpp): nothing passes
// through the surface between the two placements, however thin the mesh is. surface_distance
// answers for the placement at the step's end (the boxes are looser, the answers the same).
//
// Units: metres (any unit, consistently). Positions are double; the LBVH's float boxes are rounded
// outward from them, so no triangle within the radius is missed.
// Thread safety: const member functions may run concurrently (the solver queries every cloth
// vertex in parallel); set_positions must not run concurrently with anything else.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/cloth/obstacles.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

class MeshObstacle {
public:
    // Takes the mesh (#V positions, #T ≥ 1 counter-clockwise triangles; vertices no triangle uses
    // are allowed). Throws InvalidInput naming the element for an empty mesh, an index outside
    // [0, #V), a triangle repeating a vertex or a non-finite coordinate. O(T log T).
    explicit MeshObstacle(geometry::TriangleMeshD mesh);

    // Moves the vertices (keyframed or deforming obstacles): positions has #V entries (else
    // InvalidInput), all finite (else InvalidInput naming the vertex). Recomputes the normals and
    // pseudo-normals and refits the LBVH (topology kept, no rebuild). O(V + T), parallel, results
    // bitwise independent of the number of threads.
    void set_positions(std::span<const Vec3d> positions);
    // As set_positions, for one time step from the current placement (the step's start) to
    // `positions` (its end): the leaf boxes cover both placements of each triangle (for sweep()),
    // and previous_positions() keeps the start. max_vertex_step() is the longest vertex move.
    void move_to(std::span<const Vec3d> positions);
    // The placement at the last move_to's start (the current one when none ran since
    // construction or set_positions); #V.
    std::span<const Vec3d> previous_positions() const {
        return m_previous_positions.empty() ? std::span<const Vec3d>(m_mesh.positions)
                                            : std::span<const Vec3d>(m_previous_positions);
    }
    // The longest vertex move of the last move_to (m); 0 after construction or set_positions.
    double max_vertex_step() const { return m_max_vertex_step; }

    // surface_distance with the closest feature: the triangle and the barycentric weights (w0,
    // w1, w2 of its corners 0, 1, 2) of the closest point.
    struct SurfacePoint {
        SurfaceDistance surface;
        std::int32_t triangle = -1;
        Vec3d barycentric{};
    };
    std::optional<SurfacePoint> surface_point(const Vec3d& x, double max_distance) const;

    // A point moving on the straight line x_t0 → x_t1 over the last step (move_to's, the
    // triangles moving on straight lines from previous_positions() to the current positions; a
    // static mesh when there was none) that meets the surface from its outside (the side its
    // triangles' normals face): the earliest such meeting (conservative: a meeting is never
    // missed, collision::vertex_face_ccd), the triangle, the barycentric weights of the meeting
    // point and the time of impact in [0, 1]. Meetings from behind a triangle (points leaving a
    // closed mesh, or on the back of an open one) are not reported. Ties go to the lowest
    // triangle. Thread safe; allocates only as the CCD's thread-local search grows.
    struct SweptHit {
        std::int32_t triangle = -1;
        Vec3d barycentric{};
        double toi = 1.0;
    };
    std::optional<SweptHit> sweep(const Vec3d& x_t0, const Vec3d& x_t1) const;

    // An edge (a cloth edge) whose ends move on straight lines from (p_t0, q_t0) to (p_t1, q_t1)
    // over the last step (as sweep's point) that meets one of the surface's edges while entering
    // the surface: at the meeting, the edge's point moves, relative to the surface edge's point,
    // along the two edges' common normal turned to the inside (against the surface edge's
    // pseudo-normal, the sum of its triangles' normals at that time; along the pseudo-normal
    // itself for edges that meet parallel or edge-on). Crossing motion decides it, so cloth that
    // slides across the edge and through it is caught. That is what vertex-face contact misses: a
    // thin part of the surface (a ridge, a finger) passing between the cloth's vertices. The
    // earliest such meeting (conservative, collision::edge_edge_ccd), the surface edge (an index
    // into edges()), the time of impact in [0, 1] and the parameters of the meeting points: s along
    // p → q, t along the surface edge's first → second vertex. Ties go to the lowest edge. Each
    // surface edge is tested once (from its first triangle); the LBVH's swept leaf boxes find the
    // candidates. Thread safe.
    struct EdgeHit {
        std::int32_t edge = -1;
        double toi = 1.0;
        double s = 0.0;
        double t = 0.0;
    };
    std::optional<EdgeHit> sweep_edge(const Vec3d& p_t0, const Vec3d& q_t0, const Vec3d& p_t1,
                                      const Vec3d& q_t1) const;

    // A triangle (a cloth triangle) whose corners move on straight lines from (a_t0, b_t0, c_t0)
    // to (a_t1, b_t1, c_t1) over the last step (as sweep's point) that one of the surface's
    // vertices meets while entering it: at the meeting the vertex moves, relative to the
    // triangle's point there, through the triangle toward the side the vertex's pseudo-normal
    // (the sum of its triangles' unit normals at that time) points to (along the pseudo-normal
    // itself for a triangle that meets it edge-on). Crossing motion decides it, so cloth that
    // slides over a corner and through it is caught. That is what the cloth's vertex-face and
    // edge-edge contact miss: a tip of the surface (a fingertip, the pole of a capsule) pushed into
    // a cloth face between its vertices and edges. The earliest such meeting (conservative,
    // collision::vertex_face_ccd), the surface vertex, the time of impact in [0, 1] and the
    // barycentric weights of the meeting point on the triangle. Ties go to the lowest vertex. The
    // candidates come from an LBVH over the vertices' paths (refit by move_to and set_positions).
    // Thread safe.
    struct VertexHit {
        std::int32_t vertex = -1;
        double toi = 1.0;
        Vec3d barycentric{};
    };
    std::optional<VertexHit> sweep_triangle(const Vec3d& a_t0, const Vec3d& b_t0, const Vec3d& c_t0,
                                            const Vec3d& a_t1, const Vec3d& b_t1,
                                            const Vec3d& c_t1) const;

    // The point of the surface closest to x, if one is within max_distance (≥ 0, may be +inf):
    // its signed distance (|x - closest|, negative inside / behind the surface, see the header) and
    // the unit outward normal there — (x - closest) / distance outside, its opposite inside, and
    // the unit pseudo-normal of the closest feature when x is on the surface (distance 0). Ties
    // between triangles at equal distance go to the lowest triangle index, so the answer does not
    // depend on the traversal. std::nullopt when every triangle is farther than max_distance
    // (also for a NaN max_distance or x). Thread safe; no allocation.
    std::optional<SurfaceDistance> surface_distance(const Vec3d& x, double max_distance) const;

    // Whether the closed triangle (a, b, c) meets the surface where it is now (the closed
    // triangles intersect: geometry::triangles_intersect, exact). False for non-finite corners.
    // Thread safe; no allocation.
    bool meets_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) const;

    const geometry::TriangleMeshD& mesh() const { return m_mesh; }
    // The volume the mesh encloses (m³, by the divergence theorem: Σ a · (b × c) / 6) when it is
    // closed and consistently wound (every edge shared by exactly two triangles that run along it
    // in opposite directions), else none. Negative when it is wound inward: its normals point in,
    // so its inside is everything outside it, and cloth is kept inside it, as in a container.
    std::optional<double> enclosed_volume() const;
    // Whether enclosed_volume() has a value (closed and consistently wound).
    bool is_closed() const { return m_closed; }
    std::size_t num_triangles() const { return m_mesh.triangles.size(); }
    // Box of the surface (double, exact).
    const AABBd& bounds() const { return m_bounds; }
    // Unit face normals (#T; zero for degenerate triangles), edge pseudo-normals (indexed like
    // triangle_edges()), angle-weighted vertex pseudo-normals (#V; zero for unused vertices). The
    // pseudo-normals are sums, not unit vectors: only their direction is used.
    std::span<const Vec3d> face_normals() const { return m_face_normals; }
    std::span<const Vec3d> edge_normals() const { return m_edge_normals; }
    std::span<const Vec3d> vertex_normals() const { return m_vertex_normals; }
    // triangle_edges()[t][k]: the edge between corners k and (k + 1) % 3 of triangle t.
    std::span<const std::array<std::int32_t, 3>> triangle_edges() const { return m_triangle_edges; }
    // The surface's edges (#E, each once, vertex indices ascending), indexed like edge_normals().
    std::span<const geometry::Edge> edges() const { return m_edges; }

private:
    void update_geometry();
    // The triangles' corners per leaf (m_leaf_corners) and the vertices' paths and boxes (the
    // vertex tree refit), for the current and previous placements.
    void gather_leaves();
    // Σ of the unit normals (zero-area ones skipped) of `triangles` at fraction u of the last
    // step, the triangles moving on straight lines from previous_positions() to now.
    Vec3d unit_normal_sum(std::span<const std::int32_t> triangles, double u) const;
    std::optional<SurfacePoint> closest(const Vec3d& x, double max_distance) const;

    geometry::TriangleMeshD m_mesh;
    bool m_closed = false;  // see enclosed_volume()
    // Topology (fixed): edges of each triangle; triangles of each edge and vertex (CSR).
    std::vector<geometry::Edge> m_edges;
    std::vector<std::array<std::int32_t, 3>> m_triangle_edges;
    std::vector<std::int32_t> m_edge_triangle_offsets;
    std::vector<std::int32_t> m_edge_triangles;
    std::vector<std::int32_t> m_vertex_triangle_offsets;
    std::vector<std::int32_t> m_vertex_triangles;
    // Geometry (recomputed by set_positions).
    std::vector<Vec3d> m_face_normals;
    std::vector<std::array<double, 3>> m_corner_angles;  // #T: angle at corners 0, 1, 2 (radians)
    std::vector<Vec3d> m_edge_normals;
    std::vector<Vec3d> m_vertex_normals;
    std::vector<AABB> m_boxes;  // #T float boxes rounded outward, the LBVH's input
    // The corners of the triangle at each leaf position of the LBVH (Morton order): the query
    // reads one contiguous record per leaf instead of chasing triangle and vertex indices.
    std::vector<std::array<Vec3d, 3>> m_leaf_corners;
    // sweep_triangle's LBVH over the vertices' paths over the last step (float boxes rounded
    // outward, refit with the placement) and, per leaf position, each path's two ends.
    std::vector<AABB> m_vertex_boxes;
    bvh::LBVH m_vertex_tree;
    std::vector<std::array<Vec3d, 2>> m_vertex_paths;
    AABBd m_bounds;
    bvh::LBVH m_tree;
    // The last move_to's start (empty: none since construction or set_positions).
    std::vector<Vec3d> m_previous_positions;
    double m_max_vertex_step = 0.0;
};

// The contact projection of push_out(const Obstacle&, …) for a mesh: when x is closer than
// thickness to the surface outside, or inside the surface by at most max_depth, moves x along the
// outward normal to distance `thickness` outside the closest surface point. Returns the
// correction's length (0 when x was not moved) and the normal it moved along (zero when no
// surface point is within max(thickness, max_depth)). thickness ≥ 0, max_depth ≥ 0 (metres).
ContactCorrection push_out(const MeshObstacle& obstacle, Vec3d& x, double thickness,
                           double max_depth);

}  // namespace pliant::cloth
