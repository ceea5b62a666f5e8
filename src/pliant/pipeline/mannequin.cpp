#include "pliant/pipeline/mannequin.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::pipeline {
namespace {

constexpr double PI = std::numbers::pi;
constexpr double HIP_Z = 0.95;
constexpr double CHEST_Z = 1.45;

struct Part {
    std::vector<Vec3d> vertices;
    std::vector<geometry::Triangle> triangles;  // local indices
};

// A closed capsule around the segment a-b, built where the axis is +z from a (z = 0) to b
// (z = L) and mapped; squash_depth scales the cross-section along u (for a vertical axis the
// world's y: an elliptic torso, less deep than wide). Outward counter-clockwise winding. As
// scripts/make-body's capsule().
Part capsule(const Vec3d& a, const Vec3d& b, double radius, int segments, int cap_rings,
             int body_rings, double squash_depth = 1.0) {
    const Vec3d axis = b - a;
    const double length = norm(axis);
    const Vec3d w = axis * (1.0 / length);
    const Vec3d ref = std::abs(w.x) < 0.9 ? Vec3d{1.0, 0.0, 0.0} : Vec3d{0.0, 1.0, 0.0};
    Vec3d u{ref.y * w.z - ref.z * w.y, ref.z * w.x - ref.x * w.z, ref.x * w.y - ref.y * w.x};
    u = u * (1.0 / norm(u));
    const Vec3d v{w.y * u.z - w.z * u.y, w.z * u.x - w.x * u.z, w.x * u.y - w.y * u.x};
    std::vector<std::pair<double, double>> rings;  // (z along the axis, ring radius)
    for (int k = 1; k <= cap_rings; ++k) {
        const double phi = -PI / 2 + (PI / 2) * k / cap_rings;
        rings.emplace_back(radius * std::sin(phi), radius * std::cos(phi));
    }
    for (int k = 1; k < body_rings; ++k) {
        rings.emplace_back(length * k / body_rings, radius);
    }
    for (int k = 0; k < cap_rings; ++k) {
        const double phi = (PI / 2) * k / cap_rings;
        rings.emplace_back(length + radius * std::sin(phi), radius * std::cos(phi));
    }
    const auto point = [&](double z, double r, double angle) {
        const double x = r * std::cos(angle) * squash_depth;
        const double y = r * std::sin(angle);
        return Vec3d{a.x + u.x * x + v.x * y + w.x * z, a.y + u.y * x + v.y * y + w.y * z,
                     a.z + u.z * x + v.z * y + w.z * z};
    };
    Part part;
    part.vertices.push_back(point(-radius, 0.0, 0.0));
    for (const auto& [z, r] : rings) {
        for (int s = 0; s < segments; ++s) {
            part.vertices.push_back(point(z, r, 2 * PI * s / segments));
        }
    }
    part.vertices.push_back(point(length + radius, 0.0, 0.0));
    const auto top = static_cast<std::int32_t>(part.vertices.size()) - 1;
    for (int s = 0; s < segments; ++s) {  // bottom fan: seen from below, counter-clockwise
        part.triangles.push_back({0, 1 + (s + 1) % segments, 1 + s});
    }
    const auto num_rings = static_cast<int>(rings.size());
    for (int r = 0; r + 1 < num_rings; ++r) {
        const int base0 = 1 + r * segments;
        const int base1 = base0 + segments;
        for (int s = 0; s < segments; ++s) {
            const int s1 = (s + 1) % segments;
            part.triangles.push_back({base0 + s, base0 + s1, base1 + s1});
            part.triangles.push_back({base0 + s, base1 + s1, base1 + s});
        }
    }
    const int last = 1 + (num_rings - 1) * segments;
    for (int s = 0; s < segments; ++s) {
        part.triangles.push_back({last + s, last + (s + 1) % segments, top});
    }
    return part;
}

Vec3d rotate_x(const Vec3d& p, const Vec3d& pivot, double degrees) {
    const double t = degrees * PI / 180.0;
    const double y = p.y - pivot.y;
    const double z = p.z - pivot.z;
    return {p.x, pivot.y + y * std::cos(t) - z * std::sin(t),
            pivot.z + y * std::sin(t) + z * std::cos(t)};
}

Vec3d rotate_z(const Vec3d& p, double degrees) {
    const double t = degrees * PI / 180.0;
    return {p.x * std::cos(t) - p.y * std::sin(t), p.x * std::sin(t) + p.y * std::cos(t), p.z};
}

}  // namespace

