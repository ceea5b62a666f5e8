// The viewer's camera controller: orbit (azimuth, elevation) around a target point, pan (moves
// the target in the view plane), zoom (distance), turned into the library's render::Camera so
// that the OpenGL drawing, the ray caster and the offline renderers (`pliant render --camera`,
// the cloth preview) all see through the same camera.
//
// Angles in degrees (render::frame_box's convention: azimuth in the xy-plane from +x towards +y,
// elevation towards +z), distances in world units. The camera is orbit_camera_at (a 30° vertical
// field of view, up hint +z): at the start it is exactly `pliant render --camera AZ,EL,DIST`
// for the same box, and with DIST ≤ 0 it frames the box as render::frame_box does.
// Mouse motion is in pixels. Not thread safe; cheap (no allocation).
#pragma once

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::viewer {

class OrbitController {
public:
    static constexpr double DEGREES_PER_PIXEL = 0.3;
    static constexpr double ZOOM_PER_STEP = 0.9;   // distance factor per wheel notch
    static constexpr double MAX_ELEVATION = 89.0;  // degrees, away from the poles

    // Looks at the box's centre from (azimuth, elevation) at `distance`; distance ≤ 0: the
    // distance at which render::frame_box frames the box in a width × height image.
    // InvalidInput for an empty or non-finite box or non-finite angles.
    OrbitController(const AABBd& box, double azimuth, double elevation, double distance, int width,
                    int height);

    // Mouse drags: orbit turns the view (right: the scene turns left to right, up: the eye goes
    // down), pan moves the target so that the point under the cursor at the target's depth
    // follows it in an image `height` pixels high; zoom by wheel notches (positive: closer).
    void orbit(double dx, double dy);
    void pan(double dx, double dy, int height);
    void zoom(double notches);
    // Back to the starting view.
    void reset();

    render::Camera camera(int width, int height) const;

    double azimuth() const { return m_azimuth; }
    double elevation() const { return m_elevation; }
    double distance() const { return m_distance; }
    const Vec3d& target() const { return m_target; }
    // Changes whenever the view does (for caching rendered images).
    unsigned long long generation() const { return m_generation; }

private:
    Vec3d m_target;
    double m_azimuth, m_elevation, m_distance;
    Vec3d m_start_target;
    double m_start_azimuth, m_start_elevation, m_start_distance;
    double m_min_distance;
    unsigned long long m_generation = 0;
};

}  // namespace pliant::viewer
