#include "pliant/geometry/normals.hpp"

#include <cstdint>

#include "pliant/core/parallel.hpp"

namespace pliant::geometry {

void vertex_normals(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                    std::vector<Vec3f>& normals, std::vector<Vec3d>& sums) {
    sums.assign(positions.size(), Vec3d{});
    for (const Triangle& t : triangles) {
        const Vec3d a = positions[static_cast<std::size_t>(t[0])];
        const Vec3d n = cross(positions[static_cast<std::size_t>(t[1])] - a,
                              positions[static_cast<std::size_t>(t[2])] - a);
        for (int k = 0; k < 3; ++k) {
            sums[static_cast<std::size_t>(t[k])] += n;
        }
    }
    normals.resize(positions.size());
    parallel_for(static_cast<std::int64_t>(positions.size()), [&](std::int64_t i) {
        const auto v = static_cast<std::size_t>(i);
        const double length = norm(sums[v]);
        normals[v] = length > 0.0 ? vec3_cast<float>(sums[v] / length) : Vec3f{0.0f, 0.0f, 0.0f};
    });
}

}  // namespace pliant::geometry
