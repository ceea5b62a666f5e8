#include "pliant/geometry/generate.hpp"

#include <fmt/format.h>

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

}  // namespace pliant::geometry
