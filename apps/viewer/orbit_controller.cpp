#include "orbit_controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::viewer {

OrbitController::OrbitController(const AABBd& box, double azimuth, double elevation,
                                 double distance, int width, int height) {
    if (box.is_empty() || !is_finite(box.lo) || !is_finite(box.hi) || !std::isfinite(azimuth) ||
        !std::isfinite(elevation) || !std::isfinite(distance)) {
        throw InvalidInput(fmt::format(
            "viewer camera: expected a finite, non-empty box and finite angles and distance, got "
            "azimuth {}, elevation {}, distance {}",
            azimuth, elevation, distance));
    }
    m_target = box.center();
    m_azimuth = azimuth;
    m_elevation = std::clamp(elevation, -MAX_ELEVATION, MAX_ELEVATION);
    if (distance > 0.0) {
        m_distance = distance;
    } else {
        const render::Camera framed = render::frame_box(box, azimuth, elevation, width, height);
        m_distance = norm(framed.eye() - framed.target());
    }
    // Zooming in stops at a thousandth of the box (the near plane stays in front of the target).
    m_min_distance = 1e-3 * std::max(norm(box.extent()), 1e-9);
    m_start_target = m_target;
    m_start_azimuth = m_azimuth;
    m_start_elevation = m_elevation;
    m_start_distance = m_distance;
}

void OrbitController::orbit(double dx, double dy) {
    m_azimuth = std::fmod(m_azimuth - DEGREES_PER_PIXEL * dx, 360.0);
    m_elevation = std::clamp(m_elevation + DEGREES_PER_PIXEL * dy, -MAX_ELEVATION, MAX_ELEVATION);
    ++m_generation;
}

void OrbitController::pan(double dx, double dy, int height) {
    const render::Camera cam = camera(std::max(height, 1), std::max(height, 1));
    // World units per pixel at the target's depth.
    const double scale = m_distance / cam.focal_pixels();
    m_target += cam.right() * (-dx * scale) + cam.up() * (dy * scale);
    ++m_generation;
}

void OrbitController::zoom(double notches) {
    m_distance = std::max(m_min_distance, m_distance * std::pow(ZOOM_PER_STEP, notches));
    ++m_generation;
}

void OrbitController::reset() {
    m_target = m_start_target;
    m_azimuth = m_start_azimuth;
    m_elevation = m_start_elevation;
    m_distance = m_start_distance;
    ++m_generation;
}

render::Camera OrbitController::camera(int width, int height) const {
    return render::orbit_camera_at(m_target, m_azimuth, m_elevation, m_distance, width, height);
}

}  // namespace pliant::viewer
