// ClothScene: everything `pliant cloth` simulates, as plain data: the cloth (a generated grid or
// a mesh file) and its placement, pins, material, obstacles, gravity, timing and output format.
// Read from JSON by pipeline::read_cloth_scene (format and defaults in docs/formats.md); built into
// a ClothSolver by the caller.
//
// Units: SI; angles in degrees; +z up.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pliant/cloth/air.hpp"
#include "pliant/cloth/material.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/obstacles.hpp"
#include "pliant/cloth/vbd_stepper.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

// A flat sheet of quads_x × quads_y quads, size_x × size_y metres, centred at the origin in the
// z = 0 plane (geometry::make_grid_sheet), before the scene's transform.
struct GridSheet {
    std::array<double, 2> size{2.0, 2.0};
    std::array<int, 2> quads{134, 134};
};

// An axis-aligned box of space; pins every vertex inside it (closed), after the transform.
struct PinRegion {
    Vec3d min;
    Vec3d max;
};

// Pins bound to a mesh obstacle's surface (ClothModel::add_attached_pins): the obstacle by its
// "name" or its index in "obstacles", and how far from its surface a vertex may be (m).
struct PinAttach {
    std::string obstacle;  // name; empty: by index
    std::int64_t obstacle_index = -1;
    double max_distance = 0.05;
};

// Pinned vertices that move together (motion.hpp; no keyframes: they stay put), or that follow a
// mesh obstacle's surface (attach).
struct PinGroup {
    std::string key = "pins";            // where it was in the scene file, for messages
    std::vector<std::int32_t> vertices;  // indices into the cloth (all copies: see instances)
    std::vector<PinRegion> regions;
    Motion motion;
    std::optional<PinAttach> attach;
};

// Panels sewn together (seams.hpp): a[k] to b[k], vertex indices into the cloth (all copies, as
// pins), pulled together over `seconds` from the start, then held.
struct SceneSeam {
    std::string key = "seams[0]";  // where it was in the scene file, for messages
    std::vector<std::int32_t> a;
    std::vector<std::int32_t> b;
    double seconds = 1.0;
};

// A placement: rotate about x, then y, then z (degrees, right-handed), then translate (metres).
struct Placement {
    Vec3d rotate_degrees{0.0, 0.0, 0.0};
    Vec3d translate{0.0, 0.0, 0.0};
};

// An obstacle: an analytic shape, or a triangle mesh file (OBJ/PLY; relative paths are relative
// to the scene file) placed by mesh_placement; either moved by motion.
struct SceneObstacle {
    std::string name;  // optional; pins attach to it by name
    Obstacle shape;
    std::filesystem::path mesh;  // when not empty, the obstacle is this mesh and shape is unused
    Placement mesh_placement;
    Motion motion;
    // A deforming mesh (mesh_animation.hpp): its frames as files of one topology, either listed
    // or a printf pattern with one integer conversion ("body/frame_%04d.obj", relative to the
    // scene file) numbered from frame_start (-1: 0, or 1 when there is no frame 0) for
    // frame_count files (0: as many consecutive files as exist). mesh is then the first frame.
    std::vector<std::filesystem::path> frames;
    std::filesystem::path frames_pattern;
    int frame_start = -1;
    int frame_count = 0;
    double frames_fps = 0.0;  // frames per second; 0: the scene's fps
    bool loop = false;
};

struct ClothScene {
    // The cloth: a grid, or a mesh file (OBJ/PLY; relative paths are relative to the scene file).
    std::optional<GridSheet> grid;
    std::filesystem::path mesh;
    // Metres per unit of the mesh file's coordinates ("units": "m" 1, "cm" 0.01, "mm" 0.001, or
    // "scale"), applied to the file's positions before the transform below (which is in metres).
    double mesh_scale = 1.0;
    // Applied to the cloth's vertices in this order: rotate about x, then y, then z (degrees,
    // right-handed), then translate (metres).
    Vec3d rotate_degrees{0.0, 0.0, 0.0};
    Vec3d translate{0.0, 0.0, 0.0};
    // Copies of the cloth, each placed by its own placement after the transform above; empty: one
    // copy as is. Copy k's vertex v has index k · #V + v (pins refer to these indices); copies
    // are one mesh, so they collide with each other through self-collision.
    std::vector<Placement> instances;

    std::vector<PinGroup> pins;
    std::vector<SceneSeam> seams;

    ClothMaterial material;
    // The fabric in physical units (material_preset.hpp), when the scene gives it: a preset's name
    // ("" for none) and the tensile stiffness (N/m) and bending rigidity (N·m) that replace
    // material's stretch and bend compliances once the mesh is known (pipeline::load_cloth_setup).
    std::string material_preset;
    std::optional<double> stretch_stiffness;
    std::optional<double> bend_stiffness;
    bool self_collision = true;  // cloth/self_collision.hpp
    // The time stepper: XPBD (xpbd_stepper.hpp) when empty, else Vertex Block Descent with these
    // options (vbd_stepper.hpp).
    std::optional<VBDOptions> vbd;
    // XPBD's self-contact by Offset Geometric Contact (ogc_contact.hpp, XPBDStepper::set_ogc)
    // when set; with VBD the options are vbd->ogc.
    std::optional<OgcOptions> xpbd_ogc;
    // Cloth that starts intersecting itself is untangled before the first frame (untangle.hpp).
    bool untangle = true;
    std::vector<SceneObstacle> obstacles;
    Vec3d gravity{0.0, 0.0, -9.81};
    Air air;  // air.hpp; off by default

    double frames_per_second = 24.0;
    int frames = 72;
    // Per frame. 40 at 24 fps (h ≈ 1 ms) keeps a cloth falling at 4 m/s moving less than its
    // 5 mm thickness per substep; the drape's edge strain p99 stays at most 34 % at the impact
    // and 16 % once draped (docs/formats.md, "substeps").
    int substeps = 40;

    std::string frame_format = "obj";  // "obj" or "ply"
    // "pc2" or "mdd": also DIR/cloth.pc2 or DIR/cloth.mdd, every frame in one point cache
    // (io/pc2.hpp, io/mdd.hpp); "": none.
    std::string point_cache;
};

}  // namespace pliant::cloth
