#include "pliant/io/checkpoint.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <ostream>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {
namespace {

constexpr std::array<char, 8> MAGIC = {'P', 'L', 'N', 'T', 'C', 'K', 'P', 'T'};

std::uint32_t crc_of(std::span<const std::byte> bytes) {
    // zlib's crc32 takes at most 2^32 - 1 bytes per call.
    uLong crc = crc32(0L, Z_NULL, 0);
    while (!bytes.empty()) {
        const std::size_t n = std::min<std::size_t>(bytes.size(), 1U << 30U);
        crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(n));
        bytes = bytes.subspan(n);
    }
    return static_cast<std::uint32_t>(crc);
}

bool is_known_kind(std::uint32_t kind) {
    return kind >= 1 && kind <= 3;
}

}  // namespace

std::string_view checkpoint_kind_name(CheckpointKind kind) {
    switch (kind) {
        case CheckpointKind::cloth:
            return "cloth";
        case CheckpointKind::deform:
            return "deform";
        case CheckpointKind::nerf:
            return "nerf";
    }
    return "unknown";
}

std::uint64_t run_fingerprint(std::string_view text) {
    std::uint64_t hash = 14695981039346656037ULL;
    for (const char c : text) {
        hash ^= static_cast<unsigned char>(c);
        hash *= 1099511628211ULL;
    }
    return hash;
}

std::uint64_t run_fingerprint(std::span<const std::byte> bytes) {
    return run_fingerprint(
        std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

std::vector<std::byte> encode_checkpoint(const Checkpoint& checkpoint) {
    ByteWriter w;
    w.put(MAGIC);
    w.put(CHECKPOINT_VERSION);
    w.put(static_cast<std::uint32_t>(checkpoint.kind));
    w.put(checkpoint.fingerprint);
    w.put(static_cast<std::uint64_t>(checkpoint.payload.size()));
    w.put_bytes(checkpoint.payload);
    const std::uint32_t crc = crc_of(w.bytes());
    w.put(crc);
    return {w.bytes().begin(), w.bytes().end()};
}

Checkpoint decode_checkpoint(std::span<const std::byte> bytes, const std::string& source) {
    if (bytes.size() < CHECKPOINT_HEADER_BYTES + 4) {
        throw InvalidInput(fmt::format(
            "{}: not a complete checkpoint: {} bytes, expected at least {} (header and CRC); "
            "the file is truncated",
            source, bytes.size(), CHECKPOINT_HEADER_BYTES + 4));
    }
    ByteReader r(bytes, source);
    const auto magic = r.get<std::array<char, 8>>("magic");
    if (magic != MAGIC) {
        throw InvalidInput(
            fmt::format("{}: not a pliant checkpoint (expected the magic \"PLNTCKPT\")", source));
    }
    const auto version = r.get<std::uint32_t>("format version");
    if (version != CHECKPOINT_VERSION) {
        throw InvalidInput(fmt::format(
            "{}: checkpoint format version {}, expected {}: written by another pliant version",
            source, version, CHECKPOINT_VERSION));
    }
    const auto kind = r.get<std::uint32_t>("kind");
    if (!is_known_kind(kind)) {
        throw InvalidInput(fmt::format(
            "{}: checkpoint kind {}, expected 1 (cloth), 2 (deform) or 3 (nerf)", source, kind));
    }
    Checkpoint checkpoint;
    checkpoint.kind = static_cast<CheckpointKind>(kind);
    checkpoint.fingerprint = r.get<std::uint64_t>("fingerprint");
    const auto payload_size = r.get<std::uint64_t>("payload size");
    if (payload_size != r.remaining() - 4) {
        throw InvalidInput(fmt::format(
            "{}: the header gives a payload of {} bytes, the file holds {} after the header "
            "(expected the payload and a 4-byte CRC); the file is truncated or corrupt",
            source, payload_size, r.remaining()));
    }
    const std::span<const std::byte> payload = r.get_bytes("payload", payload_size);
    const auto stored_crc = r.get<std::uint32_t>("CRC");
    const std::uint32_t crc = crc_of(bytes.first(bytes.size() - 4));
    if (crc != stored_crc) {
        throw InvalidInput(fmt::format(
            "{}: checksum mismatch (CRC-32 {:08x}, the file says {:08x}): the checkpoint is "
            "corrupt",
            source, crc, stored_crc));
    }
    checkpoint.payload.assign(payload.begin(), payload.end());
    return checkpoint;
}

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& checkpoint) {
    const std::vector<std::byte> bytes = encode_checkpoint(checkpoint);
    write_file_atomically(path, [&](std::ostream& s) {
        s.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
    });
}

Checkpoint read_checkpoint(const std::filesystem::path& path, CheckpointKind kind,
                           std::uint64_t fingerprint) {
    const std::string text = read_file(path);
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(text.data()),
                                           text.size());
    Checkpoint checkpoint = decode_checkpoint(bytes, path.string());
    if (checkpoint.kind != kind) {
        throw InvalidInput(fmt::format(
            "{}: a checkpoint of `pliant {}`, expected one of `pliant {}`", path.string(),
            checkpoint_kind_name(checkpoint.kind), checkpoint_kind_name(kind)));
    }
    if (checkpoint.fingerprint != fingerprint) {
        throw InvalidInput(fmt::format(
            "{}: the checkpoint belongs to another run (fingerprint {:016x}, this run's is "
            "{:016x}): the scene, its input files or the options that change the result differ; "
            "run without --resume to start over",
            path.string(), checkpoint.fingerprint, fingerprint));
    }
    return checkpoint;
}

}  // namespace pliant::io
