#include "pliant/geometry/generate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::geometry {

TriangleMesh make_grid_sheet(int nx, int ny, float width, float height) {
    if (nx < 1 || ny < 1 || nx > 1 << 14 || ny > 1 << 14) {
        throw InvalidInput(
            fmt::format("make_grid_sheet: resolution {} x {} not in [1, 16384]", nx, ny));
    }
    if (!(width > 0.0f) || !(height > 0.0f) || !std::isfinite(width) || !std::isfinite(height)) {
        throw InvalidInput(fmt::format("make_grid_sheet: size {} x {} must be finite and positive",
                                       width, height));
    }
    TriangleMesh mesh;
    const auto nvx = static_cast<std::size_t>(nx) + 1;
    mesh.positions.reserve(nvx * (static_cast<std::size_t>(ny) + 1));
    for (int j = 0; j <= ny; ++j) {
        for (int i = 0; i <= nx; ++i) {
            mesh.positions.push_back(
                {width * (static_cast<float>(i) / static_cast<float>(nx) - 0.5f),
                 height * (static_cast<float>(j) / static_cast<float>(ny) - 0.5f), 0.0f});
        }
    }
    mesh.triangles.reserve(2 * static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
    const auto vertex = [nx](int i, int j) {
        return j * (nx + 1) + i;
    };
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            const std::int32_t a = vertex(i, j), b = vertex(i + 1, j), c = vertex(i + 1, j + 1),
                               d = vertex(i, j + 1);
            if ((i + j) % 2 == 0) {
                mesh.triangles.push_back({a, b, c});
                mesh.triangles.push_back({a, c, d});
            } else {
                mesh.triangles.push_back({a, b, d});
                mesh.triangles.push_back({b, c, d});
            }
        }
    }
    return mesh;
}

int nearest_square_sheet(std::int64_t triangles) {
    if (triangles < 2) {
        return 1;
    }
    if (triangles > std::int64_t{2} * (1 << 14) * (1 << 14)) {  // make_grid_sheet's limit
        throw InvalidInput(fmt::format("nearest_square_sheet: {} triangles, at most {} supported",
                                       triangles, std::int64_t{2} * (1 << 14) * (1 << 14)));
    }
    const auto guess = static_cast<std::int64_t>(std::sqrt(static_cast<double>(triangles) / 2.0));
    std::int64_t best = guess < 1 ? 1 : guess;
    for (std::int64_t n = best; n <= guess + 1; ++n) {
        if (std::llabs(2 * n * n - triangles) < std::llabs(2 * best * best - triangles)) {
            best = n;
        }
    }
    return static_cast<int>(best);
}

void fold_accordion(std::span<Vec3f> positions, float panel, float gap) {
    if (!(panel > 0.0f) || !(gap > 0.0f) || !std::isfinite(panel) || !std::isfinite(gap)) {
        throw InvalidInput(
            fmt::format("fold_accordion: panel ({}) and gap ({}) must be positive", panel, gap));
    }
    validate_positions(std::span<const Vec3f>(positions), "fold_accordion: positions");
    float x_min = INFINITY;
    for (const Vec3f& p : positions) {
        x_min = std::min(x_min, p.x);
    }
    const float radius = 0.5f * gap;
    const float arc = std::numbers::pi_v<float> * radius;
    const float period = panel + arc;
    for (Vec3f& p : positions) {
        const float s = p.x - x_min;  // arc length along the unfolded sheet
        const auto layer = static_cast<int>(std::floor(s / period));
        const float u = s - static_cast<float>(layer) * period;
        const float direction = layer % 2 == 0 ? 1.0f : -1.0f;
        const float start = layer % 2 == 0 ? 0.0f : panel;  // x where this layer's panel begins
        const float z0 = static_cast<float>(layer) * gap;
        if (u <= panel) {
            p.x = start + direction * u;
            p.z = z0;
        } else {
            // Half-cylinder fold around the axis at (start + direction·panel, z0 + radius).
            const float angle = (u - panel) / radius;
            p.x = start + direction * (panel + radius * std::sin(angle));
            p.z = z0 + radius - radius * std::cos(angle);
        }
    }
}

namespace {

void check_finite(Vec3d v, const char* who, const char* name) {
    if (!is_finite(v)) {
        throw InvalidInput(
            fmt::format("{}: {} ({}, {}, {}) must be finite", who, name, v.x, v.y, v.z));
    }
}

}  // namespace

