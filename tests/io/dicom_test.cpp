#include "pliant/io/dicom.hpp"

#include <gdcmImageReader.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "io/dicom_series.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/volume_io.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

namespace fs = std::filesystem;
using pliant::test::DicomSeriesSpec;
using test::expect_io_error;
using test::TempDir;
using volume::Volume;
using volume::VoxelType;

// Runs f, expects InvalidInput whose message holds every fragment.
template <typename F>
void expect_invalid(F&& f, std::initializer_list<std::string> fragments) {
    try {
        f();
        ADD_FAILURE() << "expected InvalidInput, nothing was thrown";
    } catch (const InvalidInput& e) {
        for (const std::string& fragment : fragments) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
                << "message: " << e.what() << "\nmissing: " << fragment;
        }
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected InvalidInput, got: " << e.what();
    }
}

// Every file voxel (i, j, k) of the spec is in `v` at its world position (DICOM LPS converted to
// RAS) with its phantom value in HU.
void expect_phantom(const Volume& v, const DicomSeriesSpec& spec) {
    const auto& o = spec.orientation;
    const Vec3d row{o[0], o[1], o[2]};
    const Vec3d column{o[3], o[4], o[5]};
    const std::array<double, 3> nn = pliant::test::slice_normal(spec);
    const Vec3d normal{nn[0], nn[1], nn[2]};
    const Vec3d p0{spec.position0[0], spec.position0[1], spec.position0[2]};
    const volume::Direction& d = v.direction();
    const auto value = [&](std::int64_t index) {
        switch (v.type()) {
            case VoxelType::i16:
                return static_cast<double>(
                    v.values<VoxelType::i16>()[static_cast<std::size_t>(index)]);
            case VoxelType::f32:
                return static_cast<double>(
                    v.values<VoxelType::f32>()[static_cast<std::size_t>(index)]);
            default:
                ADD_FAILURE() << "unexpected type " << volume::name(v.type());
                return 0.0;
        }
    };
    for (int k = 0; k < spec.slices; ++k) {
        for (int j = 0; j < spec.rows; ++j) {
            for (int i = 0; i < spec.columns; ++i) {
                const Vec3d lps = p0 + row * (i * spec.column_spacing) +
                                  column * (j * spec.row_spacing) + normal * (k * spec.slice_step);
                const Vec3d world{-lps.x, -lps.y, lps.z};
                std::array<std::int64_t, 3> index{};
                for (std::size_t a = 0; a < 3; ++a) {
                    const double u =
                        dot(d[a], world - v.origin()) / v.spacing()[static_cast<int>(a)] - 0.5;
                    index[a] = std::lround(u);
                    ASSERT_NEAR(u, static_cast<double>(index[a]), 1e-6)
                        << i << " " << j << " " << k;
                    ASSERT_GE(index[a], 0);
                    ASSERT_LT(index[a], v.dims()[a]);
                }
                ASSERT_EQ(value(v.index(index[0], index[1], index[2])),
                          pliant::test::phantom_hu(spec, i, j, k))
                    << i << " " << j << " " << k;
            }
        }
    }
}

