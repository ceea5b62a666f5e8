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
// Units: metres, seconds. Thread safe for distinct vertices (const obstacle).
#pragma once

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/core/vec3.hpp"

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

}  // namespace pliant::cloth
