// OpenVDB (.vdb) volumes through the OpenVDB library (Debian libopenvdb-dev, OpenVDB 10).
//
// Write: a scalar volume (u8, i16, u16, f32) becomes one FloatGrid named "density" (the values as
// floats: exact for the integer types); an RGBA volume (rgba8, rgba32f) becomes a FloatGrid
// "density" holding alpha and a Vec3SGrid "color" holding (r, g, b), both divided by 255 for
// rgba8 (so both RGBA types hold colour and opacity in [0, 1], as Blender and Houdini read them).
// Sparse: a voxel whose value (scalar) or alpha (RGBA) is 0 stays inactive at the background 0,
// and its colour is dropped; every other voxel is active (NaN too). Grid class: fog volume.
//
// Placement: the dense grid's voxel (i, j, k) is OpenVDB's index coordinate (i, j, k). OpenVDB
// maps an index coordinate to the world position of that voxel's centre, so the transform is the
// affine map index ↦ T + Σ_a index_a · step_a with step_a = D[a] · spacing[a] (D the direction)
// and T = origin + D · (spacing / 2), the centre of voxel (0, 0, 0) (docs/conventions.md: voxel
// i is centred at origin + D · (i + 0.5) · spacing). An axis-aligned volume gets a scale +
// translate map, an oriented one an affine map. Each grid also carries pliant's own metadata:
//   pliant_dims (vec3i)         the dense dims, so that empty borders come back
//   pliant_voxel_type (string)  "u8", "i16", "u16", "f32", "rgba8" or "rgba32f"
//   pliant_origin (vec3d)       the origin and the spacing, so that they come back bit for bit
//   pliant_spacing (vec3d)      (OpenVDB rounds scales when it builds a transform)
// A file written by pliant reads back with the same dims, type, spacing, origin, direction and
// values (except the colour of transparent RGBA voxels, which is 0). Writes are atomic
// (io/atomic_file.hpp); the grids are Blosc-compressed (OpenVDB's default).
//
// Read: the grid named `grid` when given, else the one named "density", else the only scalar
// float grid (FloatGrid or DoubleGrid); InvalidInput listing the file's grids when there is none
// or the choice is ambiguous. With pliant metadata the dense box is [0, pliant_dims); otherwise it
// is the bounding box of the active voxels and tiles (inactive voxels inside it are 0). A
// Vec3SGrid named "color" or "Cd" with the same transform makes the volume RGBA (rgba32f, or rgba8
// when pliant wrote it): colour from that grid, alpha from the float grid; otherwise the volume is
// scalar f32 (or the integer type pliant wrote, rounded and clamped). Transforms: any linear map
// whose steps are orthogonal (within volume::MAX_AXIS_COSINE; each axis may have its own voxel
// size); the grid is re-indexed to the nearest world axes and keeps its direction when oblique
// (volume/reorient.hpp). Frustum and other non-linear maps, and sheared linear maps, are
// Unsupported.
//
// Checks before OpenVDB sees the file: the 8-byte magic number, a file format version pliant
// reads (222 … 224), the header, the file and grid metadata (with the sizes inside
// file_delayed_load), every grid descriptor (offsets within the file) and the root tile and
// child counts of float, double and vec3s grids, because OpenVDB trusts them. The dense size is
// checked against max_bytes before allocating: from the grid's recorded bounding box
// (file_bbox_min/max, pliant_dims) and file_mem_bytes before the grid's tree is read, and from
// the tree's active bounding box after. Every OpenVDB exception becomes an IoError naming the path.
// Unsupported when pliant was built without OpenVDB.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

// False when pliant was built without OpenVDB (then the functions below throw Unsupported).
bool has_openvdb_support();

struct OpenVdbGridInfo {
    std::string name;
    std::string type;  // OpenVDB's value type name: "float", "double", "vec3s", …
};

// The grids in a .vdb file, by name (reads the header and metadata only).
std::vector<OpenVdbGridInfo> list_openvdb_grids(const std::filesystem::path& path);

// `grid`: the scalar grid to read; empty: "density", else the only float grid.
volume::Volume read_openvdb(const std::filesystem::path& path, std::size_t max_bytes,
                            const std::string& grid = {});

// InvalidInput when a dimension exceeds OpenVDB's 32-bit index range.
void write_openvdb(const std::filesystem::path& path, const volume::Volume& volume);

}  // namespace pliant::io