TEST(Dicom, CtSeriesInShuffledOrderReadsInHounsfieldUnits) {
    TempDir dir;
    const DicomSeriesSpec spec;
    pliant::test::write_dicom_series(dir / "ct", spec, 3);
    const Volume v = read_dicom_series(dir / "ct");
    EXPECT_EQ(v.type(), VoxelType::i16);
    EXPECT_EQ(v.dims(), (volume::Dims{32, 32, 16}));
    EXPECT_EQ(v.spacing(), (Vec3d{0.7, 0.8, 2.5}));
    EXPECT_TRUE(v.is_axis_aligned());  // axial LPS: i and j reversed into RAS, exactly
    const auto values = v.values<VoxelType::i16>();
    EXPECT_EQ(*std::min_element(values.begin(), values.end()), -1024);
    EXPECT_EQ(*std::max_element(values.begin(), values.end()), 1500);
    expect_phantom(v, spec);
    // The same through read_volume, a file of the series, and an explicit list.
    EXPECT_EQ(volume_format(dir / "ct"), VolumeFormat::dicom);
    const Volume by_dispatch = read_volume(dir / "ct");
    ASSERT_EQ(by_dispatch.size_bytes(), v.size_bytes());
    EXPECT_EQ(std::memcmp(by_dispatch.bytes().data(), v.bytes().data(), v.size_bytes()), 0);
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir / "ct")) {
        files.push_back(entry.path());
    }
    const Volume by_file = read_volume(files[5]);
    const Volume by_list = read_dicom_series(files);
    EXPECT_EQ(by_file.origin(), v.origin());
    EXPECT_EQ(std::memcmp(by_list.bytes().data(), v.bytes().data(), v.size_bytes()), 0);
    // A Part-10 file without an extension is recognised by its DICM marker.
    fs::copy_file(files[0], dir / "IM0001");
    EXPECT_EQ(volume_format(dir / "IM0001"), VolumeFormat::dicom);
}

TEST(Dicom, CompressedTransferSyntaxesReadTheSameVoxels) {
    TempDir dir;
    DicomSeriesSpec spec;
    spec.slices = 6;
    pliant::test::write_dicom_series(dir / "plain", spec, 4);
    const Volume plain = read_dicom_series(dir / "plain");
    for (const auto syntax :
         {gdcm::TransferSyntax::RLELossless, gdcm::TransferSyntax::JPEGLSLossless,
          gdcm::TransferSyntax::JPEG2000Lossless, gdcm::TransferSyntax::JPEGLosslessProcess14_1}) {
        const std::string name = gdcm::TransferSyntax::GetTSString(syntax);
        SCOPED_TRACE(name);
        spec.syntax = syntax;
        pliant::test::write_dicom_series(dir / name, spec, 5);
        const Volume v = read_dicom_series(dir / name);
        ASSERT_EQ(v.dims(), plain.dims());
        EXPECT_EQ(v.origin(), plain.origin());
        EXPECT_EQ(std::memcmp(v.bytes().data(), plain.bytes().data(), v.size_bytes()), 0);
    }
}

TEST(Dicom, TiltedSeriesKeepsItsDirectionOrIsResampled) {
    TempDir dir;
    DicomSeriesSpec spec;
    const double t = 5.0 * std::numbers::pi / 180.0;
    spec.orientation = {1, 0, 0, 0, std::cos(t), std::sin(t)};
    pliant::test::write_dicom_series(dir / "tilted", spec, 6);
    const Volume v = read_volume(dir / "tilted", {.orientation = Orientation::keep});
    ASSERT_FALSE(v.is_axis_aligned());
    EXPECT_NEAR(v.spacing().x, 0.7, 1e-12);
    EXPECT_NEAR(v.spacing().z, 2.5, 1e-9);
    // LPS row (1, 0, 0), column (0, c, s), normal (0, −s, c) → RAS (−1, 0, 0), (0, −c, s),
    // (0, s, c); the first two reversed by the re-indexing.
    const volume::Direction& d = v.direction();
    EXPECT_LT(norm(d[0] - Vec3d{1, 0, 0}), 1e-9);
    EXPECT_LT(norm(d[1] - Vec3d{0, std::cos(t), -std::sin(t)}), 1e-9);
    EXPECT_LT(norm(d[2] - Vec3d{0, std::sin(t), std::cos(t)}), 1e-9);
    expect_phantom(v, spec);
    // By default: resampled onto an axis-aligned grid covering it, air outside.
    const Volume aligned = read_volume(dir / "tilted");
    EXPECT_TRUE(aligned.is_axis_aligned());
    EXPECT_EQ(aligned.type(), VoxelType::i16);
    const auto values = aligned.values<VoxelType::i16>();
    EXPECT_EQ(*std::min_element(values.begin(), values.end()), -1024);
    EXPECT_EQ(*std::max_element(values.begin(), values.end()), 1500);
}

