#include "pliant/io/volume_io.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using volume::Volume;
using volume::VoxelType;

constexpr VoxelType ALL_TYPES[] = {VoxelType::u8,  VoxelType::i16,   VoxelType::u16,
                                   VoxelType::f32, VoxelType::rgba8, VoxelType::rgba32f};

// A 5×4×3 volume with distinct bytes everywhere (f32: also NaN-free random-ish patterns).
Volume sample(VoxelType type) {
    Volume v = Volume::allocate({5, 4, 3}, type, {0.5, 1.25, 2.0}, {-12.5, 3.0, 0.25});
    std::span<std::byte> b = v.bytes();
    for (std::size_t i = 0; i < b.size(); ++i) {
        b[i] = static_cast<std::byte>((i * 37 + 11) & 0x7f);  // 0x7f: float exponents finite
    }
    return v;
}

void expect_same(const Volume& a, const Volume& b) {
    EXPECT_EQ(a.dims(), b.dims());
    EXPECT_EQ(a.type(), b.type());
    EXPECT_EQ(a.spacing().x, b.spacing().x);
    EXPECT_EQ(a.spacing().y, b.spacing().y);
    EXPECT_EQ(a.spacing().z, b.spacing().z);
    EXPECT_EQ(a.origin().x, b.origin().x);
    EXPECT_EQ(a.origin().y, b.origin().y);
    EXPECT_EQ(a.origin().z, b.origin().z);
    ASSERT_EQ(a.size_bytes(), b.size_bytes());
    EXPECT_EQ(std::memcmp(a.bytes().data(), b.bytes().data(), a.size_bytes()), 0);
}

TEST(VolumeIo, RoundTripsEveryTypeAndFormat) {
    TempDir dir;
    for (const VoxelType type : ALL_TYPES) {
        for (const char* name :
             {"v.nrrd", "v.nhdr", "v.json", "v.nii", "v.nii.gz", "v.mha", "v.mhd"}) {
            for (const bool gzip : {false, true}) {
                const std::string file = name;
                const bool nifti = file.find(".nii") != std::string::npos;
                if (nifti && gzip) {
                    continue;
                }
                SCOPED_TRACE(file + " " + std::string(volume::name(type)) + (gzip ? " gzip" : ""));
                const Volume v = sample(type);
                if (nifti && type == VoxelType::rgba32f) {
                    EXPECT_THROW(write_volume(dir / file, v), Unsupported);
                    continue;
                }
                write_volume(dir / file, v, {.gzip = gzip});
                expect_same(v, read_volume(dir / file));
            }
        }
    }
}

// `v` turned by `degrees` about the axis (1, 2, 3)/|…| (an oblique placement, no axis near
// another).
Volume turned(Volume v, double degrees) {
    const double t = degrees * std::numbers::pi / 180.0;
    const Vec3d k = Vec3d{1.0, 2.0, 3.0} / std::sqrt(14.0);
    volume::Direction d{};
    for (std::size_t a = 0; a < 3; ++a) {
        Vec3d e{};
        e[static_cast<int>(a)] = 1.0;
        // Rodrigues: e cos t + (k × e) sin t + k (k · e)(1 − cos t).
        d[a] = e * std::cos(t) + cross(k, e) * std::sin(t) + k * (dot(k, e) * (1.0 - std::cos(t)));
    }
    v.set_direction(d);
    return v;
}

TEST(VolumeIo, ObliqueVolumesRoundTripWithTheirDirection) {
    TempDir dir;
    for (const char* name :
         {"o.nrrd", "o.nhdr", "o.json", "o.nii", "o.nii.gz", "o2.nii", "o.mha", "o.mhd"}) {
        const std::string file = name;
        SCOPED_TRACE(file);
        const Volume v = turned(sample(VoxelType::i16), 5.0);
        write_volume(dir / file, v, {.gzip = false, .nifti2 = file == "o2.nii"});
        const Volume back = read_volume(dir / file, {.orientation = Orientation::keep});
        ASSERT_FALSE(back.is_axis_aligned());
        ASSERT_EQ(back.dims(), v.dims());
        ASSERT_EQ(std::memcmp(back.bytes().data(), v.bytes().data(), v.size_bytes()), 0);
        // NIfTI-1 stores floats: within float rounding; the others exactly or to 1e-12.
        const double tolerance = file == "o.nii" || file == "o.nii.gz" ? 2e-5 : 1e-12;
        for (std::size_t a = 0; a < 3; ++a) {
            EXPECT_LT(norm(back.direction()[a] - v.direction()[a]), tolerance) << a;
        }
        for (const auto& corner : {std::array<std::int64_t, 3>{0, 0, 0}, {4, 3, 2}}) {
            const Vec3d p = v.voxel_center(corner[0], corner[1], corner[2]);
            const Vec3d q = back.voxel_center(corner[0], corner[1], corner[2]);
            EXPECT_LT(norm(p - q), tolerance * 100.0);
        }
    }
}

