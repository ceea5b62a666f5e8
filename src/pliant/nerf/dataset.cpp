#include "pliant/nerf/dataset.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "pliant/core/error.hpp"

namespace pliant::nerf {

double Pose::determinant() const {
    const Vec3d a = axis(0), b = axis(1), c = axis(2);
    return dot(a, cross(b, c));
}

render::Ray view_ray(const Intrinsics& intrinsics, const Pose& pose, double x, double y) {
    const double u = (x - intrinsics.cx) / intrinsics.fx;
    const double v = -(y - intrinsics.cy) / intrinsics.fy;
    const Vec3d d = u * pose.axis(0) + v * pose.axis(1) - pose.axis(2);
    return {pose.eye(), d / norm(d)};
}

Pose pose_from_camera(const render::Camera& camera) {
    if (camera.projection() != render::Projection::perspective) {
        throw InvalidInput(
            "nerf::pose_from_camera: the camera is orthographic, expected perspective");
    }
    const Vec3d x = camera.right(), y = camera.up(), z = -camera.forward(), t = camera.eye();
    return Pose{{x.x, y.x, z.x, t.x, x.y, y.y, z.y, t.y, x.z, y.z, z.z, t.z}};
}

Intrinsics intrinsics_from_camera(const render::Camera& camera) {
    if (camera.projection() != render::Projection::perspective) {
        throw InvalidInput(
            "nerf::intrinsics_from_camera: the camera is orthographic, expected perspective");
    }
    Intrinsics in;
    in.width = camera.width();
    in.height = camera.height();
    in.fx = camera.focal_pixels();
    in.fy = camera.focal_pixels();
    in.cx = 0.5 * camera.width();
    in.cy = 0.5 * camera.height();
    return in;
}

render::Camera camera_from_view(const Intrinsics& in, const Pose& pose) {
    if (std::fabs(in.fx - in.fy) > 1e-6 * in.fx || std::fabs(in.cx - 0.5 * in.width) > 1e-3 ||
        std::fabs(in.cy - 0.5 * in.height) > 1e-3) {
        throw Unsupported(fmt::format(
            "nerf::camera_from_view: the ray caster's camera needs square pixels and a centred "
            "principal point; got fl_x {} fl_y {} cx {} cy {} for {} x {} pixels",
            in.fx, in.fy, in.cx, in.cy, in.width, in.height));
    }
    const Vec3d x = pose.axis(0), y = pose.axis(1), z = pose.axis(2);
    const double worst =
        std::max({std::fabs(norm(x) - 1.0), std::fabs(norm(y) - 1.0), std::fabs(norm(z) - 1.0),
                  std::fabs(dot(x, y)), std::fabs(dot(y, z)), std::fabs(dot(x, z))});
    if (worst > 1e-4) {
        throw Unsupported(fmt::format(
            "nerf::camera_from_view: the pose's rotation is not orthonormal (deviation {}); the "
            "ray caster's camera has no scale or shear",
            worst));
    }
    const double fov_y = 2.0 * std::atan(0.5 * in.height / in.fy) * 180.0 / std::numbers::pi;
    const Vec3d eye = pose.eye();
    return render::Camera::perspective(eye, eye - z, y, fov_y, in.width, in.height);
}

AABBd scene_box(const Dataset& dataset) {
    if (dataset.box) {
        return *dataset.box;
    }
    if (dataset.views.empty()) {
        throw InvalidInput("nerf::scene_box: the dataset has no views");
    }
    // Least-squares point nearest to the optical axes: Σ (I − d dᵀ) p = Σ (I − d dᵀ) o.
    double a[3][3] = {};
    double b[3] = {};
    for (const View& v : dataset.views) {
        const Vec3d d = -v.camera_to_world.axis(2) / norm(v.camera_to_world.axis(2));
        const Vec3d o = v.camera_to_world.eye();
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                const double m = (r == c ? 1.0 : 0.0) - d[r] * d[c];
                a[r][c] += m;
                b[r] += m * o[c];
            }
        }
    }
    // Cramer's rule on the 3 × 3 system.
    const auto det3 = [](const double m[3][3]) {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double det = det3(a);
    const double n = static_cast<double>(dataset.views.size());
    if (!(std::fabs(det) > 1e-9 * n * n * n)) {
        throw InvalidInput(
            "nerf::scene_box: the optical axes of the views are (nearly) parallel: no point "
            "nearest to all of them; give the dataset an `aabb`");
    }
    Vec3d centre;
    for (int k = 0; k < 3; ++k) {
        double m[3][3];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                m[r][c] = c == k ? b[r] : a[r][c];
            }
        }
        centre[k] = det3(m) / det;
    }
    const Intrinsics& in = dataset.intrinsics;
    const double tan_half =
        std::min(0.5 * in.width / in.fx, 0.5 * in.height / in.fy);  // tan of the half angle
    double radius = std::numeric_limits<double>::infinity();
    for (const View& v : dataset.views) {
        radius = std::min(radius,
                          norm(v.camera_to_world.eye() - centre) * std::sin(std::atan(tan_half)));
    }
    const double half = radius / std::sqrt(3.0);
    if (!(half > 0.0) || !std::isfinite(half)) {
        throw InvalidInput(fmt::format(
            "nerf::scene_box: cannot derive a box from the cameras (half side {}); give the "
            "dataset an `aabb`",
            half));
    }
    return {centre - Vec3d{half, half, half}, centre + Vec3d{half, half, half}};
}