TEST(Dicom, SeveralSeriesInOneFolder) {
    TempDir dir;
    DicomSeriesSpec big;
    big.description = "abdomen";
    pliant::test::write_dicom_series(dir / "mixed", big, 7);
    DicomSeriesSpec scout;
    scout.slices = 4;
    scout.description = "scout";
    scout.modality = "CT";
    scout.series_uid = "1.2.3.4.5.6.7";
    pliant::test::write_dicom_series(dir / "mixed" / "sub", scout, 8);  // a subfolder: found too

    const std::vector<DicomSeriesInfo> all = list_dicom_series(dir / "mixed");
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].description, "abdomen");
    EXPECT_EQ(all[0].num_files, 16);
    EXPECT_EQ(all[0].dims, (volume::Dims{32, 32, 16}));
    EXPECT_EQ(all[0].modality, "CT");
    EXPECT_EQ(all[1].uid, "1.2.3.4.5.6.7");
    EXPECT_EQ(all[1].num_files, 4);
    EXPECT_EQ(chosen_dicom_series(dir / "mixed", ""), all[0].uid);

    std::vector<std::string> infos;
    const LogSink previous = set_log_sink([&](LogLevel level, std::string_view message) {
        if (level == LogLevel::info) {
            infos.emplace_back(message);
        }
    });
    const Volume largest = read_dicom_series(dir / "mixed");
    set_log_sink(previous);
    EXPECT_EQ(largest.dims()[2], 16);
    ASSERT_EQ(infos.size(), 1u);
    EXPECT_NE(infos[0].find("2 DICOM series"), std::string::npos) << infos[0];
    EXPECT_NE(infos[0].find("1.2.3.4.5.6.7"), std::string::npos) << infos[0];
    EXPECT_NE(infos[0].find("--series"), std::string::npos) << infos[0];

    const Volume other = read_volume(dir / "mixed", {.series_uid = "1.2.3.4.5.6.7"});
    EXPECT_EQ(other.dims(), (volume::Dims{32, 32, 4}));
    expect_invalid([&] { read_dicom_series(dir / "mixed", {.series_uid = "9.9"}); },
                   {"no DICOM series with UID 9.9", "1.2.3.4.5.6.7", "abdomen"});
}

TEST(Dicom, BrokenSeriesNameTheFiles) {
    TempDir dir;
    const DicomSeriesSpec spec;
    {
        // A missing middle slice.
        const std::vector<fs::path> files =
            pliant::test::write_dicom_series(dir / "missing", spec, 9);
        fs::remove(files[7]);
        expect_invalid([&] { read_dicom_series(dir / "missing"); },
                       {"1 slice missing between", files[6].filename().string(),
                        files[8].filename().string(), "5 mm apart", "2.5 mm"});
    }
    {
        // Uneven spacing: 2.5 mm, then 3.2 mm between slices 7 and 8.
        std::vector<double> positions;
        for (int k = 0; k < spec.slices; ++k) {
            positions.push_back(k * 2.5 + (k >= 8 ? 0.7 : 0.0));
        }
        const std::vector<fs::path> files =
            pliant::test::write_dicom_series(dir / "uneven", spec, 10, positions);
        expect_invalid([&] { read_dicom_series(dir / "uneven"); },
                       {"uneven slice spacing", "2.5 mm between", "3.2 mm between",
                        files[7].filename().string(), files[8].filename().string()});
    }
    {
        // A slice of another size in the series.
        const std::vector<fs::path> files =
            pliant::test::write_dicom_series(dir / "sizes", spec, 11);
        DicomSeriesSpec small = spec;
        small.columns = 16;
        const std::string uid = list_dicom_series(dir / "sizes").front().uid;
        pliant::test::write_dicom_slice(files[5], small, uid, "1.2.3", 5, 5 * 2.5, 6);
        expect_invalid([&] { read_dicom_series(dir / "sizes"); },
                       {"mixed sizes", files[5].filename().string(), "16x32", "32x32"});
    }
    {
        // Two slices at one position.
        const std::vector<fs::path> files =
            pliant::test::write_dicom_series(dir / "twice", spec, 12);
        const std::string uid = list_dicom_series(dir / "twice").front().uid;
        pliant::test::write_dicom_slice(dir / "twice" / "copy.dcm", spec, uid, "1.2.3", 3, 3 * 2.5,
                                        99);
        expect_invalid([&] { read_dicom_series(dir / "twice"); },
                       {"two slices at one position", "copy.dcm"});
    }
    // No DICOM at all, a non-DICOM file, a folder that is not there.
    fs::create_directories(dir / "empty");
    expect_io_error([&] { read_dicom_series(dir / "empty"); }, {"empty", "no DICOM image"});
    fs::create_directories(dir / "garbage");
    test::write_bytes(dir / "garbage" / "a.dcm", std::string(300, 'x'));
    expect_io_error([&] { read_dicom_series(dir / "garbage"); }, {"no DICOM image", "1 candidate"});
    const std::vector<fs::path> listed{dir / "garbage" / "a.dcm"};
    expect_io_error([&] { read_dicom_series(listed); }, {"a.dcm", "not a DICOM file"});
    expect_io_error([&] { read_dicom_series(dir / "nowhere"); }, {"nowhere", "no such"});
    // The memory limit, before any pixel data is read.
    pliant::test::write_dicom_series(dir / "limit", spec, 13);
    expect_io_error(
        [&] { read_dicom_series(dir / "limit", {.series_uid = "", .max_bytes = 1000}); },
        {"memory limit"});
}

