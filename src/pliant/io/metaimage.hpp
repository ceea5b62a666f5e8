// MetaImage (ITK / VTK's MetaIO: .mha with the data after the header, .mhd + a data file), the
// subset pliant reads and writes.
//
// Header: `Key = Value` lines up to `ElementDataFile`, which must be the last key. Read:
//   NDims                     2 or 3 (2: one slice, nz = 1)
//   DimSize                   nx ny [nz], each ≥ 1
//   ElementType               MET_UCHAR (u8), MET_SHORT (i16), MET_USHORT (u16), MET_FLOAT (f32);
//                             with ElementNumberOfChannels = 4: MET_UCHAR → rgba8,
//                             MET_FLOAT → rgba32f; other types and channel counts Unsupported
//   ElementSpacing            sx sy [sz] > 0 (ElementSize when absent; else 1)
//   Offset (Origin, Position) the first voxel's centre (default 0)
//   TransformMatrix           (Rotation, Orientation) NDims² numbers: consecutive groups of
//                             NDims are the world directions of the i, j, k axes (ITK's
//                             direction columns); default identity
//   BinaryData                True (ASCII data, False, is Unsupported)
//   BinaryDataByteOrderMSB    (ElementByteOrderMSB) True: big endian, byte-swapped
//   CompressedData            True: a zlib (or gzip) stream; CompressedDataSize, when present,
//                             must fit in the file
//   HeaderSize                bytes to skip in a separate data file (−1: the data is the file's
//                             tail); Unsupported with LOCAL
//   ElementDataFile           LOCAL (the data follows the header line) or one file name relative
//                             to the header; LIST and file patterns are Unsupported
// Other keys (ObjectType = Image, Comment, AnatomicalOrientation, CenterOfRotation, ElementMin,
// ElementMax, Modality, user fields …) are ignored. Coordinates are ITK's physical space, LPS:
// x and y are negated into pliant's RAS+ world (on reading and on writing), so files exchanged
// with ITK, SimpleITK and 3D Slicer keep their place. The grid is re-indexed to the nearest axes
// (volume/reorient.hpp) and keeps its direction when oblique.
//
// Write: `.mha` (LOCAL) or `.mhd` + `<stem>.raw` (`<stem>.zraw` compressed), little endian, every
// voxel type (RGBA as 4 channels), TransformMatrix / Offset / ElementSpacing from the volume's
// direction, first voxel centre and spacing; CompressedData (zlib) with CompressedDataSize on
// request. Errors: IoError "<file>: <key>: <what>, expected X, got Y"; writes are atomic.
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::Volume read_metaimage(const std::filesystem::path& path, std::size_t max_bytes);

// detached: the header at `path` (.mhd) and the data in `<stem>.raw` / `<stem>.zraw` beside it.
void write_metaimage(const std::filesystem::path& path, const volume::Volume& volume,
                     bool compressed, bool detached);

}  // namespace pliant::io
