#include "pliant/render/camera.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"

namespace pliant::render {

namespace {

constexpr int MAX_SIZE = 32768;

double radians(double degrees) {
    return degrees * std::numbers::pi / 180.0;
}

void check_finite(Vec3d v, const char* who, const char* name) {
    if (!is_finite(v)) {
        throw InvalidInput(
            fmt::format("{}: {} ({}, {}, {}) must be finite", who, name, v.x, v.y, v.z));
    }
}

}  // namespace

void Camera::init(Vec3d eye, Vec3d target, Vec3d up_hint, int width, int height, const char* who) {
    check_finite(eye, who, "eye");
    check_finite(target, who, "target");
    check_finite(up_hint, who, "up");
    if (width < 1 || width > MAX_SIZE || height < 1 || height > MAX_SIZE) {
        throw InvalidInput(
            fmt::format("{}: image size {} x {}, expected width and height in "
                        "[1, {}]",
                        who, width, height, MAX_SIZE));
    }
    const Vec3d view = target - eye;
    const double distance = norm(view);
    if (!(distance > 0.0)) {
        throw InvalidInput(
            fmt::format("{}: eye and target coincide at ({}, {}, {}); expected "
                        "distinct points",
                        who, eye.x, eye.y, eye.z));
    }
    const Vec3d forward = view / distance;
    const Vec3d side = cross(forward, up_hint);
    const double side_norm = norm(side);
    // |forward × up| = sin of the angle between them (times |up|): reject near-parallel hints,
    // whose right vector would be dominated by rounding.
    if (!(side_norm > 1e-9 * norm(up_hint))) {
        throw InvalidInput(
            fmt::format("{}: up ({}, {}, {}) is zero or parallel to the view "
                        "direction ({}, {}, {}); expected a transverse up vector",
                        who, up_hint.x, up_hint.y, up_hint.z, forward.x, forward.y, forward.z));
    }
    m_eye = eye;
    m_target = target;
    m_forward = forward;
    m_right = side / side_norm;
    m_up = cross(m_right, m_forward);
    m_width = width;
    m_height = height;
}

Camera Camera::perspective(Vec3d eye, Vec3d target, Vec3d up_hint, double fov_y_degrees, int width,
                           int height) {
    Camera c;
    c.init(eye, target, up_hint, width, height, "Camera::perspective");
    if (!(fov_y_degrees > 0.0 && fov_y_degrees < 180.0)) {
        throw InvalidInput(fmt::format(
            "Camera::perspective: fov_y_degrees {}, expected a value in (0, 180)", fov_y_degrees));
    }
    c.m_projection = Projection::perspective;
    c.m_fov_y_degrees = fov_y_degrees;
    c.m_focal_pixels = 0.5 * height / std::tan(0.5 * radians(fov_y_degrees));
    c.m_near = 1e-3 * norm(target - eye);
    return c;
}

Camera Camera::orthographic(Vec3d eye, Vec3d target, Vec3d up_hint, double view_height, int width,
                            int height) {
    Camera c;
    c.init(eye, target, up_hint, width, height, "Camera::orthographic");
    if (!(view_height > 0.0) || !std::isfinite(view_height)) {
        throw InvalidInput(fmt::format(
            "Camera::orthographic: view_height {}, expected a finite value > 0", view_height));
    }
    c.m_projection = Projection::orthographic;
    c.m_view_height = view_height;
    c.m_focal_pixels = height / view_height;
    c.m_near = 0.0;
    return c;
}

void Camera::set_near(double near) {
    const bool ok = m_projection == Projection::perspective ? near > 0.0 && std::isfinite(near)
                                                            : std::isfinite(near);
    if (!ok) {
        throw InvalidInput(fmt::format("Camera::set_near: near {}, expected a finite value{}", near,
                                       m_projection == Projection::perspective ? " > 0" : ""));
    }
    m_near = near;
}

Vec3d Camera::camera_from_world(Vec3d p) const {
    const Vec3d d = p - m_eye;
    return {dot(d, m_right), dot(d, m_up), dot(d, m_forward)};
}

PixelPoint Camera::project(Vec3d p) const {
    const Vec3d c = camera_from_world(p);
    const double scale =
        m_projection == Projection::perspective ? m_focal_pixels / c.z : m_focal_pixels;
    return {0.5 * m_width + scale * c.x, 0.5 * m_height - scale * c.y, c.z};
}

Ray Camera::ray(double x, double y) const {
    // Camera-frame offsets at depth 1 (perspective) or on the eye plane (orthographic).
    const double cx = (x - 0.5 * m_width) / m_focal_pixels;
    const double cy = (0.5 * m_height - y) / m_focal_pixels;
    if (m_projection == Projection::perspective) {
        const Vec3d d = m_forward + cx * m_right + cy * m_up;
        return {m_eye, d / norm(d)};
    }
    return {m_eye + cx * m_right + cy * m_up, m_forward};
}

Camera frame_box(const AABBd& box, double azimuth_degrees, double elevation_degrees, int width,
                 int height, const FramingOptions& options) {
    if (box.is_empty() || !is_finite(box.lo) || !is_finite(box.hi)) {
        throw InvalidInput(
            fmt::format("frame_box: box [({}, {}, {}), ({}, {}, {})] must be "
                        "finite and non-empty",
                        box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z));
    }
    if (!std::isfinite(azimuth_degrees) || !std::isfinite(elevation_degrees)) {
        throw InvalidInput(fmt::format("frame_box: azimuth {} and elevation {} must be finite",
                                       azimuth_degrees, elevation_degrees));
    }
    if (!(options.margin >= 1.0) || !std::isfinite(options.margin)) {
        throw InvalidInput(
            fmt::format("frame_box: margin {}, expected a finite value >= 1", options.margin));
    }
    if (width < 1 || height < 1) {
        throw InvalidInput(fmt::format(
            "frame_box: image size {} x {}, expected width and height >= 1", width, height));
    }
    const Vec3d centre = box.center();
    const double radius = std::max(0.5 * norm(box.extent()), 1e-6 * std::max(1.0, norm(centre)));
    const double az = radians(azimuth_degrees);
    const double el = radians(elevation_degrees);
    const Vec3d direction{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
    // +z, unless the view is (nearly) vertical: then the limit of the image's up as the elevation
    // approaches ±90°, −sign(el)·(cos az, sin az, 0).
    Vec3d up_hint{0.0, 0.0, 1.0};
    if (std::abs(std::cos(el)) < 1e-6) {
        const double s = elevation_degrees > 0.0 ? -1.0 : 1.0;
        up_hint = {s * std::cos(az), s * std::sin(az), 0.0};
    }
    const double r = options.margin * radius;
    const double aspect = static_cast<double>(width) / static_cast<double>(height);
    if (options.projection == Projection::orthographic) {
        // The sphere of radius r fits when the view is 2r high and 2r wide.
        const double view_height = 2.0 * r / std::min(1.0, aspect);
        // Eye plane outside the sphere, so all of the box is at depth > 0.
        return Camera::orthographic(centre + 2.0 * r * direction, centre, up_hint, view_height,
                                    width, height);
    }
    if (!(options.fov_y_degrees > 0.0 && options.fov_y_degrees < 180.0)) {
        throw InvalidInput(fmt::format("frame_box: fov_y_degrees {}, expected a value in (0, 180)",
                                       options.fov_y_degrees));
    }
    // A sphere of radius r at distance D subtends the half angle asin(r/D); it fits in the cone
    // of the smaller half field of view θ when r/D ≤ sin θ.
    const double half_y = 0.5 * radians(options.fov_y_degrees);
    const double half_x = std::atan(std::tan(half_y) * aspect);
    const double distance = r / std::sin(std::min(half_x, half_y));
    Camera camera = Camera::perspective(centre + distance * direction, centre, up_hint,
                                        options.fov_y_degrees, width, height);
    // The nearest box point lies at depth ≥ distance − r > 0; keep the near plane well before it.
    camera.set_near(std::min(camera.near(), 0.5 * (distance - r)));
    return camera;
}

Camera orbit_camera(const AABBd& box, double azimuth, double elevation, double distance, int width,
                    int height) {
    if (distance <= 0.0) {
        return frame_box(box, azimuth, elevation, width, height);
    }
    return orbit_camera_at(box.center(), azimuth, elevation, distance, width, height);
}

Camera orbit_camera_at(const Vec3d& target, double azimuth, double elevation, double distance,
                       int width, int height) {
    const double az = azimuth * std::numbers::pi / 180.0;
    const double el = elevation * std::numbers::pi / 180.0;
    const Vec3d dir{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
    const Vec3d up = std::fabs(std::sin(el)) > 0.999
                         ? Vec3d{-std::cos(az) * std::sin(el), -std::sin(az) * std::sin(el), 0.0}
                         : Vec3d{0.0, 0.0, 1.0};
    return Camera::perspective(target + distance * dir, target, up, ORBIT_FOV_DEGREES, width,
                               height);
}

}  // namespace pliant::render