// Lengths GDCM would allocate before reading (fuzz_dicom: a 972-byte file whose element
// (0010,0040) had VR bytes 0xBAAC made GDCM allocate 4 GB) are refused before GDCM sees the file.
TEST(Dicom, ElementLengthsBeyondTheFileAreRefusedBeforeGdcmReadsThem) {
    TempDir dir;
    const DicomSeriesSpec spec;
    const std::vector<fs::path> files = pliant::test::write_dicom_series(dir / "s", spec, 14);
    const std::string bytes = test::read_bytes(files[0]);
    // Modality (0008,0060), explicit VR CS: a VR that is not two letters and a 64 KiB length.
    const std::string modality(
        "\x08\x00\x60\x00"
        "CS",
        6);
    const std::size_t at = bytes.find(modality);
    ASSERT_NE(at, std::string::npos);
    std::string bad_vr = bytes;
    bad_vr.replace(at + 4, 4, std::string("\xBA\xAC\xFF\xFF", 4));
    test::write_bytes(dir / "bad_vr.dcm", bad_vr);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "bad_vr.dcm"}); },
                    {"bad_vr.dcm", "not a DICOM file", "(0008,0060)", "0xBAAC"});
    // Two capital letters that are no VR, in the file meta group (fuzz_dicom: "KH" in
    // (0002,0013) made GDCM assert, gdcmFileMetaInformation.cxx:436).
    const std::size_t version = bytes.find(std::string("\x02\x00\x13\x00SH", 6));
    ASSERT_NE(version, std::string::npos);
    std::string unknown_vr = bytes;
    unknown_vr.replace(version + 4, 2, "KH");
    test::write_bytes(dir / "unknown_vr.dcm", unknown_vr);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "unknown_vr.dcm"}); },
        {"unknown_vr.dcm", "element (0002,0013)", "has VR 'KH', which DICOM does not define"});
    // A Recognition Code (0008,0010) other than ACR-NEMA's (fuzz_dicom: GDCM asserted).
    const std::size_t study_time = bytes.find(std::string("\x08\x00\x30\x00TM", 6));
    ASSERT_NE(study_time, std::string::npos);
    std::string recognition = bytes;
    recognition[study_time + 2] = '\x10';
    test::write_bytes(dir / "recognition.dcm", recognition);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "recognition.dcm"}); },
        {"recognition.dcm", "Recognition Code (0008,0010) at byte", "expected ACR-NEMA"});
    // Number of Frames 0, inserted before Rows (GDCM asserts that it is not 0).
    const std::size_t rows = bytes.find(std::string("\x28\x00\x10\x00US", 6));
    ASSERT_NE(rows, std::string::npos);
    std::string no_frames = bytes;
    no_frames.insert(rows, std::string("\x28\x00\x08\x00IS\x02\x00"
                                       "0 ",
                                       10));
    test::write_bytes(dir / "frames.dcm", no_frames);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "frames.dcm"}); },
        {"frames.dcm", "Number of Frames (0028,0008) is '0'", "expected a positive integer"});
    // Image Position (0020,0032) with VR PN (fuzz_dicom: gdcm::Attribute asserted on the VR).
    const std::size_t position =
        bytes.find(std::string("\x20\x00\x32\x00"
                               "DS",
                               6));
    ASSERT_NE(position, std::string::npos);
    std::string pn = bytes;
    pn.replace(position + 4, 2, "PN");
    test::write_bytes(dir / "pn.dcm", pn);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "pn.dcm"}); },
                    {"pn.dcm", "element (0020,0032)", "has VR 'PN', expected DS"});
    // Samples per Pixel 2 (fuzz_dicom: GDCM asserted, gdcmPixelFormat.h:96).
    const std::size_t samples = bytes.find(std::string("\x28\x00\x02\x00US\x02\x00", 8));
    ASSERT_NE(samples, std::string::npos);
    std::string two_samples = bytes;
    two_samples[samples + 8] = 2;
    test::write_bytes(dir / "samples.dcm", two_samples);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "samples.dcm"}); },
        {"samples.dcm", "Samples per Pixel (0028,0002) at byte", "is 2, expected 1, 3 or 4"});
    // Pixel data (7FE0,0010), explicit VR OW: a length of 4 GB in a file of a few KB.
    const std::string pixels("\xE0\x7F\x10\x00OW\0\0", 8);
    const std::size_t p = bytes.rfind(pixels);
    ASSERT_NE(p, std::string::npos);
    std::string long_pixels = bytes;
    long_pixels.replace(p + 8, 4, std::string("\xF0\xFF\xFF\xFF", 4));
    test::write_bytes(dir / "long.dcm", long_pixels);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "long.dcm"}); },
                    {"long.dcm", "(7FE0,0010)", "declares 4294967280 bytes"});
    // RLE pixel data whose header declares 26,114 segments (fuzz_dicom: GDCM read out of
    // bounds): the first fragment's 64-byte header follows the empty offset table item.
    DicomSeriesSpec rle_spec = spec;
    rle_spec.syntax = gdcm::TransferSyntax::RLELossless;
    const std::vector<fs::path> rle_files =
        pliant::test::write_dicom_series(dir / "rle", rle_spec, 15);
    std::string rle = test::read_bytes(rle_files[0]);
    const std::string fragments("\xFE\xFF\x00\xE0\0\0\0\0\xFE\xFF\x00\xE0", 12);
    const std::size_t r = rle.find(fragments);
    ASSERT_NE(r, std::string::npos);
    rle.replace(r + 16, 4, std::string("\x02\x66\0\0", 4));
    test::write_bytes(dir / "rle.dcm", rle);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "rle.dcm"}); },
                    {"rle.dcm", "declares 26114 segments, expected 1 to 15"});
    // Bits Allocated 4624 in an RLE file (fuzz_dicom: GDCM's RLE decoder asserted).
    const std::size_t bits = rle.find(std::string("\x28\x00\x00\x01US\x02\x00", 8));
    ASSERT_NE(bits, std::string::npos);
    std::string odd_bits = test::read_bytes(rle_files[0]);
    odd_bits.replace(bits + 8, 2, std::string("\x10\x12", 2));
    test::write_bytes(dir / "bits.dcm", odd_bits);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "bits.dcm"}); },
        {"bits.dcm", "Bits Allocated (0028,0100) at byte", "is 4624, expected 8, 16 or 32 (RLE)"});
    // A fragment whose item tag is mutated to (FFFE,9696) with 2.5 GB (fuzz_dicom: GDCM
    // allocated the length): the items of encapsulated pixel data are walked too.
    std::string fragment_tag = test::read_bytes(rle_files[0]);
    fragment_tag.replace(r + 10, 6, std::string("\x96\x96\x96\x96\x96\x96", 6));
    test::write_bytes(dir / "fragment.dcm", fragment_tag);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "fragment.dcm"}); },
                    {"fragment.dcm", "pixel data fragment 1 at byte", "has tag (FFFE,9696)",
                     "expected an item (FFFE,E000) or the delimiter (FFFE,E0DD)"});
    // The delimiter after the fragments with a length (fuzz_dicom: GDCM read 0xF7000000 bytes).
    std::string delimiter = test::read_bytes(rle_files[0]);
    const std::size_t end = delimiter.rfind(std::string("\xFE\xFF\xDD\xE0\0\0\0\0", 8));
    ASSERT_NE(end, std::string::npos);
    delimiter[end + 7] = '\xF7';
    test::write_bytes(dir / "delimiter.dcm", delimiter);
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "delimiter.dcm"}); },
        {"delimiter.dcm", "delimiter (FFFE,E0DD) at byte", "declares 4143972352 bytes"});
    // A JPEG lossless fragment whose second header marker starts with 0xF5 instead of 0xFF
    // (fuzz_dicom: a libjpeg warning, on which GDCM's JPEG codec asserts).
    DicomSeriesSpec jpeg_spec = spec;
    jpeg_spec.syntax = gdcm::TransferSyntax::JPEGLosslessProcess14_1;
    std::string jpeg =
        test::read_bytes(pliant::test::write_dicom_series(dir / "jpeg", jpeg_spec, 17)[0]);
    const std::size_t soi = jpeg.find(std::string("\xFF\xD8\xFF", 3));
    ASSERT_NE(soi, std::string::npos);
    const std::size_t first = soi + 2;  // the first marker after SOI, then its length
    const std::size_t second = first + 2 +
                               (static_cast<unsigned char>(jpeg[first + 2]) << 8 |
                                static_cast<unsigned char>(jpeg[first + 3]));
    jpeg[second] = '\xF5';
    test::write_bytes(dir / "jpeg.dcm", jpeg);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "jpeg.dcm"}); },
                    {"jpeg.dcm", "the JPEG pixel data fragment at byte",
                     "has byte 0xF5 at JPEG offset", "expected a marker"});
    // In a folder such files are skipped, the good ones still read.
    fs::copy_file(dir / "long.dcm", dir / "s" / "zz_long.dcm");
    EXPECT_EQ(read_dicom_series(dir / "s").dims()[2], spec.slices);
}