TriangleMeshD make_uv_sphere(Vec3d center, double radius, int segments) {
    check_finite(center, "make_uv_sphere", "center");
    if (!(radius > 0.0) || !std::isfinite(radius)) {
        throw InvalidInput(
            fmt::format("make_uv_sphere: radius {}, expected a finite value > 0", radius));
    }
    if (segments < 3 || segments > 4096) {
        throw InvalidInput(
            fmt::format("make_uv_sphere: segments {}, expected 3 to 4096", segments));
    }
    const int stacks = std::max(2, segments / 2);
    TriangleMeshD mesh;
    mesh.positions.reserve(2 + static_cast<std::size_t>(stacks - 1) * segments);
    mesh.positions.push_back(center + Vec3d{0.0, 0.0, radius});  // north pole: vertex 0
    for (int i = 1; i < stacks; ++i) {
        const double theta = std::numbers::pi * i / stacks;  // polar angle from +z
        for (int j = 0; j < segments; ++j) {
            const double phi = 2.0 * std::numbers::pi * j / segments;
            mesh.positions.push_back(center + radius * Vec3d{std::sin(theta) * std::cos(phi),
                                                             std::sin(theta) * std::sin(phi),
                                                             std::cos(theta)});
        }
    }
    const auto south = static_cast<std::int32_t>(mesh.positions.size());
    mesh.positions.push_back(center - Vec3d{0.0, 0.0, radius});
    const auto ring = [segments](int i, int j) {  // vertex j of ring i (1 … stacks − 1)
        return static_cast<std::int32_t>(1 + (i - 1) * segments + (j % segments));
    };
    // Seen from outside, +phi runs to the right when +z is up, so (north, ring j, ring j+1) is
    // counter-clockwise from outside.
    for (int j = 0; j < segments; ++j) {
        mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    }
    for (int i = 1; i + 1 < stacks; ++i) {
        for (int j = 0; j < segments; ++j) {
            const std::int32_t a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j + 1),
                               d = ring(i + 1, j);
            mesh.triangles.push_back({a, d, c});
            mesh.triangles.push_back({a, c, b});
        }
    }
    for (int j = 0; j < segments; ++j) {
        mesh.triangles.push_back({south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
    }
    return mesh;
}

TriangleMeshD make_box(Vec3d min, Vec3d max) {
    check_finite(min, "make_box", "min");
    check_finite(max, "make_box", "max");
    if (!(min.x < max.x && min.y < max.y && min.z < max.z)) {
        throw InvalidInput(
            fmt::format("make_box: min ({}, {}, {}) must be below max ({}, {}, {}) "
                        "on every axis",
                        min.x, min.y, min.z, max.x, max.y, max.z));
    }
    TriangleMeshD mesh;
    // Corner k has x from bit 0, y from bit 1, z from bit 2 (0 → min, 1 → max).
    for (int k = 0; k < 8; ++k) {
        mesh.positions.push_back({(k & 1) != 0 ? max.x : min.x, (k & 2) != 0 ? max.y : min.y,
                                  (k & 4) != 0 ? max.z : min.z});
    }
    // Each face as a quad counter-clockwise seen from outside, split along its first diagonal.
    static constexpr std::int32_t QUADS[6][4] = {
        {0, 4, 6, 2},  // −x
        {1, 3, 7, 5},  // +x
        {0, 1, 5, 4},  // −y
        {2, 6, 7, 3},  // +y
        {0, 2, 3, 1},  // −z
        {4, 5, 7, 6},  // +z
    };
    for (const auto& q : QUADS) {
        mesh.triangles.push_back({q[0], q[1], q[2]});
        mesh.triangles.push_back({q[0], q[2], q[3]});
    }
    return mesh;
}

TriangleMeshD make_plane_square(Vec3d point, Vec3d normal, double half_size) {
    check_finite(point, "make_plane_square", "point");
    check_finite(normal, "make_plane_square", "normal");
    const double length = norm(normal);
    if (!(length > 0.0)) {
        throw InvalidInput("make_plane_square: normal (0, 0, 0), expected a nonzero vector");
    }
    if (!(half_size > 0.0) || !std::isfinite(half_size)) {
        throw InvalidInput(
            fmt::format("make_plane_square: half_size {}, expected a finite value > 0", half_size));
    }
    const Vec3d n = normal / length;
    // The coordinate axis least aligned with n gives a well-conditioned first tangent.
    const Vec3d axis =
        std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z)
            ? Vec3d{1.0, 0.0, 0.0}
            : (std::abs(n.y) <= std::abs(n.z) ? Vec3d{0.0, 1.0, 0.0} : Vec3d{0.0, 0.0, 1.0});
    Vec3d u = cross(axis, n);
    u = u / norm(u);
    const Vec3d v = cross(n, u);  // (u, v, n) right-handed
    TriangleMeshD mesh;
    mesh.positions = {point + half_size * (-1.0 * u - v), point + half_size * (u - v),
                      point + half_size * (u + v), point + half_size * (v - u)};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    return mesh;
}

}  // namespace pliant::geometry