TEST(VolumeIo, ObliqueFilesAreResampledOnRequestOfTheDefault) {
    // The case that used to be refused ("only axis-aligned volumes are supported"): a NIfTI tilted
    // by 5°. Kept, it has its direction; by default it is resampled, with one info line.
    TempDir dir;
    Volume v = turned(Volume::allocate({6, 5, 4}, VoxelType::i16, {1, 1, 2}, {3, 4, 5}), 5.0);
    for (auto& x : v.values<VoxelType::i16>()) {
        x = 700;
    }
    v.values<VoxelType::i16>()[0] = -1000;
    write_volume(dir / "tilted.nii.gz", v);
    EXPECT_FALSE(
        read_volume(dir / "tilted.nii.gz", {.orientation = Orientation::keep}).is_axis_aligned());
    std::vector<std::string> infos;
    const LogSink previous = set_log_sink([&](LogLevel level, std::string_view message) {
        if (level == LogLevel::info) {
            infos.emplace_back(message);
        }
    });
    const Volume aligned = read_volume(dir / "tilted.nii.gz");
    set_log_sink(previous);
    EXPECT_TRUE(aligned.is_axis_aligned());
    ASSERT_EQ(infos.size(), 1u);
    EXPECT_NE(infos[0].find("tilted.nii.gz"), std::string::npos) << infos[0];
    EXPECT_NE(infos[0].find("resampled"), std::string::npos) << infos[0];
    EXPECT_EQ(aligned.spacing(), (Vec3d{1.0, 1.0, 1.0}));
    // Outside the turned box: the smallest value (air in CT), not 0.
    const auto values = aligned.values<VoxelType::i16>();
    EXPECT_EQ(*std::min_element(values.begin(), values.end()), -1000);
    EXPECT_EQ(*std::max_element(values.begin(), values.end()), 700);
    // It covers the turned box.
    const AABBd turned_box = v.world_bounds();
    EXPECT_LE(aligned.bounds().lo.x, turned_box.lo.x + 1e-4);
    EXPECT_GE(aligned.bounds().hi.y, turned_box.hi.y - 1e-4);
}

TEST(VolumeIo, NrrdSpaceOriginIsTheFirstVoxelCentre) {
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\n"
                                  "space directions: (2,0,0) (0,1,0) (0,0,1)\n"
                                  "space origin: (10,0,0)\nencoding: raw\n\n") +
                          std::string("\x01\x02", 2));
    const Volume v = read_volume(dir / "a.nrrd");
    EXPECT_EQ(v.origin().x, 9.0);
    EXPECT_EQ(v.spacing().x, 2.0);
    EXPECT_EQ(v.voxel_center(0, 0, 0).x, 10.0);
}

TEST(VolumeIo, NrrdNegativeDirectionFlipsAndKeepsWorldPositions) {
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\n"
                                  "space directions: (-2,0,0) (0,1,0) (0,0,1)\n"
                                  "space origin: (10,0,0)\nencoding: raw\n\n") +
                          std::string("\x01\x02", 2));
    const Volume v = read_volume(dir / "a.nrrd");
    EXPECT_EQ(v.voxel_center(0, 0, 0).x, 8.0);
    EXPECT_EQ(v.values<VoxelType::u8>()[0], 2);
    EXPECT_EQ(v.values<VoxelType::u8>()[1], 1);
}

TEST(VolumeIo, NrrdPermutedAxesAreSwappedExactly) {
    // Grid i runs along world y, j along x: axis-aligned after swapping i and j.
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 3 1\n"
                                  "space directions: (0,2,0) (1,0,0) (0,0,1)\n"
                                  "space origin: (10,20,30)\nencoding: raw\n\n") +
                          std::string("\x01\x02\x03\x04\x05\x06", 6));
    const Volume v = read_volume(dir / "a.nrrd", {.orientation = Orientation::keep});
    EXPECT_TRUE(v.is_axis_aligned());
    EXPECT_EQ(v.dims(), (volume::Dims{3, 2, 1}));
    EXPECT_EQ(v.spacing(), (Vec3d{1.0, 2.0, 1.0}));
    EXPECT_EQ(v.voxel_center(0, 0, 0), (Vec3d{10.0, 20.0, 30.0}));
    // File voxel (i, j) = byte 1 + i + 2 j sits at x = 10 + j, y = 20 + 2 i.
    const auto values = v.values<VoxelType::u8>();
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(2, 1, 0))], 1 + 1 + 2 * 2);
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(1, 0, 0))], 1 + 0 + 2 * 1);
}