// A data element header cut short at the end of the file (fuzz_dicom,
// fuzz/findings/dicom/crash-gdcm-vr16-assert: 4 zero bytes after the pixel data) made GDCM
// 3.0.21 abort in an assertion (gdcmVR16ExplicitDataElement.txx:46): it is refused first.
TEST(Dicom, HeaderCutShortAtTheEndIsRefusedBeforeGdcmReadsIt) {
    TempDir dir;
    const DicomSeriesSpec spec;
    const std::vector<fs::path> files = pliant::test::write_dicom_series(dir / "s", spec, 16);
    const std::string bytes = test::read_bytes(files[0]);
    // The finding's tail: a tag (0000,0000) and nothing after it.
    test::write_bytes(dir / "tail4.dcm", bytes + std::string(4, '\0'));
    expect_io_error(
        [&] { read_dicom_series(std::vector<fs::path>{dir / "tail4.dcm"}); },
        {"tail4.dcm", "not a DICOM file pliant can read",
         "data element at byte " + std::to_string(bytes.size()) + " is cut short: 4 bytes left"});
    // A tag and a VR, no length.
    test::write_bytes(dir / "tail7.dcm", bytes + std::string("\x08\x00\x70\x00LO\x00", 7));
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "tail7.dcm"}); },
                    {"tail7.dcm", "cut short: 7 bytes left"});
    // The file meta group alone (fuzz_dicom: GDCM asserted reading past it): the preamble, "DICM",
    // the 12-byte group length element, then the group's length in bytes.
    const std::size_t group_length =
        static_cast<unsigned char>(bytes[140]) |
        static_cast<std::size_t>(static_cast<unsigned char>(bytes[141])) << 8;
    const std::string meta = bytes.substr(0, 144 + group_length);
    test::write_bytes(dir / "meta_only.dcm", meta);
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{dir / "meta_only.dcm"}); },
                    {"meta_only.dcm", "ends after its file meta group", "no data set"});
    // The fuzzer's file itself (a CT slice written by GDCM, mutated).
    const fs::path finding =
        fs::path(PLIANT_SOURCE_DIR) / "fuzz" / "findings" / "dicom" / "crash-gdcm-vr16-assert";
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{finding}); },
                    {"crash-gdcm-vr16-assert", "not a DICOM file pliant can read",
                     "byte 972 is cut short: 4 bytes left"});
    // In a folder it is skipped; the good slices still read.
    fs::copy_file(dir / "tail4.dcm", dir / "s" / "zz_tail4.dcm");
    EXPECT_EQ(read_dicom_series(dir / "s").dims()[2], spec.slices);
}

