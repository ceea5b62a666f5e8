#include "pliant/io/metaimage.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "pliant/core/error.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using volume::Volume;
using volume::VoxelType;

constexpr std::size_t MAX = Volume::MAX_BYTES;

// 3 × 2 × 2 big-endian shorts 0 … 11, as ITK writes a header.
std::string itk_header(const std::string& extra = "", const std::string& data_file = "LOCAL") {
    return "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = True\n"
           "CompressedData = False\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = 10 20 30\n"
           "CenterOfRotation = 0 0 0\nAnatomicalOrientation = RAI\n"
           "ElementSpacing = 0.5 0.75 2\nDimSize = 3 2 2\nElementType = MET_SHORT\n" +
           extra + "ElementDataFile = " + data_file + "\n";
}

std::string big_endian_shorts(int count) {
    std::string out;
    for (int v = 0; v < count; ++v) {
        out.push_back(static_cast<char>((v >> 8) & 0xff));
        out.push_back(static_cast<char>(v & 0xff));
    }
    return out;
}

TEST(MetaImage, ReadsAnItkHeaderInLpsIntoRas) {
    TempDir dir;
    test::write_bytes(dir / "a.mha", itk_header() + big_endian_shorts(12));
    const Volume v = read_metaimage(dir / "a.mha", MAX);
    EXPECT_EQ(v.type(), VoxelType::i16);
    EXPECT_TRUE(v.is_axis_aligned());
    EXPECT_EQ(v.dims(), (volume::Dims{3, 2, 2}));
    EXPECT_EQ(v.spacing(), (Vec3d{0.5, 0.75, 2.0}));
    // LPS: i toward +L (−x in RAS), j toward +P (−y): both reversed. The first file voxel, value 0,
    // is at LPS (10, 20, 30) = RAS (−10, −20, 30): the far corner in x and y of the volume.
    const auto values = v.values<VoxelType::i16>();
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(2, 1, 0))], 0);
    EXPECT_EQ(v.voxel_center(2, 1, 0), (Vec3d{-10.0, -20.0, 30.0}));
    EXPECT_EQ(values[static_cast<std::size_t>(v.index(0, 0, 1))], 2 + 3 * 1 + 6 * 1);
}

TEST(MetaImage, ReadsDetachedDataWithHeaderSize) {
    TempDir dir;
    test::write_bytes(dir / "d.raw", std::string(7, 'x') + big_endian_shorts(12));
    test::write_bytes(dir / "d.mhd", itk_header("HeaderSize = 7\n", "d.raw"));
    const Volume v = read_metaimage(dir / "d.mhd", MAX);
    EXPECT_EQ(v.values<VoxelType::i16>()[static_cast<std::size_t>(v.index(2, 1, 0))], 0);
    test::write_bytes(dir / "t.mhd", itk_header("HeaderSize = -1\n", "d.raw"));
    EXPECT_EQ(read_metaimage(dir / "t.mhd", MAX).values<VoxelType::i16>()[0],
              v.values<VoxelType::i16>()[0]);
}

TEST(MetaImage, RoundTripsEveryTypeCompressedOrNot) {
    TempDir dir;
    for (const VoxelType type : {VoxelType::u8, VoxelType::i16, VoxelType::u16, VoxelType::f32,
                                 VoxelType::rgba8, VoxelType::rgba32f}) {
        for (const bool compressed : {false, true}) {
            for (const bool detached : {false, true}) {
                SCOPED_TRACE(std::string(volume::name(type)) + (compressed ? " zlib" : "") +
                             (detached ? " mhd" : " mha"));
                Volume v = Volume::allocate({5, 4, 3}, type, {0.3, 1.0 / 3.0, 2.5}, {-1, 2, 3.75});
                auto bytes = v.bytes();
                for (std::size_t i = 0; i < bytes.size(); ++i) {
                    bytes[i] = static_cast<std::byte>((i * 29 + 5) & 0x7f);
                }
                const auto path = dir / (detached ? "r.mhd" : "r.mha");
                write_metaimage(path, v, compressed, detached);
                const Volume back = read_metaimage(path, MAX);
                ASSERT_EQ(back.dims(), v.dims());
                ASSERT_EQ(back.type(), v.type());
                EXPECT_EQ(back.spacing(), v.spacing());
                // The file holds the first voxel's centre: origin + s / 2 − s / 2 may round.
                EXPECT_LT(norm(back.origin() - v.origin()), 1e-14);
                EXPECT_TRUE(back.is_axis_aligned());
                EXPECT_EQ(std::memcmp(back.bytes().data(), v.bytes().data(), v.size_bytes()), 0);
                if (compressed && detached) {
                    // zlib, as MetaIO writes it (not gzip): 0x78 first.
                    EXPECT_EQ(test::read_bytes(dir / "r.zraw").at(0), '\x78');
                }
            }
        }
    }
}

