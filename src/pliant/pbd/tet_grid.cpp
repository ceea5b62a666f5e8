#include "pliant/pbd/tet_grid.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/volume/visibility.hpp"

namespace pliant::pbd {
namespace {

using volume::Dims;

// 1 per cell whose voxel range, dilated by one voxel, holds a visible voxel.
std::vector<std::uint8_t> active_cells(const volume::Volume& volume, const TetGridOptions& options,
                                       const std::array<std::int32_t, 3>& cells) {
    const std::int64_t num_cells = std::int64_t{cells[0]} * cells[1] * cells[2];
    std::vector<std::uint8_t> active(static_cast<std::size_t>(num_cells), 1);
    if (options.full_box) {
        return active;
    }
    const std::vector<std::uint8_t> visible = volume::visible_voxels(volume, options.tf);
    const Dims& dims = volume.dims();
    const std::int64_t b = options.cell_voxels;
    parallel_for(
        num_cells,
        [&](std::int64_t cell) {
            const std::int64_t ci = cell % cells[0];
            const std::int64_t cj = (cell / cells[0]) % cells[1];
            const std::int64_t ck = cell / (std::int64_t{cells[0]} * cells[1]);
            const std::int64_t i0 = std::max<std::int64_t>(ci * b - 1, 0);
            const std::int64_t i1 = std::min((ci + 1) * b + 1, dims[0]);
            const std::int64_t j0 = std::max<std::int64_t>(cj * b - 1, 0);
            const std::int64_t j1 = std::min((cj + 1) * b + 1, dims[1]);
            const std::int64_t k0 = std::max<std::int64_t>(ck * b - 1, 0);
            const std::int64_t k1 = std::min((ck + 1) * b + 1, dims[2]);
            std::uint8_t any = 0;
            for (std::int64_t k = k0; k < k1 && any == 0; ++k) {
                for (std::int64_t j = j0; j < j1 && any == 0; ++j) {
                    const std::uint8_t* row = visible.data() + volume.index(0, j, k);
                    for (std::int64_t i = i0; i < i1; ++i) {
                        any |= row[i];
                    }
                }
            }
            active[static_cast<std::size_t>(cell)] = any;
        },
        256);
    return active;
}

}  // namespace

TetGrid build_tet_grid(const volume::Volume& volume, const TetGridOptions& options) {
    if (options.cell_voxels < 1) {
        throw InvalidInput("tet grid: cells must be at least 1 voxel wide, got " +
                           std::to_string(options.cell_voxels));
    }
    if (volume.empty()) {
        throw InvalidInput("tet grid: the volume is empty");
    }
    const Dims& dims = volume.dims();
    const std::int64_t b = options.cell_voxels;
    TetGrid grid;
    grid.cell_voxels = options.cell_voxels;
    std::array<std::int64_t, 3> lattice{};
    for (int axis = 0; axis < 3; ++axis) {
        const std::int64_t n = (dims[static_cast<std::size_t>(axis)] + b - 1) / b;
        grid.cells[static_cast<std::size_t>(axis)] = static_cast<std::int32_t>(n);
        lattice[static_cast<std::size_t>(axis)] = n + 1;
    }
    const std::int64_t num_lattice = lattice[0] * lattice[1] * lattice[2];
    if (num_lattice > std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput("tet grid: " + std::to_string(num_lattice) +
                           " lattice vertices exceed the 2^31 - 1 a mesh can index; use larger "
                           "cells (got " +
                           std::to_string(b) + " voxels per cell)");
    }
    const std::vector<std::uint8_t> active = active_cells(volume, options, grid.cells);

    // Vertices of active cells, numbered in lattice order.
    auto lattice_index = [&](std::int64_t a, std::int64_t bb, std::int64_t c) {
        return a + lattice[0] * (bb + lattice[1] * c);
    };
    std::vector<std::int32_t> vertex_of(static_cast<std::size_t>(num_lattice), -1);
    const std::int64_t num_cells = static_cast<std::int64_t>(active.size());
    for (std::int64_t cell = 0; cell < num_cells; ++cell) {
        if (active[static_cast<std::size_t>(cell)] == 0) {
            continue;
        }
        const std::int64_t ci = cell % grid.cells[0];
        const std::int64_t cj = (cell / grid.cells[0]) % grid.cells[1];
        const std::int64_t ck = cell / (std::int64_t{grid.cells[0]} * grid.cells[1]);
        for (int corner = 0; corner < 8; ++corner) {
            vertex_of[static_cast<std::size_t>(lattice_index(
                ci + (corner & 1), cj + ((corner >> 1) & 1), ck + ((corner >> 2) & 1)))] = 0;
        }
    }
    const Vec3d& spacing = volume.spacing();
    const Vec3d& origin = volume.origin();
    std::int32_t next = 0;
    for (std::int64_t c = 0; c < lattice[2]; ++c) {
        for (std::int64_t bb = 0; bb < lattice[1]; ++bb) {
            for (std::int64_t a = 0; a < lattice[0]; ++a) {
                std::int32_t& v = vertex_of[static_cast<std::size_t>(lattice_index(a, bb, c))];
                if (v < 0) {
                    continue;
                }
                v = next++;
                grid.vertex_lattice.push_back({static_cast<std::int32_t>(a),
                                               static_cast<std::int32_t>(bb),
                                               static_cast<std::int32_t>(c)});
                const Vec3d p{origin.x + static_cast<double>(std::min(a * b, dims[0])) * spacing.x,
                              origin.y + static_cast<double>(std::min(bb * b, dims[1])) * spacing.y,
                              origin.z + static_cast<double>(std::min(c * b, dims[2])) * spacing.z};
                grid.mesh.positions.push_back(vec3_cast<float>(p));
            }
        }
    }

    // 5 tets per active cell, in cell order.
    for (std::int64_t cell = 0; cell < num_cells; ++cell) {
        if (active[static_cast<std::size_t>(cell)] == 0) {
            continue;
        }
        const std::int64_t ci = cell % grid.cells[0];
        const std::int64_t cj = (cell / grid.cells[0]) % grid.cells[1];
        const std::int64_t ck = cell / (std::int64_t{grid.cells[0]} * grid.cells[1]);
        std::array<std::int32_t, 8> corner_vertex{};
        for (int corner = 0; corner < 8; ++corner) {
            corner_vertex[static_cast<std::size_t>(corner)] =
                vertex_of[static_cast<std::size_t>(lattice_index(
                    ci + (corner & 1), cj + ((corner >> 1) & 1), ck + ((corner >> 2) & 1)))];
        }
        const auto& tets = CELL_TETS[static_cast<std::size_t>((ci + cj + ck) & 1)];
        for (const auto& tet : tets) {
            grid.mesh.tets.push_back({corner_vertex[static_cast<std::size_t>(tet[0])],
                                      corner_vertex[static_cast<std::size_t>(tet[1])],
                                      corner_vertex[static_cast<std::size_t>(tet[2])],
                                      corner_vertex[static_cast<std::size_t>(tet[3])]});
            grid.tet_cell.push_back(static_cast<std::int32_t>(cell));
        }
    }
    return grid;
}

}  // namespace pliant::pbd