TEST(Dicom, FractionalRescaleGivesFloats) {
    TempDir dir;
    DicomSeriesSpec spec;
    spec.slices = 3;
    spec.slope = 0.5;
    spec.intercept = -1024.0;
    pliant::test::write_dicom_series(dir / "f", spec, 14);
    const Volume v = read_dicom_series(dir / "f");
    EXPECT_EQ(v.type(), VoxelType::f32);
    expect_phantom(v, spec);
}

}  // namespace
}  // namespace pliant::io

namespace pliant::io {
namespace {

// Every input fuzz_dicom found (fuzz/findings/dicom/: GDCM assertions, out-of-memory, a leak) is
// an IoError or InvalidInput naming the file, read alone; among the slices of a valid series in
// a folder they are skipped and the series reads as before, bitwise. GDCM parses each file in a
// child process (io/forked_call.hpp), so what the walk of io/dicom.cpp does not refuse first
// (oom-f0432a…: a 4.28 GB allocation) ends the child, not the test.
TEST(Dicom, EveryFuzzFindingIsAnErrorAndIsSkippedInAFolder) {
    TempDir dir;
    DicomSeriesSpec spec;
    spec.slices = 5;
    pliant::test::write_dicom_series(dir / "clean", spec, 21);
    const Volume clean = read_dicom_series(dir / "clean");
    fs::copy(dir / "clean", dir / "mixed");
    const fs::path findings = fs::path(PLIANT_SOURCE_DIR) / "fuzz" / "findings" / "dicom";
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(findings)) {
        files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    ASSERT_GE(files.size(), 12U);
    for (const fs::path& file : files) {
        SCOPED_TRACE(file.filename().string());
        try {
            read_dicom_series(std::vector<fs::path>{file});
            ADD_FAILURE() << "read without an error";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(file.filename().string()), std::string::npos)
                << e.what();
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(file.filename().string()), std::string::npos)
                << e.what();
        }
        fs::copy_file(file, dir / "mixed" / (file.filename().string() + ".dcm"));
    }
    const Volume mixed = read_dicom_series(dir / "mixed");
    ASSERT_EQ(mixed.dims(), clean.dims());
    ASSERT_EQ(mixed.size_bytes(), clean.size_bytes());
    EXPECT_EQ(std::memcmp(mixed.bytes().data(), clean.bytes().data(), clean.size_bytes()), 0);
}

