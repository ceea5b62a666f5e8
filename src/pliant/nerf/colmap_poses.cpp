#include "pliant/nerf/colmap_poses.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/core/error.hpp"

namespace pliant::nerf {

namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 multiply(const Mat3& a, const Mat3& b) {
    Mat3 c{};
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
            for (int j = 0; j < 3; ++j) {
                c[r][k] += a[r][j] * b[j][k];
            }
        }
    }
    return c;
}

Vec3d rotate(const Mat3& a, Vec3d v) {
    return {a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
            a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
            a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z};
}

Mat3 rotation_of(const Pose& p) {
    return {{{p.m[0], p.m[1], p.m[2]}, {p.m[4], p.m[5], p.m[6]}, {p.m[8], p.m[9], p.m[10]}}};
}

// The smallest rotation taking unit a to unit b (Rodrigues); a half turn about an axis
// perpendicular to a when they are opposite.
Mat3 rotation_between(Vec3d a, Vec3d b) {
    const Vec3d v = cross(a, b);
    const double c = dot(a, b);
    if (c < -1.0 + 1e-12) {
        Vec3d axis = std::fabs(a.x) < 0.9 ? cross(a, Vec3d{1, 0, 0}) : cross(a, Vec3d{0, 1, 0});
        axis = axis / norm(axis);
        Mat3 r{};
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                r[i][j] = 2.0 * axis[i] * axis[j] - (i == j ? 1.0 : 0.0);
            }
        }
        return r;
    }
    const Mat3 vx = {{{0.0, -v.z, v.y}, {v.z, 0.0, -v.x}, {-v.y, v.x, 0.0}}};
    const Mat3 vx2 = multiply(vx, vx);
    Mat3 r{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            r[i][j] = (i == j ? 1.0 : 0.0) + vx[i][j] + vx2[i][j] / (1.0 + c);
        }
    }
    return r;
}

// Least-squares point nearest to the lines (o_i, d_i): Σ (I − d dᵀ) p = Σ (I − d dᵀ) o; false
// when the system is (nearly) singular.
bool nearest_point_to_axes(const std::vector<Vec3d>& origins, const std::vector<Vec3d>& dirs,
                           Vec3d& out) {
    double a[3][3] = {};
    double b[3] = {};
    for (std::size_t i = 0; i < origins.size(); ++i) {
        const Vec3d d = dirs[i];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                const double m = (r == c ? 1.0 : 0.0) - d[r] * d[c];
                a[r][c] += m;
                b[r] += m * origins[i][c];
            }
        }
    }
    const auto det3 = [](const double m[3][3]) {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double det = det3(a);
    const double n = static_cast<double>(origins.size());
    if (!(std::fabs(det) > 1e-6 * n * n * n)) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        double m[3][3];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                m[r][c] = c == k ? b[r] : a[r][c];
            }
        }
        out[k] = det3(m) / det;
    }
    return true;
}

}  // namespace

Intrinsics intrinsics_from_colmap(const io::ColmapCamera& camera) {
    const std::vector<double>& p = camera.params;
    const std::string_view name = io::colmap_camera_model_name(camera.model_id).value_or("?");
    if (static_cast<int>(p.size()) != io::colmap_camera_model_num_params(camera.model_id)) {
        throw InvalidInput(
            fmt::format("COLMAP camera {}: model {} needs {} parameters, got {}", camera.id, name,
                        io::colmap_camera_model_num_params(camera.model_id), p.size()));
    }
    Intrinsics in;
    in.width = static_cast<int>(camera.width);
    in.height = static_cast<int>(camera.height);
    const auto single_focal = [&](LensModel model) {
        in.fx = in.fy = p[0];
        in.cx = p[1];
        in.cy = p[2];
        in.lens.model = model;
    };
    const auto two_focals = [&](LensModel model) {
        in.fx = p[0];
        in.fy = p[1];
        in.cx = p[2];
        in.cy = p[3];
        in.lens.model = model;
    };
    switch (camera.model_id) {
        case 0:
            single_focal(LensModel::simple_pinhole);
            break;
        case 1:
            two_focals(LensModel::pinhole);
            break;
        case 2:
            single_focal(LensModel::simple_radial);
            in.lens.k1 = p[3];
            break;
        case 3:
            single_focal(LensModel::radial);
            in.lens.k1 = p[3];
            in.lens.k2 = p[4];
            break;
        case 4:
            two_focals(LensModel::opencv);
            in.lens.k1 = p[4];
            in.lens.k2 = p[5];
            in.lens.p1 = p[6];
            in.lens.p2 = p[7];
            break;
        case 5:
            two_focals(LensModel::opencv_fisheye);
            in.lens.k1 = p[4];
            in.lens.k2 = p[5];
            in.lens.k3 = p[6];
            in.lens.k4 = p[7];
            break;
        default:
            throw Unsupported(fmt::format(
                "COLMAP camera {}: camera model {} is not supported (supported: {}); convert the "
                "model with `colmap image_undistorter` or re-run COLMAP with the OPENCV model",
                camera.id, name, lens_model_names()));
    }
    return in;
}

