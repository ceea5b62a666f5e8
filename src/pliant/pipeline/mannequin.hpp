// The walking mannequin of scripts/make-body, built in the library so that the garment demo
// needs no Python: one closed, outward-wound (counter-clockwise seen from outside) triangle mesh
// per phase of a walk cycle, the same vertices and triangles at every phase, in metres, +z up,
// feet at z = 0, facing -y. Parts: a torso (an elliptic capsule, half-axes 0.17 m across, along
// x, and 0.1054 m deep, along y, from the hips at z = 0.95 m to the shoulders at 1.45 m), a head,
// two legs and two arms (capsules). At phase p ∈ [0, 1) the legs swing ±swing_degrees · sin 2πp
// about the hip joints in opposite phase, the arms swing against the legs (0.8 of it), the hips
// turn turn_degrees · sin 2πp about z, the chest half as much the other way, and the torso twists
// smoothly between them (a deformation, not a rigid motion). Phase 0 stands straight. The parts
// overlap where they join: a point is inside the body when it is inside any part (generalized
// winding number ≥ 1).
//
// scripts/make-body writes the same frames (its defaults: 12 segments, turn 30°, swing 25°) as
// an OBJ sequence; tests/pipeline/garment_scene_test.cpp checks that the two agree.
#pragma once

#include <string>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::pipeline {

struct MannequinOptions {
    int segments = 12;            // around each part (≥ 3)
    double turn_degrees = 30.0;   // hip turn amplitude
    double swing_degrees = 25.0;  // leg swing amplitude
};

// The mannequin at `phase` (any real; the cycle repeats every 1). InvalidInput for segments < 3
// or non-finite values. With 12 segments: 852 vertices, 1,680 triangles.
geometry::TriangleMeshD mannequin_at(double phase, const MannequinOptions& options = {});

// `mesh` as OBJ text (v lines with 6 decimals, f lines; 1-based), after a `# comment` line.
std::string mesh_obj(const geometry::TriangleMeshD& mesh, const std::string& comment);

}  // namespace pliant::pipeline