// The finding the walk lets through: GDCM's fallback re-read as mixed explicit/implicit VR takes
// VR bytes for a 4,277,910,206-byte length. Its child process may map 512 MiB beyond what it
// starts with (more under AddressSanitizer), so the allocation fails at once and the file is
// reported as not parsed.
TEST(Dicom, GdcmsHugeAllocationEndsInItsChildProcess) {
    const fs::path finding = fs::path(PLIANT_SOURCE_DIR) / "fuzz" / "findings" / "dicom" /
                             "oom-f0432a152e206f03d28fa2ca28e61129828144c4";
    expect_io_error([&] { read_dicom_series(std::vector<fs::path>{finding}); },
                    {"oom-f0432a152e206f03d28fa2ca28e61129828144c4", "GDCM"});
    expect_io_error([&] { list_dicom_series(std::vector<fs::path>{finding}); },
                    {"oom-f0432a152e206f03d28fa2ca28e61129828144c4", "GDCM"});
}

}  // namespace
}  // namespace pliant::io

namespace pliant::io {
namespace {

// One multi-frame file (8 x 6 x 4 unsigned 16-bit values i + 10 j + 100 k): its geometry and
// its pixels each come from a GDCM child process; both as GDCM reads them in this process.
TEST(Dicom, MultiFrameFileReadsWholeWithGdcmsGeometry) {
    TempDir dir;
    gdcm::Trace::WarningOff();  // GDCM notes on stderr what the writer fills in itself
    const std::array<unsigned, 3> dims{8, 6, 4};
    gdcm::SmartPointer<gdcm::Image> image = new gdcm::Image;
    image->SetNumberOfDimensions(3);
    for (unsigned a = 0; a < 3; ++a) {
        image->SetDimension(a, dims[a]);
    }
    image->SetPixelFormat(gdcm::PixelFormat::UINT16);
    image->SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    image->SetOrigin(0, -20.0);
    image->SetOrigin(1, 10.0);
    image->SetOrigin(2, 30.0);
    image->SetSpacing(0, 0.5);
    image->SetSpacing(1, 0.75);
    image->SetSpacing(2, 1.5);
    std::vector<std::uint16_t> pixels;
    for (unsigned k = 0; k < dims[2]; ++k) {
        for (unsigned j = 0; j < dims[1]; ++j) {
            for (unsigned i = 0; i < dims[0]; ++i) {
                pixels.push_back(static_cast<std::uint16_t>(i + 10 * j + 100 * k));
            }
        }
    }
    gdcm::DataElement data(gdcm::Tag(0x7fe0, 0x0010));
    data.SetByteValue(reinterpret_cast<const char*>(pixels.data()),
                      static_cast<std::uint32_t>(pixels.size() * 2));
    image->SetDataElement(data);
    image->SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
    gdcm::ImageWriter writer;
    writer.SetImage(*image);
    const fs::path file = dir / "frames.dcm";
    writer.SetFileName(file.c_str());
    ASSERT_TRUE(writer.Write());

    gdcm::ImageReader reader;  // what GDCM reads in this process
    reader.SetFileName(file.c_str());
    ASSERT_TRUE(reader.Read());
    const double* spacing = reader.GetImage().GetSpacing();
    const double* origin = reader.GetImage().GetOrigin();

    const Volume v = read_dicom_series(file);
    ASSERT_EQ(v.type(), VoxelType::i16);  // no rescaling, and every value fits
    ASSERT_EQ(v.dims(), (volume::Dims{8, 6, 4}));
    EXPECT_EQ(v.spacing(), (Vec3d{spacing[0], spacing[1], spacing[2]}));
    // Axial LPS into RAS: i and j reversed, k kept; voxel centres at origin + (index + 0.5) ·
    // spacing, so the file's first voxel (LPS origin) is at RAS (-x, -y, z).
    EXPECT_TRUE(v.is_axis_aligned());
    const auto values = v.values<VoxelType::i16>();
    for (std::int64_t k = 0; k < 4; ++k) {
        for (std::int64_t j = 0; j < 6; ++j) {
            for (std::int64_t i = 0; i < 8; ++i) {
                ASSERT_EQ(values[static_cast<std::size_t>(v.index(7 - i, 5 - j, k))],
                          i + 10 * j + 100 * k)
                    << i << " " << j << " " << k;
            }
        }
    }
    const Vec3d first_centre =
        v.origin() + Vec3d{7.5 * v.spacing().x, 5.5 * v.spacing().y, 0.5 * v.spacing().z};
    EXPECT_NEAR(first_centre.x, -origin[0], 1e-9);
    EXPECT_NEAR(first_centre.y, -origin[1], 1e-9);
    EXPECT_NEAR(first_centre.z, origin[2], 1e-9);
}

}  // namespace
}  // namespace pliant::io
