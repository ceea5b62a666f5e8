#include "random_meshes.hpp"

#include <cmath>
#include <random>

#include "pliant/geometry/generate.hpp"

namespace pliant::test {

geometry::TriangleMesh random_triangle_soup(int n, float size, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_real_distribution<float> offset(-size, size);
    geometry::TriangleMesh mesh;
    for (int t = 0; t < n; ++t) {
        const Vec3f c{unit(rng), unit(rng), unit(rng)};
        for (int k = 0; k < 3; ++k) {
            mesh.positions.push_back(c + Vec3f{offset(rng), offset(rng), offset(rng)} * 0.5f);
        }
        mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    return mesh;
}

geometry::TriangleMesh jittered_sheet(int nx, int ny, float jitter, float amplitude,
                                      std::uint32_t seed) {
    geometry::TriangleMesh mesh = geometry::make_grid_sheet(nx, ny, 1.0f, 1.0f);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const float h = jitter / static_cast<float>(nx > ny ? nx : ny);
    for (Vec3f& p : mesh.positions) {
        p.x += h * u(rng);
        p.y += h * u(rng);
        p.z = amplitude * std::sin(9.0f * p.x) * std::cos(7.0f * p.y) + h * u(rng);
    }
    return mesh;
}

std::vector<AABB> triangle_boxes(const geometry::TriangleMesh& mesh, float inflate) {
    std::vector<AABB> boxes(mesh.triangles.size());
    for (std::size_t t = 0; t < boxes.size(); ++t) {
        AABB b;
        for (const std::int32_t v : mesh.triangles[t]) {
            b.extend(mesh.positions[static_cast<std::size_t>(v)]);
        }
        boxes[t] = b.inflated(inflate);
    }
    return boxes;
}

std::vector<AABB> random_boxes(int n, float size, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<AABB> boxes(static_cast<std::size_t>(n));
    for (AABB& b : boxes) {
        b.lo = {unit(rng), unit(rng), unit(rng)};
        b.hi = b.lo + Vec3f{unit(rng), unit(rng), unit(rng)} * size;
    }
    return boxes;
}

}  // namespace pliant::test