geometry::TriangleMeshD mannequin_at(double phase, const MannequinOptions& options) {
    if (options.segments < 3 || !std::isfinite(phase) || !std::isfinite(options.turn_degrees) ||
        !std::isfinite(options.swing_degrees)) {
        throw InvalidInput(fmt::format(
            "pipeline::mannequin_at: expected segments >= 3 and finite phase, turn and swing; got "
            "segments {}, phase {}, turn {}, swing {}",
            options.segments, phase, options.turn_degrees, options.swing_degrees));
    }
    const int seg = options.segments;
    const double swing = options.swing_degrees * std::sin(2 * PI * phase);
    const double hips = options.turn_degrees * std::sin(2 * PI * phase);
    const double chest = -0.5 * hips;
    std::vector<Part> parts;
    // Torso: twisted between the hips' and the chest's turn.
    Part torso = capsule({0, 0, HIP_Z}, {0, 0, CHEST_Z}, 0.17, seg, 4, 6, 0.62);
    for (Vec3d& p : torso.vertices) {
        const double f = std::clamp((p.z - HIP_Z) / (CHEST_Z - HIP_Z), 0.0, 1.0);
        p = rotate_z(p, hips + (chest - hips) * f);
    }
    parts.push_back(std::move(torso));
    // Head, turning with the chest.
    Part head = capsule({0, 0, 1.62}, {0, 0, 1.70}, 0.10, seg, 4, 2);
    for (Vec3d& p : head.vertices) {
        p = rotate_z(p, chest);
    }
    parts.push_back(std::move(head));
    // Legs: from the hip joints down, swinging in opposite phase, turning with the hips.
    for (const auto& [side, sign] : {std::pair{-1.0, 1.0}, std::pair{1.0, -1.0}}) {
        const Vec3d hip{0.095 * side, 0.0, HIP_Z + 0.02};
        Part leg = capsule(hip, {0.095 * side, 0.0, 0.08}, 0.075, seg, 3, 8);
        for (Vec3d& p : leg.vertices) {
            p = rotate_z(rotate_x(p, hip, sign * swing), hips);
        }
        parts.push_back(std::move(leg));
    }
    // Arms: from the shoulders down, swinging against the legs, turning with the chest.
    for (const auto& [side, sign] : {std::pair{-1.0, -1.0}, std::pair{1.0, 1.0}}) {
        const Vec3d shoulder{0.235 * side, 0.0, 1.40};
        Part arm = capsule(shoulder, {0.26 * side, 0.0, 0.88}, 0.045, seg, 3, 6);
        for (Vec3d& p : arm.vertices) {
            p = rotate_z(rotate_x(p, shoulder, sign * swing * 0.8), chest);
        }
        parts.push_back(std::move(arm));
    }
    geometry::TriangleMeshD mesh;
    for (const Part& part : parts) {
        const auto offset = static_cast<std::int32_t>(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), part.vertices.begin(), part.vertices.end());
        for (const geometry::Triangle& t : part.triangles) {
            mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
    }
    return mesh;
}

std::string mesh_obj(const geometry::TriangleMeshD& mesh, const std::string& comment) {
    std::string obj = "# " + comment + "\n";
    auto out = std::back_inserter(obj);
    for (const Vec3d& p : mesh.positions) {
        fmt::format_to(out, "v {:.6f} {:.6f} {:.6f}\n", p.x, p.y, p.z);
    }
    for (const geometry::Triangle& t : mesh.triangles) {
        fmt::format_to(out, "f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    return obj;
}

}  // namespace pliant::pipeline