TEST(VolumeIo, NrrdLpsSpaceIsConvertedToRas) {
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\n"
                                  "space: left-posterior-superior\n"
                                  "space directions: (2,0,0) (0,1,0) (0,0,1)\n"
                                  "space origin: (10,5,7)\nencoding: raw\n\n") +
                          std::string("\x01\x02", 2));
    const Volume v = read_volume(dir / "a.nrrd");
    EXPECT_TRUE(v.is_axis_aligned());
    // LPS (10, 5, 7) is RAS (−10, −5, 7); i ran toward +L = −x, so the voxels are reversed.
    EXPECT_EQ(v.voxel_center(1, 0, 0), (Vec3d{-10.0, -5.0, 7.0}));
    EXPECT_EQ(v.voxel_center(0, 0, 0), (Vec3d{-12.0, -5.0, 7.0}));
    EXPECT_EQ(v.values<VoxelType::u8>()[0], 2);
}

TEST(VolumeIo, NrrdShearIsUnsupported) {
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\n"
                      "space directions: (1,0,0) (0.3,1,0) (0,0,1)\nencoding: raw\n\nx");
    try {
        read_volume(dir / "a.nrrd");
        ADD_FAILURE() << "no error";
    } catch (const Unsupported& e) {
        EXPECT_NE(std::string(e.what()).find("sheared"), std::string::npos) << e.what();
    }
}

TEST(VolumeIo, NrrdBigEndianIsSwapped) {
    TempDir dir;
    test::write_bytes(dir / "a.nrrd",
                      std::string("NRRD0004\ntype: short\ndimension: 3\nsizes: 1 1 1\n"
                                  "endian: big\nencoding: raw\n\n") +
                          std::string("\x01\x02", 2));
    EXPECT_EQ(read_volume(dir / "a.nrrd").values<VoxelType::i16>()[0], 0x0102);
}

std::string header(const std::string& sizes, const std::string& extra = "") {
    return "NRRD0004\ntype: uchar\ndimension: 3\nsizes: " + sizes + "\n" + extra +
           "encoding: raw\n\n";
}

TEST(VolumeIo, BrokenInputs) {
    TempDir dir;
    const auto p = dir / "b.nrrd";
    test::write_bytes(p, header("2 2 2") + "abc");
    expect_io_error([&] { read_volume(p); }, {"b.nrrd", "truncated", "8 bytes"});
    test::write_bytes(p, header("2 2 2") + "abcdefghij");
    expect_io_error([&] { read_volume(p); }, {"more voxel data", "expected 8"});
    test::write_bytes(p, "NRRD0004\ntype: double\ndimension: 3\nsizes: 1 1 1\nencoding: raw\n\nx");
    EXPECT_THROW(read_volume(p), Unsupported);
    test::write_bytes(p, header("100000 100000 100000") + "x");
    expect_io_error([&] { read_volume(p); }, {"100000×100000×100000", "memory limit"});
    test::write_bytes(p, header("1 1 1", "spacings: nan 1 1\n") + "x");
    expect_io_error([&] { read_volume(p); }, {"spacing of axis 0", "finite"});
    test::write_bytes(p, header("0 1 1") + "x");
    expect_io_error([&] { read_volume(p); }, {"size of axis 0"});
    test::write_bytes(p, "");
    expect_io_error([&] { read_volume(p); }, {"empty"});
    test::write_bytes(p, std::string("\x89garbage\x00\x01", 11));
    expect_io_error([&] { read_volume(p); }, {"not a NRRD file"});
    // Lying gzip header: 1 GB declared in a few bytes.
    test::write_bytes(p,
                      "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1000 1000 1000\n"
                      "encoding: gzip\n\nxxxx");
    expect_io_error([&] { read_volume(p); }, {"compressed bytes cannot hold"});
    // Missing detached data file.
    const auto h = dir / "d.nhdr";
    test::write_bytes(h,
                      "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: raw\n"
                      "data file: nowhere.raw\n");
    expect_io_error([&] { read_volume(h); }, {"nowhere.raw", "does not exist"});
}

TEST(VolumeIo, LimitIsConfigurable) {
    TempDir dir;
    write_volume(dir / "v.nrrd", sample(VoxelType::f32));
    expect_io_error([&] { read_volume(dir / "v.nrrd", {.max_bytes = 100}); }, {"memory limit"});
}

