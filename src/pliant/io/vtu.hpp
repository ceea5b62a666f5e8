// A tetrahedral mesh as a VTK XML UnstructuredGrid (.vtu, VTK file format 1.0), what ParaView,
// VTK and meshio read.
//
// Written: Points (Float32, 3 components: the positions), Cells (connectivity Int64, offsets
// Int64, types UInt8 = VTK_TETRA 10, the 4 vertex indices in the mesh's order: pliant's positive
// orientation is VTK's), and, when rest positions are given:
//   PointData  "displacement"  (Float32 × 3)  positions − rest positions, world units
//              "rest_position" (Float32 × 3)  the rest positions
//   CellData   "volume_ratio"  (Float32)      signed volume now / signed volume at rest (1: kept,
//                                             < 0: inverted; 0 for a degenerate rest tet)
// Encoding: format="binary" (base64 inline, header_type UInt64: each array is base64 of an
// 8-byte little-endian byte count followed by the little-endian values), byte_order
// LittleEndian: portable, one self-contained file. Written atomically (io/atomic_file.hpp).
//
// InvalidInput when a tet index is outside [0, #V), or rest positions are given with another
// count than positions.
#pragma once

#include <filesystem>
#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"

namespace pliant::io {

// positions: #V; tets: #T; rest_positions: #V or empty (no point or cell data).
void write_vtu(const std::filesystem::path& path, std::span<const Vec3f> positions,
               std::span<const geometry::Tet> tets, std::span<const Vec3f> rest_positions = {});

}  // namespace pliant::io
