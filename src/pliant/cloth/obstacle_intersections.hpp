// Cloth through obstacles: an exact count, on the cloth as it is, of where it passes into an
// obstacle, for the per-frame checks (pipeline/cloth_simulation.hpp) beside the count of the
// cloth's own intersecting pairs.
//
//   const std::int64_t n = count_obstacle_intersections(model);  // 0: the cloth is out of them
//
// What is counted, with the obstacles where the model has them now (their placement at time()):
//   - a triangle-mesh obstacle: the pairs (cloth triangle, obstacle triangle) whose closed point
//     sets intersect (collision::count_intersecting_pairs of two meshes, exact predicates): a
//     cloth edge through the surface, or a surface edge (a thin part: a finger, a ridge) through
//     the cloth, between vertices that are all outside;
//   - an analytic obstacle: the cloth triangles with a point in the closed solid (a plane's
//     closed back half-space, a sphere's closed ball, a box's closed box). Boxes are decided
//     exactly (a vertex inside, or the triangle meets one of the box's 12 surface triangles);
//     planes by the sign of each vertex's offset, spheres by the distance from the centre to the
//     triangle against the radius, both in double.
// The cloth keeps `thickness` from every obstacle, so a cloth in contact counts nothing; touching
// the surface itself counts. The sum over the obstacles is returned. Cloth vertices pinned to an
// obstacle (attached pins) are counted like any other.
//
// Cost: per mesh obstacle an LBVH over each mesh and one pair traversal; per analytic obstacle
// one pass over the cloth's triangles. Reads only positions and placements: no solver state.
// Parallel inside; the count is the same for any number of threads.
#pragma once

#include <cstdint>

#include "pliant/cloth/cloth_model.hpp"

namespace pliant::cloth {

std::int64_t count_obstacle_intersections(const ClothModel& model);

// Whether the closed triangle (a, b, c) has a point in the closed solid of `obstacle`, as
// count_obstacle_intersections decides it.
bool triangle_reaches_into(const Obstacle& obstacle, const Vec3d& a, const Vec3d& b,
                           const Vec3d& c);

// The first of the model's obstacles, where they are now, that the closed triangle (a, b, c)
// meets as count_obstacle_intersections decides it: a mesh obstacle's surface (MeshObstacle::
// meets_triangle, the corners taken into its rest frame), then an analytic obstacle's solid. The
// index among mesh_obstacles(), or mesh_obstacles().size() + the index among obstacles(); -1 when
// it meets none. Thread safe; no allocation.
std::int32_t obstacle_met_by(const ClothModel& model, const Vec3d& a, const Vec3d& b,
                             const Vec3d& c);

// Whether the closed triangle (a, b, c) meets any of the model's obstacles where they are now
// (obstacle_met_by).
bool triangle_meets_obstacles(const ClothModel& model, const Vec3d& a, const Vec3d& b,
                              const Vec3d& c);

}  // namespace pliant::cloth
