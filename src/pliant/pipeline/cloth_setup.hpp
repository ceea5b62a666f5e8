// A cloth scene made ready to simulate: the cloth mesh (generated or read, placed, instanced),
// its pin groups resolved to vertex indices, the obstacles (mesh obstacles read and placed once)
// and the shapes that draw them. Shared by `pliant cloth` (cloth_run.hpp, cloth_preview.hpp) and
// the viewer (`pliant view cloth`), so that both simulate exactly the same thing.
//
//   const ClothSetup setup = load_cloth_setup(scene, "scenes/drape.json");
//   std::unique_ptr<cloth::ClothSolver> solver = make_solver(scene, setup);   // again to reset
//
// load_cloth_setup reads the files the scene names (cloth and obstacle meshes) and throws
// InvalidInput / IoError for a scene that cannot be built (scene_name prefixes the messages).
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pliant/cloth/mesh_animation.hpp"
#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/scene.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/cloth/untangle.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/obj_polygons.hpp"

namespace pliant::pipeline {

// An obstacle as drawn: its triangles at the rest placement and its motion (and, for a deforming
// mesh, its animation: rest holds frame 0).
struct ObstacleShape {
    geometry::TriangleMeshD rest;
    cloth::Motion motion;
    std::shared_ptr<const cloth::MeshAnimation> animation;
    bool smooth = true;   // false for boxes, planes and meshes (flat shading)
    bool bounded = true;  // false for planes: left out of the camera's framing
};

// A cloth whose box diagonal lies outside [MIN, MAX] metres gets a warning (units or scale
// wrong), and so does a thickness outside [MIN, MAX] times the mean edge length.
inline constexpr double MIN_PLAUSIBLE_CLOTH_SIZE = 0.01;
inline constexpr double MAX_PLAUSIBLE_CLOTH_SIZE = 10.0;
inline constexpr double MIN_THICKNESS_PER_EDGE = 0.01;
inline constexpr double MAX_THICKNESS_PER_EDGE = 0.5;

struct ClothSetup {
    geometry::TriangleMeshD mesh;  // the cloth at the start, all instances
    // A cloth read from an OBJ or PLY file as its polygons (io/obj_polygons.hpp,
    // io/ply_polygons.hpp), all instances, its vertices those of `mesh`: frames are written with
    // its faces, UVs, groups, materials and PLY properties.
    std::optional<io::PolygonMesh> garment;
    // The scene's material with its physical stiffnesses (scene.stretch_stiffness,
    // scene.bend_stiffness) turned into compliances for this mesh.
    cloth::ClothMaterial material;
    std::vector<std::vector<std::int32_t>> pins;  // per scene pin group, its vertices
    // Per scene obstacle: the mesh obstacle (null for analytic shapes), shared between solvers.
    std::vector<std::shared_ptr<const cloth::MeshObstacle>> mesh_obstacles;
    // Per scene obstacle: the animation of a deforming mesh (its "frames"), else null.
    std::vector<std::shared_ptr<const cloth::MeshAnimation>> animations;
    std::vector<ObstacleShape> shapes;  // per scene obstacle
};

// max_memory_bytes: a cloth whose triangles need more memory (memory_budget.hpp) is refused
// before it is generated; 0: the memory available (available_memory_bytes()).
ClothSetup load_cloth_setup(const cloth::ClothScene& scene, const std::string& scene_name,
                            std::uint64_t max_memory_bytes = 0);

// A solver at the scene's start: material, pins with their motion, obstacles, gravity, air and
// self-collision as the scene says. Pin groups attached to an obstacle are added after the
// obstacles (a vertex in a moving and an attached group follows the attached one).
std::unique_ptr<cloth::ClothSolver> make_solver(const cloth::ClothScene& scene,
                                                const ClothSetup& setup);

// What the start of a run did to cloth that intersects itself.
struct StartState {
    std::int64_t initial_intersections = 0;          // exact count before untangling
    std::optional<cloth::UntangleResult> untangled;  // when the scene asked for it and needed it
};

// Input cloth with more intersecting pairs than this per triangle (on average) is refused.
inline constexpr std::int64_t MAX_INITIAL_PAIRS_PER_TRIANGLE = 4;

// Makes a new solver's state the start `pliant cloth` simulates: counts its intersecting pairs
// (exactly), throws InvalidInput when there are more than MAX_INITIAL_PAIRS_PER_TRIANGLE per
// triangle (layers on or through each other: untangling cannot separate them and simulating
// them costs minutes and gigabytes per frame), and untangles the cloth when there are any and
// the scene says "untangle" (the default). It logs what it finds (log.hpp), for `pliant cloth`
// and the viewer alike: vertices inside obstacles, intersections at the start, and what
// untangling did. scene_name prefixes the messages.
StartState prepare_start(const cloth::ClothScene& scene, const std::string& scene_name,
                         cloth::ClothSolver& solver);

// The untangling report of stats.json and `view cloth --json` (docs/formats.md): null when
// nothing was untangled, else iterations, region_moves, pairs_left, max_displacement_m, ms.
nlohmann::ordered_json untangle_report(const StartState& start);

// The box a camera frames: the cloth's points and the bounded obstacles' rest shapes (plane
// squares are as large as the scene, so they are left out).
AABBd framing_box(std::span<const Vec3d> cloth, const std::vector<ObstacleShape>& obstacles);

// The files of a deforming mesh obstacle's frames: its list, or its pattern expanded (from
// frame_start, or 0, or 1 when there is no file 0; frame_count files, or as many consecutive ones
// as exist). InvalidInput naming `key` for a pattern without exactly one integer conversion
// (%d or %0Nd), a pattern that matches no file, a missing frame of a given count.
std::vector<std::filesystem::path> obstacle_frame_files(const cloth::SceneObstacle& obstacle,
                                                        const std::string& scene_name,
                                                        const std::string& key);

// The shape of one obstacle as drawn: a UV sphere, a box, a plane's square (half size
// `plane_half_size`, centred at the point of the plane closest to `centre`), or the mesh as given
// (already placed by its mesh placement).
ObstacleShape obstacle_shape(const cloth::SceneObstacle& obstacle,
                             const geometry::TriangleMeshD* mesh, const Vec3d& centre,
                             double plane_half_size);

}  // namespace pliant::pipeline