TEST(VolumeIo, NiftiBrokenInputs) {
    TempDir dir;
    write_volume(dir / "v.nii", sample(VoxelType::i16));
    std::string bytes = test::read_bytes(dir / "v.nii");
    test::write_bytes(dir / "t.nii", bytes.substr(0, bytes.size() - 10));
    expect_io_error([&] { read_volume(dir / "t.nii"); }, {"truncated"});
    test::write_bytes(dir / "e.nii", "");
    expect_io_error([&] { read_volume(dir / "e.nii"); }, {"empty"});
    test::write_bytes(dir / "g.nii", std::string(400, 'g'));
    expect_io_error([&] { read_volume(dir / "g.nii"); },
                    {"not a NIfTI file: sizeof_hdr is 1734829927, expected 348 (NIfTI-1) or 540"});
    // Header fields that lie: checked before niftilib (which would print "** ERROR" lines).
    test::write_bytes(dir / "h.nii", bytes.substr(0, 100));
    expect_io_error([&] { read_volume(dir / "h.nii"); },
                    {"truncated NIfTI-1 header: expected 348 bytes, got 100"});
    std::string bad_ndim = bytes;
    bad_ndim[40] = 9;  // dim[0], little endian
    bad_ndim[41] = 0;
    test::write_bytes(dir / "n.nii", bad_ndim);
    expect_io_error([&] { read_volume(dir / "n.nii"); },
                    {"dim[0] out of range, expected 1 to 7, got 9"});
    std::string zero_dim = bytes;
    zero_dim[44] = 0;  // dim[2]
    zero_dim[45] = 0;
    test::write_bytes(dir / "z.nii", zero_dim);
    expect_io_error([&] { read_volume(dir / "z.nii"); }, {"dim[2] is 0, expected at least 1"});
    // Valid files keep reading, gzip too.
    write_volume(dir / "v.nii.gz", sample(VoxelType::i16));
    EXPECT_EQ(read_volume(dir / "v.nii.gz").dims(), read_volume(dir / "v.nii").dims());
}

TEST(VolumeIo, RawSidecarBrokenInputs) {
    TempDir dir;
    write_volume(dir / "v.json", sample(VoxelType::u16));
    test::write_bytes(dir / "v.raw", "abc");
    expect_io_error([&] { read_volume(dir / "v.json"); }, {"v.raw", "truncated", "120 bytes"});
    test::write_bytes(dir / "w.json", R"({"format": "pliant-raw-volume", "bogus": 1})");
    expect_io_error([&] { read_volume(dir / "w.json"); }, {"unknown key \"bogus\""});
    // A number no double holds is refused by the JSON parser (out_of_range, not parse_error).
    test::write_bytes(dir / "n.json", R"({"data_file": 88e0080000, "dims": [4, 4, 4]})");
    expect_io_error([&] { read_volume(dir / "n.json"); },
                    {"n.json", "not valid JSON", "number overflow"});
}

TEST(VolumeIo, UnknownExtensionIsUnsupported) {
    EXPECT_THROW(read_volume("volume.xyz"), Unsupported);
}

TEST(VolumeIo, ReadsColin27WhenInstalled) {
    const std::filesystem::path path = "/usr/share/mricron/templates/ch2.nii.gz";
    if (!std::filesystem::exists(path)) {
        GTEST_SKIP() << path << " absent (Debian mricron-data)";
    }
    const Volume v = read_volume(path);
    EXPECT_EQ(v.dims(), (volume::Dims{181, 217, 181}));
    EXPECT_EQ(v.type(), VoxelType::u8);
    EXPECT_NEAR(v.spacing().x, 1.0, 1e-6);
    EXPECT_NEAR(v.spacing().y, 1.0, 1e-6);
    EXPECT_NEAR(v.spacing().z, 1.0, 1e-6);
}

TEST(VolumeIo, ReadsInvesaliusCraniumWhenInstalled) {
    const std::filesystem::path path = "/usr/share/doc/invesalius-examples/examples/Cranium.inv3";
    if (!std::filesystem::exists(path)) {
        GTEST_SKIP() << path << " absent (Debian invesalius-examples)";
    }
    const Volume v = read_volume(path);
    EXPECT_EQ(v.dims(), (volume::Dims{256, 256, 108}));
    EXPECT_EQ(v.type(), VoxelType::i16);
    EXPECT_NEAR(v.spacing().x, 0.9570312, 1e-6);
    EXPECT_EQ(v.spacing().z, 1.5);
    EXPECT_EQ(v.values<VoxelType::i16>()[0], -998);  // 0xfc1a, the first bytes of matrix.dat
    expect_io_error([&] { read_volume(path, {.max_bytes = 1000}); }, {"memory limit"});
}

}  // namespace
}  // namespace pliant::io
