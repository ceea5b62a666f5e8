// Shared pieces of the volume readers and writers (io/nrrd, io/nifti, io/raw_volume, io/inv3):
// checking declared sizes before allocating, reading raw or gzip-compressed voxel data straight
// into a Volume's bytes, writing them deflated, byte swapping. (Flips and axis swaps are
// volume::place_nearest_axes.)
//
// Every function throws IoError "<path>: <what>, expected X, got Y" for a bad file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <ostream>
#include <span>
#include <string>

#include "pliant/volume/volume.hpp"

namespace pliant::io::detail {

// deflate cannot compress by more than about 1032:1; a gzip stream of n bytes never inflates to
// more than n · MAX_INFLATE_RATIO bytes (plus a small constant).
inline constexpr std::uint64_t MAX_INFLATE_RATIO = 1032;

// Checks declared dims (each 1 … 2^31 - 1) and that dims · bytes_per_voxel(type) fits in
// max_bytes, before anything is allocated. Returns the data size in bytes. `what` names the
// header (e.g. "NRRD header").
std::size_t check_declared_size(const std::filesystem::path& path, const volume::Dims& dims,
                                volume::VoxelType type, std::size_t max_bytes);

// Size of a regular file; IoError when missing or not a regular file.
std::uint64_t file_size(const std::filesystem::path& path);

// Reads exactly out.size() bytes of `path` starting at `offset`. With `exact`, the file must end
// right after them ("more data than the header declares" otherwise). Checks the file size first.
void read_raw_data(const std::filesystem::path& path, std::uint64_t offset,
                   std::span<std::byte> out, bool exact);

// Inflates the gzip (or zlib) stream in `path` from `offset` into exactly out.size() bytes.
// Refuses before reading when the compressed size cannot hold out.size() bytes; fails when the
// stream ends early, is corrupt, or holds more data than out.size().
void read_gzip_data(const std::filesystem::path& path, std::uint64_t offset,
                    std::span<std::byte> out);

// Writes `bytes` to `out` as one gzip member (level 6).
void write_gzip(std::ostream& out, std::span<const std::byte> bytes);
// Writes `bytes` to `out` as one zlib stream (RFC 1950, level 6; MetaImage's CompressedData).
void write_zlib(std::ostream& out, std::span<const std::byte> bytes);

// Reverses the byte order of every channel (2- and 4-byte types; 1-byte types are unchanged).
void swap_channel_bytes(volume::Volume& volume);

// Writes a header-and-data volume file, each file atomically: with `data_file` empty, `header`
// followed by the data at `path`; else the data to `data_file` first, then `header` alone to
// `path` (the header names the data file). Used by the NRRD and MetaImage writers.
void write_header_and_data(const std::filesystem::path& path, const std::string& header,
                           const std::filesystem::path& data_file,
                           const std::function<void(std::ostream&)>& write_data);

// "256×256×108" for messages.
std::string dims_text(const volume::Dims& dims);

}  // namespace pliant::io::detail
