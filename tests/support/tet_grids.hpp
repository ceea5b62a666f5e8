// Tet grids for the pbd tests: cells of `cell_voxels` unit voxels over a volume of `dims` voxels
// whose visible voxels form a ball (a ragged set of active cells), or every cell (full_box).
#pragma once

#include <cstddef>
#include <cstdint>

#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::test {

inline pbd::TetGrid ball_tet_grid(volume::Dims dims, bool full_box, int cell_voxels = 2) {
    volume::Volume v =
        volume::Volume::allocate(dims, volume::VoxelType::u8, {1.0, 1.0, 1.0}, {0.0, 0.0, 0.0});
    const auto data = v.values<volume::VoxelType::u8>();
    for (std::int64_t k = 0; k < dims[2]; ++k) {
        for (std::int64_t j = 0; j < dims[1]; ++j) {
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const double dx = static_cast<double>(i) - dims[0] / 2.0;
                const double dy = static_cast<double>(j) - dims[1] / 2.0;
                const double dz = static_cast<double>(k) - dims[2] / 2.0;
                data[static_cast<std::size_t>(v.index(i, j, k))] =
                    dx * dx + dy * dy + dz * dz < 0.2 * dims[0] * dims[0] ? 200 : 0;
            }
        }
    }
    return pbd::build_tet_grid(v, {.cell_voxels = cell_voxels, .full_box = full_box});
}

}  // namespace pliant::test
