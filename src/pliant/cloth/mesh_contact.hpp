// Contact of one cloth vertex with a moving (rigid or deforming) triangle-mesh obstacle over one
// substep: the swept test that keeps a vertex from passing through the surface between two
// placements, the push out to `thickness` outside the surface, and the bounds that make a jumping
// obstacle push cloth out over several substeps instead of sweeping it through in one. A stepper
// calls it per free vertex after its constraint projection (XPBDStepper::resolve_obstacles); the
// result carries what velocity-level friction needs (the surface's own velocity at the contact).
//
// Per vertex moving from `start` (the substep's start) to x (after the constraints), in the
// mesh's rest frame (state.previous_pose for start, state.pose for x):
//   1. swept: when the segment start → x meets the moving surface from outside
//      (MeshObstacle::sweep: vertex-face CCD against the triangles moving from
//      previous_positions() to positions()), x goes to the meeting point's place on the surface
//      at the substep's end, `thickness` along its triangle's normal;
//   2. push out: within max_depth = |x - start| + the surface's largest move + 2 thickness +
//      extra_depth of the surface, x is pushed to `thickness` outside the closest point
//      (extra_depth: how far behind the surface lagging vertices can be, see 3);
//   3. bounds: the correction c of 1 and 2 is split into `settled`, the part that undoes a
//      penetration the vertex began the substep with (its distance behind `thickness` from the
//      surface at the substep's start, along the contact's normal), and the rest. Of settled at
//      most max_settle is kept; of the rest at most |x - start| + thickness + max_push (a
//      surface that moves more than max_push per substep pushes cloth at that bounded speed and
//      the vertex lags, `lag` m, behind the surface). What is not kept is taken back along c.
// The surface velocity is that of the closest surface point: (pose p_end - previous_pose
// p_start) / h, p the same barycentric point of the contact's triangle at both placements.
//
// Edges (resolve_mesh_edge_contacts): a thin part of the surface (a ridge, a finger, the
// mannequin's arm) can pass between two cloth vertices without either coming near it. After the
// vertex contacts, every cloth edge moving from its substep start to its place now (both ends
// in the rest frame as above) is swept against the moving surface's edges
// (MeshObstacle::sweep_edge: edge-edge CCD, entering meetings only). For a meeting at s along
// the cloth edge (a, b) and t along the surface edge, with n the surface edge's unit
// pseudo-normal at the substep's end and o its point t there, the constraint
//   C = (x_a + s (x_b - x_a) - o) · n - thickness ≥ 0
// is projected as a PBD contact with the ends' inverse masses w: x_a += w_a (1 - s) λ n,
// x_b += w_b s λ n, λ = -C / (w_a (1 - s)² + w_b s²): the cloth edge's point goes `thickness`
// outside the surface edge, the edge lifted over the ridge. Corrections are computed per edge
// in parallel and averaged per vertex (Jacobi) in edge order: the same bits for any number of
// threads. As for vertices (3 above), the point's whole correction in the substep (the vertex
// pass's and the edge pass's, from `before_contact`, the positions before the vertex pass) is at
// most its own motion from the start to before_contact + thickness + max_push.
//
// Faces (resolve_mesh_face_contacts): a tip of the surface (a fingertip, the pole of a capsule)
// can enter a cloth triangle between its vertices and edges, where neither pass looks. After the
// edge pass, every cloth triangle moving as above is swept against the surface's vertices
// (MeshObstacle::sweep_triangle: vertex-face CCD, entering meetings only). For a meeting at the
// triangle's barycentric weights w, with n the surface vertex's unit pseudo-normal at the
// substep's end (angle-weighted, MeshObstacle::vertex_normals) and o the vertex there,
//   C = (Σ_i w_i x_i - o) · n - thickness ≥ 0
// is projected as for edges: x_i += w_i inv_i λ n, λ = -C / Σ_i w_i² inv_i, bounded and averaged
// per vertex in triangle order the same way.
//
// Units: metres, seconds. Thread safe for distinct vertices (const obstacle).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {

struct MeshContact {
    double depth = 0.0;    // length of the correction kept (m); 0: no contact
    double settled = 0.0;  // the part of depth that undid a penetration the substep began with
    Vec3d normal{0.0, 0.0, 1.0};            // unit, outward, world frame
    Vec3d surface_velocity{0.0, 0.0, 0.0};  // m/s, the surface point's
    bool swept = false;                     // step 1 caught the vertex
    double lag = 0.0;                       // correction held back by max_push (m)
};

// thickness ≥ 0, h > 0, max_settle, max_push and extra_depth ≥ 0 (m; max_settle and max_push
// +inf: unbounded).
MeshContact resolve_mesh_contact(const MovingMeshObstacle& obstacle, Vec3d& x, const Vec3d& start,
                                 double thickness, double h, double max_settle, double max_push,
                                 double extra_depth);

// Buffers the edge and face passes reuse from substep to substep.
struct MeshFeatureContactScratch {
    std::vector<std::array<Vec3d, 3>> corrections;  // per cloth edge or triangle, world frame (m)
    std::vector<std::uint8_t> has_correction;       // per cloth edge or triangle
    std::vector<Vec3d> sums;                        // #V
    std::vector<std::int32_t> counts;               // #V
};

// The edge pass of the header: cloth `edges` (#E vertex pairs into positions) moving from
// `start` (#V, the substep's start) to `positions` (#V, moved in place; before_contact: #V, the
// positions before the vertex pass) against `obstacle`;
// inverse_masses (#V; 0: the vertex does not move). Returns the cloth edges corrected.
// thickness, max_push ≥ 0 (m; max_push +inf: unbounded). Parallel; bitwise the same for any number
// of threads.
std::int64_t resolve_mesh_edge_contacts(const MovingMeshObstacle& obstacle,
                                        std::span<Vec3d> positions, std::span<const Vec3d> start,
                                        std::span<const Vec3d> before_contact,
                                        std::span<const double> inverse_masses,
                                        std::span<const geometry::Edge> edges, double thickness,
                                        double max_push, MeshFeatureContactScratch& scratch);

// The face pass of the header: cloth `triangles` (#T vertex triples into positions) moving as in
// the edge pass, against the surface's vertices (MeshObstacle::sweep_triangle); the same
// arguments and result (the cloth triangles corrected).
std::int64_t resolve_mesh_face_contacts(const MovingMeshObstacle& obstacle,
                                        std::span<Vec3d> positions, std::span<const Vec3d> start,
                                        std::span<const Vec3d> before_contact,
                                        std::span<const double> inverse_masses,
                                        std::span<const geometry::Triangle> triangles,
                                        double thickness, double max_push,
                                        MeshFeatureContactScratch& scratch);

}  // namespace pliant::cloth
