// Raw voxels + JSON sidecar, pliant's simplest volume format (docs/formats.md, "Volumes").
//
// The sidecar `<stem>.json` (strict keys: an unknown key is an error):
//   {"format": "pliant-raw-volume", "version": 1,
//    "data_file": "<stem>.raw",            relative to the sidecar's folder
//    "dims": [nx, ny, nz],                 integers ≥ 1, x fastest in the data
//    "type": "u8" | "i16" | "u16" | "f32" | "rgba8" | "rgba32f",
//    "spacing": [sx, sy, sz],              finite, > 0
//    "origin": [ox, oy, oz],               box corner (voxel centres at origin + D (i + 0.5) s)
//    "direction": [[..], [..], [..]],      optional: the world directions of the i, j, k axes
//                                          (unit, orthogonal; default identity; written only
//                                          for oriented volumes)
//    "endian": "little",                   "big" is read (swapped), never written
//    "encoding": "raw" | "gzip"}           gzip: data_file is `<stem>.raw.gz`
// The data file holds exactly nx·ny·nz voxels, channels interleaved, no header.
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

// `path`: the sidecar (.json) or the data file (.raw / .raw.gz: its sidecar is `<stem>.json`).
volume::Volume read_raw_volume(const std::filesystem::path& path, std::size_t max_bytes);

// Writes `<stem>.raw[.gz]` then `<stem>.json`, each atomically; `path` may name either.
void write_raw_volume(const std::filesystem::path& path, const volume::Volume& volume, bool gzip);

// The sidecar path for a .json/.raw/.raw.gz path.
std::filesystem::path raw_volume_sidecar(const std::filesystem::path& path);

}  // namespace pliant::io