void validate(const Dataset& dataset) {
    const Intrinsics& in = dataset.intrinsics;
    if (in.width < 1 || in.height < 1 || !(in.fx > 0.0) || !(in.fy > 0.0) ||
        !std::isfinite(in.fx) || !std::isfinite(in.fy) || !std::isfinite(in.cx) ||
        !std::isfinite(in.cy)) {
        throw InvalidInput(fmt::format(
            "nerf dataset: intrinsics {} x {} fl_x {} fl_y {} cx {} cy {}: expected positive "
            "sizes and focal lengths, finite principal point",
            in.width, in.height, in.fx, in.fy, in.cx, in.cy));
    }
    if (dataset.views.empty()) {
        throw InvalidInput("nerf dataset: no views");
    }
    const std::size_t pixels = 3 * static_cast<std::size_t>(in.width) * in.height;
    for (std::size_t i = 0; i < dataset.views.size(); ++i) {
        const View& v = dataset.views[i];
        for (double x : v.camera_to_world.m) {
            if (!std::isfinite(x)) {
                throw InvalidInput(fmt::format(
                    "nerf dataset: view {} ('{}'): transform_matrix has a non-finite entry", i,
                    v.name));
            }
        }
        const double scale =
            std::max({norm(v.camera_to_world.axis(0)), norm(v.camera_to_world.axis(1)),
                      norm(v.camera_to_world.axis(2))});
        const double det = v.camera_to_world.determinant();
        if (!(std::fabs(det) > 1e-12 * scale * scale * scale) || !(scale > 0.0)) {
            throw InvalidInput(fmt::format(
                "nerf dataset: view {} ('{}'): transform_matrix is singular (det of the rotation "
                "{})",
                i, v.name, det));
        }
        if (v.rgb.size() != pixels) {
            throw InvalidInput(fmt::format(
                "nerf dataset: view {} ('{}'): {} colour values, expected 3 x {} x {} = {}", i,
                v.name, v.rgb.size(), in.width, in.height, pixels));
        }
    }
    if (dataset.box &&
        (dataset.box->is_empty() || !is_finite(dataset.box->lo) || !is_finite(dataset.box->hi) ||
         !(dataset.box->hi.x > dataset.box->lo.x && dataset.box->hi.y > dataset.box->lo.y &&
           dataset.box->hi.z > dataset.box->lo.z))) {
        throw InvalidInput(fmt::format(
            "nerf dataset: aabb [({}, {}, {}), ({}, {}, {})]: expected finite min < max per axis",
            dataset.box->lo.x, dataset.box->lo.y, dataset.box->lo.z, dataset.box->hi.x,
            dataset.box->hi.y, dataset.box->hi.z));
    }
}

render::Image to_image(const Intrinsics& intrinsics, const View& view) {
    render::Image image(intrinsics.width, intrinsics.height);
    for (std::size_t p = 0; p < image.num_pixels(); ++p) {
        const render::Rgb8 c =
            render::to_rgb8({view.rgb[3 * p], view.rgb[3 * p + 1], view.rgb[3 * p + 2]});
        image.pixels[3 * p] = c.r;
        image.pixels[3 * p + 1] = c.g;
        image.pixels[3 * p + 2] = c.b;
    }
    return image;
}

std::vector<float> from_image(const render::Image& image) {
    std::vector<float> rgb(image.pixels.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        rgb[i] = static_cast<float>(image.pixels[i]) / 255.0f;
    }
    return rgb;
}

}  // namespace pliant::nerf