io::ColmapCamera colmap_camera_from_intrinsics(const Intrinsics& in, std::uint32_t id) {
    io::ColmapCamera c;
    c.id = id;
    c.width = static_cast<std::uint64_t>(in.width);
    c.height = static_cast<std::uint64_t>(in.height);
    const Lens& l = in.lens;
    switch (l.model) {
        case LensModel::simple_pinhole:
            c.model_id = 0;
            c.params = {in.fx, in.cx, in.cy};
            break;
        case LensModel::pinhole:
            c.model_id = 1;
            c.params = {in.fx, in.fy, in.cx, in.cy};
            break;
        case LensModel::simple_radial:
            c.model_id = 2;
            c.params = {in.fx, in.cx, in.cy, l.k1};
            break;
        case LensModel::radial:
            c.model_id = 3;
            c.params = {in.fx, in.cx, in.cy, l.k1, l.k2};
            break;
        case LensModel::opencv:
            if (l.k3 != 0.0 || l.k4 != 0.0) {
                throw Unsupported(
                    "nerf::colmap_camera_from_intrinsics: COLMAP's OPENCV model has no k3, k4");
            }
            c.model_id = 4;
            c.params = {in.fx, in.fy, in.cx, in.cy, l.k1, l.k2, l.p1, l.p2};
            break;
        case LensModel::opencv_fisheye:
            c.model_id = 5;
            c.params = {in.fx, in.fy, in.cx, in.cy, l.k1, l.k2, l.k3, l.k4};
            break;
    }
    return c;
}

Pose pose_from_colmap(const std::array<double, 4>& qvec, const std::array<double, 3>& tvec) {
    const double n =
        std::sqrt(qvec[0] * qvec[0] + qvec[1] * qvec[1] + qvec[2] * qvec[2] + qvec[3] * qvec[3]);
    if (!(n > 1e-6) || !std::isfinite(n)) {
        throw InvalidInput(
            fmt::format("COLMAP quaternion ({}, {}, {}, {}): norm {} is not a "
                        "rotation",
                        qvec[0], qvec[1], qvec[2], qvec[3], n));
    }
    const double w = qvec[0] / n, x = qvec[1] / n, y = qvec[2] / n, z = qvec[3] / n;
    // World-to-camera rotation R (Hamilton quaternion, as COLMAP's QuaternionToRotationMatrix).
    const Mat3 r = {{{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                     {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                     {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}}};
    const Vec3d t{tvec[0], tvec[1], tvec[2]};
    // C = −Rᵀ t; the camera axes in world coordinates are the rows of R; OpenGL flips y and z.
    Vec3d c;
    for (int k = 0; k < 3; ++k) {
        c[k] = -(r[0][k] * t.x + r[1][k] * t.y + r[2][k] * t.z);
    }
    Pose pose;
    for (int row = 0; row < 3; ++row) {
        pose.m[4 * row + 0] = r[0][row];
        pose.m[4 * row + 1] = -r[1][row];
        pose.m[4 * row + 2] = -r[2][row];
        pose.m[4 * row + 3] = c[row];
    }
    return pose;
}

void colmap_from_pose(const Pose& pose, std::array<double, 4>& qvec, std::array<double, 3>& tvec) {
    // R (world-to-camera, OpenCV) has as rows the camera's x, −y_gl, −z_gl axes.
    Mat3 r{};
    for (int k = 0; k < 3; ++k) {
        r[0][k] = pose.m[4 * k + 0];
        r[1][k] = -pose.m[4 * k + 1];
        r[2][k] = -pose.m[4 * k + 2];
    }
    // Rotation matrix → quaternion (Shepperd's method: the largest diagonal term first).
    const double tr = r[0][0] + r[1][1] + r[2][2];
    double w, x, y, z;
    if (tr > 0.0) {
        const double s = 2.0 * std::sqrt(1.0 + tr);
        w = 0.25 * s;
        x = (r[2][1] - r[1][2]) / s;
        y = (r[0][2] - r[2][0]) / s;
        z = (r[1][0] - r[0][1]) / s;
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        const double s = 2.0 * std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]);
        w = (r[2][1] - r[1][2]) / s;
        x = 0.25 * s;
        y = (r[0][1] + r[1][0]) / s;
        z = (r[0][2] + r[2][0]) / s;
    } else if (r[1][1] > r[2][2]) {
        const double s = 2.0 * std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]);
        w = (r[0][2] - r[2][0]) / s;
        x = (r[0][1] + r[1][0]) / s;
        y = 0.25 * s;
        z = (r[1][2] + r[2][1]) / s;
    } else {
        const double s = 2.0 * std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]);
        w = (r[1][0] - r[0][1]) / s;
        x = (r[0][2] + r[2][0]) / s;
        y = (r[1][2] + r[2][1]) / s;
        z = 0.25 * s;
    }
    if (w < 0.0) {
        w = -w;
        x = -x;
        y = -y;
        z = -z;
    }
    qvec = {w, x, y, z};
    const Vec3d c = pose.eye();
    const Vec3d t = -rotate(r, c);  // t = −R C
    tvec = {t.x, t.y, t.z};
}

