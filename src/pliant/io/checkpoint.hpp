// pliant's checkpoint files (DIR/checkpoint.bin): the state of a long run (cloth, deform, nerf
// train) saved so that `--resume` continues it. Format (docs/formats.md, "Checkpoints"), all
// little-endian:
//
//   offset  size  field
//   0       8     magic "PLNTCKPT"
//   8       4     format version (u32, CHECKPOINT_VERSION)
//   12      4     kind (u32: 1 cloth, 2 deform, 3 nerf)
//   16      8     fingerprint (u64: what the run belongs to, a hash of its scene, inputs and the
//                 options that change its result; run_fingerprint)
//   24      8     payload size P (u64)
//   32      P     payload (the run's own layout, core/bytes.hpp)
//   32 + P  4     CRC-32 (zlib's crc32) of bytes 0 .. 32 + P
//
// write_checkpoint writes the file atomically (io/atomic_file.hpp): a run killed while writing
// leaves the previous checkpoint. read_checkpoint checks everything above and throws
// InvalidInput "<path>: <what>" for a file that is not a complete checkpoint of the expected
// kind and fingerprint (truncated, another file, a corrupt byte, another scene or options), and
// IoError when it cannot be read.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::io {

inline constexpr std::uint32_t CHECKPOINT_VERSION = 1;
inline constexpr std::size_t CHECKPOINT_HEADER_BYTES = 32;

enum class CheckpointKind : std::uint32_t { cloth = 1, deform = 2, nerf = 3 };

// The name of a kind ("cloth", "deform", "nerf").
std::string_view checkpoint_kind_name(CheckpointKind kind);

// FNV-1a (64 bit) of `text`: the fingerprint of a run described by a canonical text or by the
// bytes of its inputs and options serialized in a fixed order (core/bytes.hpp's ByteWriter).
std::uint64_t run_fingerprint(std::string_view text);
std::uint64_t run_fingerprint(std::span<const std::byte> bytes);

struct Checkpoint {
    CheckpointKind kind = CheckpointKind::cloth;
    std::uint64_t fingerprint = 0;
    std::vector<std::byte> payload;
};

// The file's bytes (header, payload, CRC).
std::vector<std::byte> encode_checkpoint(const Checkpoint& checkpoint);
// Parses a file's bytes; `source` names it in errors. InvalidInput: see the header comment.
Checkpoint decode_checkpoint(std::span<const std::byte> bytes, const std::string& source);

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);
// Reads and checks `path`: also InvalidInput when its kind or fingerprint differ from those
// expected (a checkpoint of another command, scene or options).
Checkpoint read_checkpoint(const std::filesystem::path& path, CheckpointKind kind,
                           std::uint64_t fingerprint);

}  // namespace pliant::io
