// Cloth sheets for the cloth tests: a flat square sheet of n × n quads, side `size` metres, at
// height z (metres), in double precision.
#pragma once

#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::test {

inline geometry::TriangleMeshD flat_sheet(int n, double size, double z) {
    const geometry::TriangleMesh flat =
        geometry::make_grid_sheet(n, n, static_cast<float>(size), static_cast<float>(size));
    geometry::TriangleMeshD mesh = geometry::convert_precision<double>(flat);
    for (Vec3d& p : mesh.positions) {
        p.z = z;
    }
    return mesh;
}

}  // namespace pliant::test