ColmapTransforms transforms_from_colmap(const io::ColmapModel& model,
                                        const ColmapConversionOptions& options) {
    if (model.images.empty()) {
        throw InvalidInput("COLMAP model: no registered images");
    }
    if (!(options.points_quantile > 0.0 && options.points_quantile <= 1.0)) {
        throw InvalidInput(
            fmt::format("nerf::transforms_from_colmap: points_quantile {} must be in (0, 1]",
                        options.points_quantile));
    }
    ColmapTransforms out;
    // Step 1: frames in COLMAP's world, sorted by name.
    std::vector<const io::ColmapImage*> images;
    images.reserve(model.images.size());
    for (const io::ColmapImage& im : model.images) {
        images.push_back(&im);
    }
    std::sort(images.begin(), images.end(), [](const io::ColmapImage* a, const io::ColmapImage* b) {
        return a->name != b->name ? a->name < b->name : a->id < b->id;
    });
    for (const io::ColmapImage* im : images) {
        const io::ColmapCamera* camera = model.find_camera(im->camera_id);
        if (camera == nullptr) {
            throw InvalidInput(
                fmt::format("COLMAP model: image {} ('{}') names camera {}, which "
                            "the model does not have",
                            im->id, im->name, im->camera_id));
        }
        ColmapFrame f;
        f.file_path = im->name;
        f.image_id = im->id;
        f.intrinsics = intrinsics_from_colmap(*camera);
        f.camera_to_world = pose_from_colmap(im->qvec, im->tvec);
        out.frames.push_back(std::move(f));
    }

    // Step 2: orientation Q.
    Mat3 q = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    if (options.orient_up) {
        Vec3d up;
        for (const ColmapFrame& f : out.frames) {
            up += f.camera_to_world.axis(1);
        }
        if (norm(up) > 1e-9) {
            q = rotation_between(up / norm(up), Vec3d{0, 0, 1});
        }
    }

    // Step 3: centre c (COLMAP world).
    std::vector<Vec3d> eyes, dirs;
    for (const ColmapFrame& f : out.frames) {
        eyes.push_back(f.camera_to_world.eye());
        dirs.push_back(-f.camera_to_world.axis(2));
    }
    Vec3d mean;
    for (const Vec3d& e : eyes) {
        mean += e;
    }
    mean = mean / static_cast<double>(eyes.size());
    Vec3d centre;
    switch (options.centre) {
        case ColmapCentre::none:
            break;
        case ColmapCentre::camera_mean:
            centre = mean;
            break;
        case ColmapCentre::focus:
            if (!nearest_point_to_axes(eyes, dirs, centre)) {
                centre = mean;
            }
            break;
    }

    // Step 4: scale s.
    const auto camera_scale = [&] {
        double extent = 0.0;
        for (const Vec3d& e : eyes) {
            const Vec3d d = rotate(q, e - centre);
            extent = std::max({extent, std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)});
        }
        return extent > 0.0 ? 1.0 / extent : 1.0;
    };
    constexpr std::size_t MIN_POINTS = 8;
    double s = 1.0;
    out.scale_used = options.scale;
    if (options.scale == ColmapScale::points && model.points.size() < MIN_POINTS) {
        out.scale_used = ColmapScale::cameras;
    }
    if (out.scale_used == ColmapScale::cameras) {
        s = camera_scale();
    } else if (out.scale_used == ColmapScale::points) {
        std::vector<double> extent;
        extent.reserve(model.points.size());
        for (const io::ColmapPoint3D& p : model.points) {
            const Vec3d d = rotate(q, Vec3d{p.xyz[0], p.xyz[1], p.xyz[2]} - centre);
            extent.push_back(std::max({std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)}));
        }
        const auto k = static_cast<std::size_t>(
            std::ceil(options.points_quantile * static_cast<double>(extent.size())) - 1.0);
        const auto nth =
            extent.begin() + static_cast<std::ptrdiff_t>(std::min(k, extent.size() - 1));
        std::nth_element(extent.begin(), nth, extent.end());
        s = *nth > 0.0 ? 1.0 / *nth : camera_scale();
    }

    // Step 5: apply x' = s Q (x − c) to poses and points.
    out.centre = centre;
    out.scale = s;
    const Vec3d shift = -s * rotate(q, centre);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            out.world_from_colmap[4 * r + c] = s * q[r][c];
        }
        out.world_from_colmap[4 * r + 3] = shift[r];
    }
    for (ColmapFrame& f : out.frames) {
        const Mat3 rot = multiply(q, rotation_of(f.camera_to_world));
        const Vec3d eye = s * rotate(q, f.camera_to_world.eye() - centre);
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                f.camera_to_world.m[4 * r + c] = rot[r][c];
            }
            f.camera_to_world.m[4 * r + 3] = eye[r];
        }
    }
    out.points.reserve(model.points.size());
    out.point_colors.reserve(model.points.size());
    for (const io::ColmapPoint3D& p : model.points) {
        out.points.push_back(s * rotate(q, Vec3d{p.xyz[0], p.xyz[1], p.xyz[2]} - centre));
        out.point_colors.push_back(p.rgb);
    }
    return out;
}

}  // namespace pliant::nerf