TEST(MetaImage, BrokenInputsNameTheFileAndTheKey) {
    TempDir dir;
    const std::string data = big_endian_shorts(12);
    const auto check = [&](const std::string& name, const std::string& bytes,
                           std::initializer_list<std::string_view> fragments) {
        test::write_bytes(dir / name, bytes);
        SCOPED_TRACE(name);
        expect_io_error([&] { read_metaimage(dir / name, MAX); }, fragments);
    };
    check("truncated.mha", itk_header() + data.substr(0, 20),
          {"truncated.mha", "truncated voxel data", "24 bytes"});
    check("extra.mha", itk_header() + data + "xx", {"more voxel data"});
    check("empty.mha", "", {"empty file"});
    check("garbage.mha", std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'),
          {"not a MetaImage header"});
    std::string wrong_dims = itk_header();
    wrong_dims.replace(wrong_dims.find("DimSize = 3 2 2"), 15, "DimSize = 3 2");
    check("dims.mha", wrong_dims + data, {"DimSize: expected 3 sizes (NDims), got 2"});
    std::string zero_spacing = itk_header();
    zero_spacing.replace(zero_spacing.find("0.5 0.75 2"), 10, "0 0.75 2");
    check("spacing.mha", zero_spacing + data, {"ElementSpacing", "> 0"});
    check("noend.mha", itk_header().substr(0, itk_header().find("ElementDataFile")),
          {"no ElementDataFile"});
    check("twice.mha", "NDims = 3\nNDims = 3\nElementDataFile = LOCAL\n", {"NDims appears twice"});
    check("missing.mhd", itk_header("", "nowhere.raw"), {"nowhere.raw", "does not exist"});
    std::string maybe = itk_header();
    maybe.replace(maybe.find("CompressedData = False"), 22, "CompressedData = maybe");
    check("bool.mha", maybe + data, {"CompressedData: expected True or False"});
    std::string compressed = itk_header();
    compressed.replace(compressed.find("CompressedData = False"), 22,
                       "CompressedData = True\nCompressedDataSize = 9999");
    check("zsize.mha", compressed + "xyz", {"CompressedDataSize is 9999"});
    compressed.replace(compressed.find("CompressedDataSize = 9999"), 25, "CompressedDataSize = 3");
    check("zcorrupt.mha", compressed + "xyz", {"zcorrupt.mha"});
    test::write_bytes(dir / "limit.mha", itk_header() + data);
    expect_io_error([&] { read_metaimage(dir / "limit.mha", 10); }, {"memory limit"});
}

TEST(MetaImage, ValidFilesPliantDoesNotReadAreUnsupported) {
    TempDir dir;
    const auto unsupported = [&](const std::string& name, const std::string& bytes,
                                 const std::string& fragment) {
        test::write_bytes(dir / name, bytes);
        try {
            read_metaimage(dir / name, MAX);
            ADD_FAILURE() << name << ": no error";
        } catch (const Unsupported& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    std::string dbl = itk_header();
    dbl.replace(dbl.find("MET_SHORT"), 9, "MET_DOUBLE");
    unsupported("double.mha", dbl, "ElementType");
    std::string ascii = itk_header();
    ascii.replace(ascii.find("BinaryData = True"), 17, "BinaryData = False");
    unsupported("ascii.mha", ascii, "BinaryData");
    unsupported("list.mhd", itk_header("", "LIST"), "ElementDataFile");
    unsupported("pattern.mhd", itk_header("", "slice%03d.raw 1 2 1"), "ElementDataFile");
    std::string four = itk_header();
    four.replace(four.find("NDims = 3"), 9, "NDims = 4");
    unsupported("four.mha", four, "NDims");
    unsupported("channels.mha", itk_header("ElementNumberOfChannels = 3\n"),
                "ElementNumberOfChannels");
    std::string sheared = itk_header();
    sheared.replace(sheared.find("1 0 0 0 1 0 0 0 1"), 17, "1 0 0 0.5 1 0 0 0 1");
    unsupported("sheared.mha", sheared, "sheared");
}

TEST(MetaImage, TwoDimensionalImagesAreOneSlice) {
    TempDir dir;
    test::write_bytes(dir / "s.mha",
                      std::string("NDims = 2\nDimSize = 2 2\nElementType = MET_UCHAR\n"
                                  "ElementSpacing = 0.5 0.25\nElementDataFile = LOCAL\n"
                                  "\x01\x02\x03\x04"));
    const Volume v = read_metaimage(dir / "s.mha", MAX);
    EXPECT_EQ(v.dims(), (volume::Dims{2, 2, 1}));
    EXPECT_EQ(v.spacing(), (Vec3d{0.5, 0.25, 1.0}));
}

}  // namespace
}  // namespace pliant::io
