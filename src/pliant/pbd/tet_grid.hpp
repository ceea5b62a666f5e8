// TetGrid: a regular tetrahedral grid over a volume, the soft body the XPBD solver deforms and the
// resampler rasterizes back into voxels (Park & Kye 2022: a 64 × 64 × 64 grid of cells over a 256³
// volume, i.e. cells of B = 4 voxels).
//
// Lattice: cells of B × B × B voxels, cells = ceil(dims / B) along each axis. Lattice vertex
// (a, b, c), 0 ≤ a ≤ cells.x, sits at origin + (min(a·B, dims.x)·sx, …): the grid covers exactly
// the volume's box [origin, origin + dims · spacing] (a last, partial cell is thinner).
//
// Tets: each cell is split into 5 tets, a central one and four corner ones, mirrored in
// alternate cells (parity (i + j + k) mod 2) so that the face diagonals of neighbouring cells
// coincide and the mesh is conforming. With cell corners numbered
//   corner = dx + 2·dy + 4·dz  (dx, dy, dz ∈ {0, 1}),
// an even cell has the central tet {1, 2, 4, 7} and corner tets at 0, 3, 5, 6; an odd cell the
// central tet {0, 3, 5, 6} and corner tets at 1, 2, 4, 7 (CELL_TETS). A cell's 5 tets are
// consecutive in `mesh.tets`, corner tets first, central tet last; cells in lattice order (x
// fastest). Every tet is positively oriented (geometry/tet_mesh.hpp).
//
// Active cells: by default only cells whose voxels, dilated by one voxel on every side (the
// trilinear footprint of a sample), hold a visible voxel: alpha > 0 for RGBA volumes, opacity > 0
// under the transfer function for scalar volumes given one, value ≠ 0 otherwise (NaN is not
// visible). `full_box` keeps every cell. Only vertices of active cells are kept, numbered in
// lattice order.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pbd {

struct TetGridOptions {
    int cell_voxels = 4;    // B ≥ 1: voxels per cell side
    bool full_box = false;  // keep every cell, visible or not
    // Visibility of a scalar volume's voxels; nullptr: value ≠ 0. Ignored for RGBA volumes.
    const volume::TransferFunction* tf = nullptr;
};

// Corner numbers (dx + 2·dy + 4·dz) of the 5 tets of an even [0] and an odd [1] cell, each
// positively oriented, corner tets first.
inline constexpr std::array<std::array<std::array<int, 4>, 5>, 2> CELL_TETS{{
    {{{0, 1, 2, 4}, {3, 2, 1, 7}, {5, 1, 4, 7}, {6, 4, 2, 7}, {1, 2, 4, 7}}},
    {{{1, 3, 0, 5}, {2, 0, 3, 6}, {4, 5, 0, 6}, {7, 3, 5, 6}, {0, 5, 3, 6}}},
}};

struct TetGrid {
    geometry::TetMesh mesh;                      // rest positions (world units) and tets
    int cell_voxels = 4;                         // B
    std::array<std::int32_t, 3> cells{0, 0, 0};  // lattice cells along x, y, z
    // Per vertex: its lattice coordinates (a, b, c), 0 ≤ a ≤ cells[0] …  #V
    std::vector<std::array<std::int32_t, 3>> vertex_lattice;
    // Per tet: the linear index i + cells.x·(j + cells.y·k) of its cell.  #T
    std::vector<std::int32_t> tet_cell;

    std::int64_t num_active_cells() const { return static_cast<std::int64_t>(tet_cell.size()) / 5; }
};

// The tet grid over `volume` (any voxel type). InvalidInput when cell_voxels < 1, the volume is
// empty, or the lattice would need more than 2³¹ − 1 vertices. A grid with no visible voxel has
// no tets. Parallel over cells, deterministic.
TetGrid build_tet_grid(const volume::Volume& volume, const TetGridOptions& options = {});

}  // namespace pliant::pbd
