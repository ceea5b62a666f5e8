#include "pliant/nerf/lens.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"

namespace pliant::nerf {

namespace {

constexpr std::array<std::pair<LensModel, std::string_view>, 6> NAMES = {{
    {LensModel::simple_pinhole, "SIMPLE_PINHOLE"},
    {LensModel::pinhole, "PINHOLE"},
    {LensModel::simple_radial, "SIMPLE_RADIAL"},
    {LensModel::radial, "RADIAL"},
    {LensModel::opencv, "OPENCV"},
    {LensModel::opencv_fisheye, "OPENCV_FISHEYE"},
}};

constexpr int MAX_NEWTON_STEPS = 50;
constexpr double NEWTON_TOLERANCE = 1e-12;  // on the residual, normalized units (or radians)

}  // namespace

std::string_view lens_model_name(LensModel model) {
    for (const auto& [m, name] : NAMES) {
        if (m == model) {
            return name;
        }
    }
    return "UNKNOWN";
}

std::optional<LensModel> lens_model_from_name(std::string_view name) {
    for (const auto& [m, n] : NAMES) {
        if (n == name) {
            return m;
        }
    }
    return std::nullopt;
}

std::string lens_model_names() {
    std::string s;
    for (const auto& [m, name] : NAMES) {
        s += s.empty() ? "" : ", ";
        s += name;
    }
    return s;
}

bool Lens::is_identity() const {
    return k1 == 0.0 && k2 == 0.0 && k3 == 0.0 && k4 == 0.0 && p1 == 0.0 && p2 == 0.0;
}

bool lens_model_uses(LensModel model, std::string_view key) {
    switch (model) {
        case LensModel::simple_pinhole:
        case LensModel::pinhole:
            return false;
        case LensModel::simple_radial:
            return key == "k1";
        case LensModel::radial:
            return key == "k1" || key == "k2";
        case LensModel::opencv:
            return key == "k1" || key == "k2" || key == "k3" || key == "k4" || key == "p1" ||
                   key == "p2";
        case LensModel::opencv_fisheye:
            return key == "k1" || key == "k2" || key == "k3" || key == "k4";
    }
    return false;
}

void validate(const Lens& lens, std::string_view where) {
    const std::array<std::pair<std::string_view, double>, 6> coefficients = {{
        {"k1", lens.k1},
        {"k2", lens.k2},
        {"k3", lens.k3},
        {"k4", lens.k4},
        {"p1", lens.p1},
        {"p2", lens.p2},
    }};
    for (const auto& [key, value] : coefficients) {
        if (!std::isfinite(value)) {
            throw InvalidInput(
                fmt::format("{}: distortion coefficient {} = {} is not finite", where, key, value));
        }
        if (value != 0.0 && !lens_model_uses(lens.model, key)) {
            throw InvalidInput(
                fmt::format("{}: distortion coefficient {} = {} but the camera model {} has no {}",
                            where, key, value, lens_model_name(lens.model), key));
        }
    }
}

Point2 distort(const Lens& lens, Point2 p) {
    const double u = p.x, v = p.y;
    if (lens.model == LensModel::opencv_fisheye) {
        const double r = std::sqrt(u * u + v * v);
        if (r < 1e-15) {
            return p;  // θ_d / r → 1
        }
        const double t = std::atan(r), t2 = t * t;
        const double td =
            t * (1.0 + t2 * (lens.k1 + t2 * (lens.k2 + t2 * (lens.k3 + t2 * lens.k4))));
        return {u * td / r, v * td / r};
    }
    const double r2 = u * u + v * v;
    const double radial = 1.0 + r2 * (lens.k1 + r2 * (lens.k2 + r2 * (lens.k3 + r2 * lens.k4)));
    return {u * radial + 2.0 * lens.p1 * u * v + lens.p2 * (r2 + 2.0 * u * u),
            v * radial + 2.0 * lens.p2 * u * v + lens.p1 * (r2 + 2.0 * v * v)};
}

std::optional<Vec3d> undistorted_direction(const Lens& lens, Point2 d) {
    if (!std::isfinite(d.x) || !std::isfinite(d.y)) {
        return std::nullopt;
    }
    if (lens.is_identity()) {
        const Vec3d dir{d.x, d.y, 1.0};
        return dir / norm(dir);
    }
    if (lens.model == LensModel::opencv_fisheye) {
        // Solve g(θ) = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) − θ_d = 0 with g' > 0 (the
        // monotone branch).
        const double rd = std::sqrt(d.x * d.x + d.y * d.y);
        if (rd < 1e-15) {
            return Vec3d{0.0, 0.0, 1.0};
        }
        double t = rd;
        for (int step = 0; step < MAX_NEWTON_STEPS; ++step) {
            const double t2 = t * t;
            const double g =
                t * (1.0 + t2 * (lens.k1 + t2 * (lens.k2 + t2 * (lens.k3 + t2 * lens.k4)))) - rd;
            const double dg =
                1.0 + t2 * (3.0 * lens.k1 +
                            t2 * (5.0 * lens.k2 + t2 * (7.0 * lens.k3 + t2 * 9.0 * lens.k4)));
            if (std::fabs(g) <= NEWTON_TOLERANCE * std::max(1.0, rd)) {
                if (!(dg > 0.0) || !(t >= 0.0) || !(t < std::numbers::pi)) {
                    return std::nullopt;
                }
                const double s = std::sin(t) / rd;
                return Vec3d{d.x * s, d.y * s, std::cos(t)};
            }
            if (!(dg > 0.0)) {
                return std::nullopt;
            }
            t -= g / dg;
            if (!std::isfinite(t)) {
                return std::nullopt;
            }
        }
        return std::nullopt;
    }
    // Radial-tangential: Newton on F(u, v) = distort(u, v) − d with the analytic Jacobian; the
    // solution must have det J > 0 (the lens does not fold back there).
    double u = d.x, v = d.y;
    for (int step = 0; step < MAX_NEWTON_STEPS; ++step) {
        const double r2 = u * u + v * v;
        const double radial = 1.0 + r2 * (lens.k1 + r2 * (lens.k2 + r2 * (lens.k3 + r2 * lens.k4)));
        const double dradial =
            lens.k1 + r2 * (2.0 * lens.k2 + r2 * (3.0 * lens.k3 + r2 * 4.0 * lens.k4));
        const double fx = u * radial + 2.0 * lens.p1 * u * v + lens.p2 * (r2 + 2.0 * u * u) - d.x;
        const double fy = v * radial + 2.0 * lens.p2 * u * v + lens.p1 * (r2 + 2.0 * v * v) - d.y;
        const double a = radial + 2.0 * u * u * dradial + 2.0 * lens.p1 * v + 6.0 * lens.p2 * u;
        const double b = 2.0 * u * v * dradial + 2.0 * lens.p1 * u + 2.0 * lens.p2 * v;
        const double c = 2.0 * u * v * dradial + 2.0 * lens.p2 * v + 2.0 * lens.p1 * u;
        const double e = radial + 2.0 * v * v * dradial + 2.0 * lens.p2 * u + 6.0 * lens.p1 * v;
        const double det = a * e - b * c;
        const double scale = std::max({1.0, std::fabs(d.x), std::fabs(d.y)});
        if (std::fabs(fx) <= NEWTON_TOLERANCE * scale &&
            std::fabs(fy) <= NEWTON_TOLERANCE * scale) {
            if (!(det > 0.0)) {
                return std::nullopt;
            }
            const Vec3d dir{u, v, 1.0};
            return dir / norm(dir);
        }
        if (!(std::fabs(det) > 1e-300)) {
            return std::nullopt;
        }
        u -= (e * fx - b * fy) / det;
        v -= (a * fy - c * fx) / det;
        if (!std::isfinite(u) || !std::isfinite(v)) {
            return std::nullopt;
        }
    }
    return std::nullopt;
}

std::optional<Point2> undistort(const Lens& lens, Point2 distorted) {
    if (lens.is_identity()) {
        return distorted;
    }
    const std::optional<Vec3d> dir = undistorted_direction(lens, distorted);
    if (!dir || !(dir->z > 0.0)) {
        return std::nullopt;
    }
    return Point2{dir->x / dir->z, dir->y / dir->z};
}

}  // namespace pliant::nerf
