// Camera: a pinhole perspective or an orthographic camera over a width × height image, with the
// world → pixel projection and the per-pixel ray generation shared by the mesh rasterizer and the
// volume ray caster.
//
// Conventions
//   - World: right-handed, +z up for scenes (DESIGN.md), world units (metres in scenes).
//   - Camera frame: an orthonormal, right-handed basis (right, up, -forward): forward points from
//     the eye to the target; right = normalize(forward × up_hint); up = right × forward. Camera
//     coordinates of a point p: x = (p − eye)·right, y = (p − eye)·up, depth = (p − eye)·forward
//     (positive in front of the camera).
//   - Pixels: continuous pixel coordinates (x, y) have their origin at the top-left corner of the
//     image, x to the right, y downwards; pixel (i, j) (column i, row j) covers
//     [i, i+1) × [j, j+1) and its centre is (i + 0.5, j + 0.5).
//   - Square pixels. `focal_pixels()` f maps camera coordinates to pixels:
//       perspective:  x = W/2 + f·cx/depth,  y = H/2 − f·cy/depth,  f = (H/2) / tan(fov_y/2)
//       orthographic: x = W/2 + f·cx,        y = H/2 − f·cy,        f = H / view_height
//     so the vertical field of view (or view height) spans the image height exactly and the
//     horizontal extent follows from the aspect W/H.
//   - Near distance: the rasterizer draws only what lies at depth ≥ near() (triangles crossing it
//     are clipped). Default: 1e-3 · |target − eye| (perspective), 0 (orthographic: the eye plane).
//
// Values are immutable after construction except near(); all members are const and thread safe.
#pragma once

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::render {

enum class Projection { perspective, orthographic };

// A ray origin + t·direction, t ≥ 0; direction has unit length.
struct Ray {
    Vec3d origin;
    Vec3d direction;
};

// A projected point: continuous pixel coordinates and the camera depth (see the header comment).
// For the perspective camera x and y are meaningful only when depth > 0.
struct PixelPoint {
    double x = 0.0;
    double y = 0.0;
    double depth = 0.0;
};

class Camera {
public:
    // Throws InvalidInput (naming the argument and its value) for non-finite vectors, eye ==
    // target, up_hint parallel to the view direction (or zero), fov_y_degrees outside (0, 180),
    // and width or height outside [1, 32768].
    static Camera perspective(Vec3d eye, Vec3d target, Vec3d up_hint, double fov_y_degrees,
                              int width, int height);
    // view_height: the world extent the image height covers (> 0, finite). Same other checks.
    static Camera orthographic(Vec3d eye, Vec3d target, Vec3d up_hint, double view_height,
                               int width, int height);

    Projection projection() const { return m_projection; }
    int width() const { return m_width; }
    int height() const { return m_height; }
    Vec3d eye() const { return m_eye; }
    Vec3d target() const { return m_target; }
    Vec3d forward() const { return m_forward; }
    Vec3d right() const { return m_right; }
    Vec3d up() const { return m_up; }
    // Vertical field of view in degrees (perspective; 0 for orthographic).
    double fov_y_degrees() const { return m_fov_y_degrees; }
    // World height covered by the image (orthographic; 0 for perspective).
    double view_height() const { return m_view_height; }
    // Pixels per unit of cx/depth (perspective) or of cx (orthographic).
    double focal_pixels() const { return m_focal_pixels; }
    double near() const { return m_near; }
    // Throws InvalidInput unless near is finite and > 0 (perspective) or finite (orthographic).
    void set_near(double near);

    // (x, y, depth) of p in the camera frame (x right, y up, depth along forward).
    Vec3d camera_from_world(Vec3d p) const;
    // Continuous pixel coordinates and depth of world point p.
    PixelPoint project(Vec3d p) const;
    // The ray through continuous pixel coordinates (x, y): from the eye (perspective) or from the
    // point of the eye plane (orthographic) that projects to (x, y). project() of any point of the
    // ray with depth > 0 gives back (x, y).
    Ray ray(double x, double y) const;
    // The ray through the centre (i + 0.5, j + 0.5) of pixel (i, j).
    Ray pixel_ray(int i, int j) const { return ray(i + 0.5, j + 0.5); }

private:
    Camera() = default;
    void init(Vec3d eye, Vec3d target, Vec3d up_hint, int width, int height, const char* who);

    Projection m_projection = Projection::perspective;
    int m_width = 0;
    int m_height = 0;
    Vec3d m_eye, m_target, m_forward, m_right, m_up;
    double m_fov_y_degrees = 0.0;
    double m_view_height = 0.0;
    double m_focal_pixels = 1.0;
    double m_near = 0.0;
};

struct FramingOptions {
    Projection projection = Projection::perspective;
    double fov_y_degrees = 30.0;  // perspective only, in (0, 180)
    double margin = 1.1;          // ≥ 1: the box's bounding sphere grown by this factor must fit
};

// A camera looking at the centre of `box` from direction (azimuth, elevation), in degrees:
// azimuth is measured in the xy-plane from +x towards +y, elevation from the xy-plane towards +z
// (so the eye sits at centre + D·(cos el·cos az, cos el·sin az, sin el)); up hint +z (at
// elevation ±90 the image's up is the horizontal direction away from the azimuth, so the view
// turns continuously). D is chosen so that the box's bounding sphere, grown by `margin`, fits in
// both the vertical and horizontal field of view, hence every point of the box projects inside
// the image and lies in front of the near distance. A box of zero size is framed as a sphere of
// radius 1e-6·max(1, |centre|). Throws InvalidInput for an empty or non-finite box, non-finite
// angles, margin < 1, and the Camera constructors' conditions.
Camera frame_box(const AABBd& box, double azimuth_degrees, double elevation_degrees, int width,
                 int height, const FramingOptions& options = {});

// The orbit camera of the CLI and the viewer: a perspective camera at azimuth, elevation (degrees,
// frame_box's convention) and `distance` world units from `target`, looking at it:
// eye = target + distance · (cos el cos az, cos el sin az, sin el), vertical field of view
// ORBIT_FOV_DEGREES, up hint +z (at elevation ±90° the horizontal direction away from the
// azimuth). distance > 0.
inline constexpr double ORBIT_FOV_DEGREES = 30.0;
Camera orbit_camera_at(const Vec3d& target, double azimuth, double elevation, double distance,
                       int width, int height);

// The same around the box's centre; distance ≤ 0 frames the box (frame_box).
Camera orbit_camera(const AABBd& box, double azimuth, double elevation, double distance, int width,
                    int height);

}  // namespace pliant::render
