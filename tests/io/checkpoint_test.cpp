// io/checkpoint.hpp and core/bytes.hpp: a checkpoint round-trips; every broken file (truncated at
// every length, any flipped byte, another magic, version, kind or fingerprint) is InvalidInput
// naming the file; ByteReader's reads are bounds-checked and name the field.
#include "pliant/io/checkpoint.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::io {
namespace {

Checkpoint sample() {
    ByteWriter w;
    w.put(std::int32_t{7});
    w.put_vector(std::vector<Vec3d>{{1, 2, 3}, {4, 5, 6}});
    w.put_string("stats");
    Checkpoint c;
    c.kind = CheckpointKind::deform;
    c.fingerprint = run_fingerprint("scene");
    c.payload.assign(w.bytes().begin(), w.bytes().end());
    return c;
}

std::string message_of(const std::vector<std::byte>& bytes) {
    try {
        decode_checkpoint(bytes, "dir/checkpoint.bin");
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

TEST(Checkpoint, RoundTripsWithTheDocumentedLayout) {
    const Checkpoint c = sample();
    const std::vector<std::byte> bytes = encode_checkpoint(c);
    ASSERT_EQ(bytes.size(), CHECKPOINT_HEADER_BYTES + c.payload.size() + 4);
    EXPECT_EQ(std::memcmp(bytes.data(), "PLNTCKPT", 8), 0);
    std::uint32_t version = 0, kind = 0, crc = 0;
    std::uint64_t fingerprint = 0, payload_size = 0;
    std::memcpy(&version, bytes.data() + 8, 4);
    std::memcpy(&kind, bytes.data() + 12, 4);
    std::memcpy(&fingerprint, bytes.data() + 16, 8);
    std::memcpy(&payload_size, bytes.data() + 24, 8);
    std::memcpy(&crc, bytes.data() + bytes.size() - 4, 4);
    EXPECT_EQ(version, CHECKPOINT_VERSION);
    EXPECT_EQ(kind, 2u);
    EXPECT_EQ(fingerprint, c.fingerprint);
    EXPECT_EQ(payload_size, c.payload.size());
    // zlib's CRC-32 of everything before it, computed here independently.
    EXPECT_EQ(crc,
              static_cast<std::uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()),
                                               static_cast<uInt>(bytes.size() - 4))));
    const Checkpoint back = decode_checkpoint(bytes, "x");
    EXPECT_EQ(back.kind, c.kind);
    EXPECT_EQ(back.fingerprint, c.fingerprint);
    EXPECT_EQ(back.payload, c.payload);

    ByteReader r(back.payload, "x");
    EXPECT_EQ(r.get<std::int32_t>("frame"), 7);
    std::vector<Vec3d> v;
    r.get_vector("positions", v, 2);
    EXPECT_EQ(v[1], (Vec3d{4, 5, 6}));
    EXPECT_EQ(r.get_string("stats"), "stats");
    r.expect_end();
}

TEST(Checkpoint, EveryTruncationAndFlippedByteIsRefused) {
    const std::vector<std::byte> bytes = encode_checkpoint(sample());
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        const std::vector<std::byte> cut(bytes.begin(), bytes.begin() + static_cast<long>(n));
        const std::string message = message_of(cut);
        EXPECT_NE(message.find("dir/checkpoint.bin"), std::string::npos) << n << ": " << message;
    }
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::vector<std::byte> flipped = bytes;
        flipped[i] ^= std::byte{0x10};
        EXPECT_NE(message_of(flipped), "") << "byte " << i;
    }
    std::vector<std::byte> longer = bytes;
    longer.push_back(std::byte{0});
    EXPECT_NE(message_of(longer).find("truncated or corrupt"), std::string::npos);
}

TEST(Checkpoint, FileOfAnotherKindOrRunIsRefused) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                      ("pliant_checkpoint_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::filesystem::path path = dir / "checkpoint.bin";
    const Checkpoint c = sample();
    write_checkpoint(path, c);
    EXPECT_EQ(read_checkpoint(path, CheckpointKind::deform, c.fingerprint).payload, c.payload);
    try {
        read_checkpoint(path, CheckpointKind::cloth, c.fingerprint);
        ADD_FAILURE();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("pliant deform"), std::string::npos) << e.what();
    }
    try {
        read_checkpoint(path, CheckpointKind::deform, run_fingerprint("another scene"));
        ADD_FAILURE();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("belongs to another run"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos);
    }
    EXPECT_THROW(read_checkpoint(dir / "missing.bin", CheckpointKind::deform, 0), IoError);
    std::filesystem::remove_all(dir);
}

TEST(ByteReader, ReadsAreBoundsCheckedAndNameTheField) {
    ByteWriter w;
    w.put(std::uint64_t{1} << 60);  // a count far beyond the buffer
    w.put(std::uint8_t{2});
    ByteReader r(w.bytes(), "state.bin");
    std::vector<double> values;
    try {
        r.get_vector("velocities", values);
        ADD_FAILURE();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("state.bin: velocities: truncated"), std::string::npos)
            << e.what();
    }
    ByteReader flags(w.bytes().subspan(8), "state.bin");
    EXPECT_THROW(flags.get_bool("has_grab"), InvalidInput);  // 2 is no boolean
    ByteReader short_read(w.bytes().first(3), "state.bin");
    EXPECT_THROW(short_read.get<double>("time"), InvalidInput);
    ByteWriter counted;
    counted.put_vector(std::vector<float>{1, 2, 3});
    ByteReader wrong_count(counted.bytes(), "state.bin");
    EXPECT_THROW(wrong_count.get_vector("rest_lengths", values, 4), InvalidInput);
    ByteReader left_over(counted.bytes(), "state.bin");
    left_over.get<std::uint64_t>("count");
    EXPECT_THROW(left_over.expect_end(), InvalidInput);
}

}  // namespace
}  // namespace pliant::io
