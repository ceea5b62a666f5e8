// InVesalius 3 projects (.inv3), read only: a gzip-compressed tar holding main.plist (an Apple
// XML property list) and the image matrix it names. Verified on Debian's invesalius-examples
// Cranium.inv3 (format_version 1): main.plist has
//   matrix: {dtype: "int16", filename: "matrix.dat", shape: [nz, ny, nx]}   (numpy C order)
//   spacing: [sx, sy, sz]
// and matrix.dat is nz·ny·nx little-endian int16 values, x fastest, no header. The result is an
// i16 volume with that spacing and origin (0, 0, 0); masks, surfaces and measurements are
// ignored. The tar is parsed here (ustar / GNU long names) while inflating with zlib's gzread;
// the matrix entry's size must equal the plist's shape before anything is allocated.
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::Volume read_inv3(const std::filesystem::path& path, std::size_t max_bytes);

}  // namespace pliant::io
