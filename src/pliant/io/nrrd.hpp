// NRRD (teem.sourceforge.net/nrrd/format.html), the subset pliant reads and writes.
//
// Read: magic NRRD0001…NRRD0005; attached data or detached (`data file:` relative to the header's
// folder); encodings raw and gzip; endian little or big (big is byte-swapped); types uchar, short,
// ushort, float and their synonyms (uint8, int16, unsigned short int, …); dimension 3 (scalar) or
// 4 with a leading axis of size 4 (RGBA: uchar → rgba8, float → rgba32f); `spacings` or
// `space directions` (any orthogonal directions: the volume is re-indexed to the nearest axes,
// volume/reorient.hpp, and keeps its direction when oblique; sheared directions are Unsupported);
// `space` left-posterior-superior (LPS) or left-anterior-superior is converted to pliant's RAS+
// world (LPS: x and y negated; LAS: x), any other space is taken as it is; `space origin` is the
// first voxel's centre (without it, the box corner is at the world origin). `byte skip` ≥ 0 or
// −1 (raw only). Other fields (kinds, labels, units, key/value pairs) are ignored.
//
// Write: NRRD0004, attached header (.nrrd) or detached (.nhdr + `<stem>.raw[.gz]` beside it),
// raw or gzip, little endian, `space dimension: 3` (pliant's world), `space directions`
// (diagonal for axis-aligned volumes, direction × spacing otherwise) and `space origin` (first
// voxel centre), kinds domain (RGBA-color for RGBA).
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::Volume read_nrrd(const std::filesystem::path& path, std::size_t max_bytes);

// detached: header at `path`, data in `<path without extension>.raw` (or .raw.gz).
void write_nrrd(const std::filesystem::path& path, const volume::Volume& volume, bool gzip,
                bool detached);

}  // namespace pliant::io
