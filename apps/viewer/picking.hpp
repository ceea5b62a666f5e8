// Picking what lies under the mouse: a ray against triangles (the cloth), a point among
// projected vertices (the volume's tet mesh), and the point a dragged vertex should go to.
//
// Pixel coordinates are continuous image coordinates (render::Camera: origin at the top-left
// corner, y downwards; the centre of pixel (i, j) is (i + 0.5, j + 0.5)). All functions are
// serial, O(T) or O(V), deterministic, and run once per mouse event (a 36k-triangle cloth takes
// well under a millisecond), so no acceleration structure is kept.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::viewer {

struct TriangleHit {
    std::int32_t triangle = -1;  // -1: no hit
    double t = 0.0;              // distance along the ray (unit direction)
    double u = 0.0, v = 0.0;     // barycentric weights of corners 1 and 2 (corner 0: 1 − u − v)
};

// The nearest triangle the ray hits at t ≥ 0, seen from either side (Möller–Trumbore in double;
// degenerate triangles are never hit). Ties keep the lower triangle index.
TriangleHit intersect_triangles(const render::Ray& ray, std::span<const Vec3d> positions,
                                std::span<const geometry::Triangle> triangles);

// The corner of the hit triangle nearest to the hit point (largest barycentric weight; ties to
// the lower corner); -1 without a hit.
std::int32_t nearest_corner(const TriangleHit& hit, std::span<const geometry::Triangle> triangles);

// Among the points in front of the camera that project within radius_pixels of (x, y), the one
// nearest to the camera (smallest depth; ties: the lower index), skipping points on the removed
// side of `clip` (render::ClipPlane keeps (p − point) · normal ≥ 0); -1 when there is none.
std::int32_t pick_point(const render::Camera& camera, std::span<const Vec3f> points, double x,
                        double y, double radius_pixels,
                        const std::optional<render::ClipPlane>& clip = std::nullopt);

// Where a vertex grabbed at `anchor` goes when the mouse is at (x, y): the point of the ray
// through (x, y) on the plane through `anchor` parallel to the image plane (so dragging moves
// the vertex in the view plane at its own depth).
Vec3d drag_target(const render::Camera& camera, double x, double y, const Vec3d& anchor);

}  // namespace pliant::viewer
