#include "pliant/io/dicom.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/detail/volume_data.hpp"
#include "pliant/io/forked_call.hpp"
#include "pliant/io/shared_memory.hpp"
#include "pliant/volume/reorient.hpp"

#ifdef PLIANT_HAS_GDCM
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmPixelFormat.h>
#include <gdcmScanner.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>
#include <gdcmTransferSyntax.h>
#endif

namespace pliant::io {

namespace fs = std::filesystem;

bool is_dicom_file(const fs::path& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (f == nullptr) {
        return false;
    }
    std::array<char, 132> head{};
    const std::size_t got = std::fread(head.data(), 1, head.size(), f);
    std::fclose(f);
    return got == head.size() && std::memcmp(head.data() + 128, "DICM", 4) == 0;
}

#ifndef PLIANT_HAS_GDCM

namespace {
[[noreturn]] void no_gdcm(const fs::path& path) {
    throw Unsupported(fmt::format(
        "{}: this pliant was built without GDCM, so it cannot read DICOM: install libgdcm-dev "
        "(scripts/install-deps), reconfigure and rebuild, or convert the series to NIfTI first",
        path.string()));
}
}  // namespace

bool has_dicom_support() {
    return false;
}
std::vector<DicomSeriesInfo> list_dicom_series(const fs::path& path) {
    no_gdcm(path);
}
std::vector<DicomSeriesInfo> list_dicom_series(std::span<const fs::path> files) {
    no_gdcm(files.empty() ? fs::path("DICOM") : files.front());
}
std::string chosen_dicom_series(const fs::path& path, const std::string&) {
    no_gdcm(path);
}
volume::Volume read_dicom_series(const fs::path& path, const DicomReadOptions&) {
    no_gdcm(path);
}
volume::Volume read_dicom_series(std::span<const fs::path> files, const DicomReadOptions&) {
    no_gdcm(files.empty() ? fs::path("DICOM") : files.front());
}

#else

namespace {

using volume::VoxelType;

const gdcm::Tag SERIES_UID(0x0020, 0x000e);
const gdcm::Tag SERIES_DESCRIPTION(0x0008, 0x103e);
const gdcm::Tag MODALITY(0x0008, 0x0060);
const gdcm::Tag ROWS(0x0028, 0x0010);
const gdcm::Tag COLUMNS(0x0028, 0x0011);
const gdcm::Tag NUMBER_OF_FRAMES(0x0028, 0x0008);
const gdcm::Tag IMAGE_POSITION(0x0020, 0x0032);
const gdcm::Tag IMAGE_ORIENTATION(0x0020, 0x0037);
const gdcm::Tag PIXEL_SPACING(0x0028, 0x0030);
const gdcm::Tag IMAGER_PIXEL_SPACING(0x0018, 0x1164);
const gdcm::Tag INSTANCE_NUMBER(0x0020, 0x0013);
const gdcm::Tag SPACING_BETWEEN_SLICES(0x0018, 0x0088);
const gdcm::Tag SLICE_THICKNESS(0x0018, 0x0050);

// Rounding in positions and cosines that files carry (decimal strings of limited length).
constexpr double POSITION_TOLERANCE_MM = 2e-3;
constexpr double RELATIVE_GAP_TOLERANCE = 0.02;
constexpr double ORIENTATION_TOLERANCE = 1e-4;
constexpr double GANTRY_TILT_WARNING_DEGREES = 0.5;

void quiet_gdcm() {
    static std::once_flag once;
    std::call_once(once, [] {
        gdcm::Trace::SetDebug(false);
        gdcm::Trace::SetWarning(false);
        gdcm::Trace::SetError(false);
    });
}

using detail::lower;

std::string trim(std::string_view text) {
    std::size_t b = 0;
    std::size_t e = text.size();
    while (b < e && (std::isspace(static_cast<unsigned char>(text[b])) != 0 || text[b] == '\0')) {
        ++b;
    }
    while (e > b &&
           (std::isspace(static_cast<unsigned char>(text[e - 1])) != 0 || text[e - 1] == '\0')) {
        --e;
    }
    return std::string(text.substr(b, e - b));
}

// A DICOM multi-valued decimal string "a\b\c" → its numbers; nullopt when absent, empty or
// malformed (a wrong count included).
std::optional<std::vector<double>> numbers(const char* text, std::size_t count) {
    if (text == nullptr) {
        return std::nullopt;
    }
    std::vector<double> out;
    std::string_view rest(text);
    while (true) {
        const std::size_t slash = rest.find('\\');
        const std::string token = trim(rest.substr(0, slash));
        double v = 0;
        if (token.empty() || detail::parse_real(token, v) != detail::ParseStatus::ok ||
            !std::isfinite(v)) {
            return std::nullopt;
        }
        out.push_back(v);
        if (slash == std::string_view::npos) {
            break;
        }
        rest = rest.substr(slash + 1);
    }
    if (out.size() != count) {
        return std::nullopt;
    }
    return out;
}

std::optional<std::int64_t> integer(const char* text) {
    if (text == nullptr) {
        return std::nullopt;
    }
    std::int64_t v = 0;
    if (detail::parse_integer(trim(text), v) != detail::ParseStatus::ok) {
        return std::nullopt;
    }
    return v;
}

std::string text_of(const char* text) {
    return text == nullptr ? std::string() : trim(text);
}

Vec3d ras(const Vec3d& lps) {
    return {-lps.x, -lps.y, lps.z};
}

std::string vec_text(const Vec3d& v) {
    return fmt::format("({:g}, {:g}, {:g})", v.x, v.y, v.z);
}

// One file's header fields that decide where its slice goes.
struct Slice {
    fs::path file;
    std::string series_uid;
    std::string description;
    std::string modality;
    std::int64_t rows = 0;
    std::int64_t columns = 0;
    std::int64_t frames = 1;
    std::optional<Vec3d> position;                       // ImagePositionPatient, LPS, mm
    std::optional<std::array<Vec3d, 2>> orientation;     // row and column cosines, LPS
    std::optional<std::array<double, 2>> pixel_spacing;  // between rows, between columns (mm)
    bool imager_spacing = false;                         // from ImagerPixelSpacing
    std::optional<std::int64_t> instance;
    std::optional<double> spacing_between_slices;
    std::optional<double> slice_thickness;
    double along = 0.0;  // position along the slice normal, mm (set when sorting)
};

// Candidate files of a folder, recursively, in name order: Part-10 files and *.dcm / *.dicom /
// *.ima (a DICOM file without a preamble is found by its extension only).
std::vector<fs::path> candidate_files(const fs::path& dir) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        throw IoError(fmt::format("{}: no such folder", dir.string()));
    }
    std::vector<fs::path> files;
    for (auto it = fs::recursive_directory_iterator(
             dir, fs::directory_options::skip_permission_denied, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        if (!it->is_regular_file(ec)) {
            continue;
        }
        const fs::path& p = it->path();
        const std::string ext = lower(p.extension().string());
        if (ext == ".dcm" || ext == ".dicom" || ext == ".ima" || is_dicom_file(p)) {
            files.push_back(p);
        }
    }
    if (ec) {
        throw IoError(fmt::format("{}: cannot list the folder: {}", dir.string(), ec.message()));
    }
    std::sort(files.begin(), files.end());
    return files;
}

// The VR (or VRs, "US or SS") of the image attributes GDCM reads through gdcm::Attribute while
// reading an image (PS3.6); empty for other tags.
std::string_view image_attribute_vr(unsigned group, unsigned element) {
    static const std::map<std::pair<unsigned, unsigned>, std::string_view> VRS = {
        {{0x0008, 0x0060}, "CS"},       {{0x0018, 0x0050}, "DS"},
        {{0x0018, 0x0088}, "DS"},       {{0x0018, 0x1164}, "DS"},
        {{0x0020, 0x0013}, "IS"},       {{0x0020, 0x0032}, "DS"},
        {{0x0020, 0x0037}, "DS"},       {{0x0028, 0x0002}, "US"},
        {{0x0028, 0x0004}, "CS"},       {{0x0028, 0x0006}, "US"},
        {{0x0028, 0x0008}, "IS"},       {{0x0028, 0x0010}, "US"},
        {{0x0028, 0x0011}, "US"},       {{0x0028, 0x0030}, "DS"},
        {{0x0028, 0x0100}, "US"},       {{0x0028, 0x0101}, "US"},
        {{0x0028, 0x0102}, "US"},       {{0x0028, 0x0103}, "US"},
        {{0x0028, 0x0120}, "US or SS"}, {{0x0028, 0x1050}, "DS"},
        {{0x0028, 0x1051}, "DS"},       {{0x0028, 0x1052}, "DS"},
        {{0x0028, 0x1053}, "DS"},       {{0x0028, 0x1054}, "LO"},
        {{0x0028, 0x1101}, "US or SS"}, {{0x0028, 0x1102}, "US or SS"},
        {{0x0028, 0x1103}, "US or SS"}};
    const auto it = VRS.find({group, element});
    return it == VRS.end() ? std::string_view{} : it->second;
}

// Why GDCM's JPEG codec must not be given the JPEG stream `j` (the first fragment of JPEG pixel
// data), or nullopt. Its GetHeaderInfo asserts on any libjpeg warning while reading the header
// (gdcmJPEGBITSCodec.hxx:386: a byte other than 0xFF before a marker, fuzz_dicom) and on
// component counts it does not handle, so the markers from SOI to SOS are walked (ITU T.81
// annex B): each a 0xFF marker (fill bytes allowed) with a length within the fragment, JFIF
// version 1, an Adobe transform of 0 to 2, and a frame header of 1 or 3 components.
std::optional<std::string> jpeg_header_problem(const std::vector<unsigned char>& j) {
    if (j.size() < 4 || j[0] != 0xFF || j[1] != 0xD8) {
        return std::string("does not start with a JPEG SOI marker");
    }
    std::size_t at = 2;
    while (at < j.size()) {
        if (j[at] != 0xFF) {
            return fmt::format("has byte 0x{:02X} at JPEG offset {}, expected a marker", j[at], at);
        }
        while (at < j.size() && j[at] == 0xFF) {
            ++at;  // fill bytes
        }
        if (at + 2 >= j.size()) {
            return std::string("ends inside its JPEG header");
        }
        const unsigned m = j[at];
        if (m == 0xD8 || m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {
            ++at;
            continue;  // no length
        }
        if (m == 0xD9) {
            return std::string("ends (EOI) before its JPEG scan");
        }
        const std::size_t length = static_cast<std::size_t>(j[at + 1]) << 8 | j[at + 2];
        if (length < 2 || at + 1 + length > j.size()) {
            return fmt::format(
                "has a JPEG marker 0xFF{:02X} of {} bytes at offset {}, beyond the "
                "fragment",
                m, length, at - 1);
        }
        const unsigned char* body = j.data() + at + 3;
        const std::size_t n = length - 2;
        if (m == 0xDA) {
            return std::nullopt;  // the scan: the header is complete
        }
        if (m == 0xE0 && n >= 7 && std::memcmp(body, "JFIF", 5) == 0 && body[5] != 1) {
            return fmt::format("has JFIF version {}, expected 1", body[5]);
        }
        if (m == 0xEE && n >= 12 && std::memcmp(body, "Adobe", 5) == 0 && body[11] > 2) {
            return fmt::format("has Adobe transform {}, expected 0 to 2", body[11]);
        }
        const bool frame = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
        if (frame &&
            (n < 6 || (body[5] != 1 && body[5] != 3) || n != 6 + std::size_t{3} * body[5])) {
            return fmt::format(
                "has a JPEG frame header of {} bytes with {} components, expected "
                "1 or 3 components",
                n, n >= 6 ? body[5] : 0);
        }
        at += 1 + length;
    }
    return std::string("ends before its JPEG scan");
}

// Why GDCM must not be given `file`, or nullopt. GDCM allocates an element's declared length
// before reading it (a 972-byte file declaring 4 GB made it allocate 4 GB: fuzz_dicom), so the
// data elements are walked first, as PS3.5 section 7 lays them out: each defined length must fit
// in the bytes left, and an explicit VR must be two capital letters. Sequences and items are
// entered, not skipped, so nested elements are checked too. Encapsulated pixel data's items are
// walked (what is inside a JPEG fragment is the codec's to check; RLE's segment tables are
// checked). The walk also stops after the file meta group for the transfer syntaxes it cannot walk
// (deflate, explicit big endian), where GDCM is trusted as before.
std::optional<std::string> element_length_problem(const fs::path& file) {
    std::FILE* f = std::fopen(file.c_str(), "rb");
    if (f == nullptr) {
        return std::nullopt;  // GDCM reports it
    }
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(file, ec);
    std::array<unsigned char, 132> head{};
    const bool part10 = !ec && std::fread(head.data(), 1, head.size(), f) == head.size() &&
                        std::memcmp(head.data() + 128, "DICM", 4) == 0;
    std::uintmax_t pos = part10 ? 132 : 0;
    std::string syntax;  // (0002,0010), read when the meta group has it
    const auto u16 = [](const unsigned char* b) {
        return static_cast<unsigned>(b[0] | b[1] << 8);
    };
    const auto u32 = [](const unsigned char* b) {
        return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
               static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
    };
    std::optional<std::string> problem;
    bool data_set = false;  // an element after the file meta group was seen
    bool rle_syntax = false;
    bool jpeg_syntax = false;  // ITU T.81 JPEG: the first fragment's header is checked  // RLE
                               // Lossless: the fragments' segment tables are checked too
    int fragment = -1;         // in encapsulated pixel data: 0 the offset table, then the fragments
    while (!ec && pos + 8 <= size) {
        std::array<unsigned char, 12> h{};
        if (std::fseek(f, static_cast<long>(pos), SEEK_SET) != 0 ||
            std::fread(h.data(), 1, std::min<std::uintmax_t>(12, size - pos), f) == 0) {
            break;
        }
        const unsigned group = u16(h.data());
        const unsigned element = u16(h.data() + 2);
        data_set = data_set || group != 0x0002;
        if (group != 0x0002 &&
            (syntax == "1.2.840.10008.1.2.1.99" || syntax == "1.2.840.10008.1.2.2")) {
            break;  // deflated or big-endian data set
        }
        const bool item = group == 0xFFFE;
        // Without a meta group (no transfer syntax) the VR bytes tell, as GDCM guesses too.
        const bool letters = std::isupper(h[4]) != 0 && std::isupper(h[5]) != 0;
        const bool explicit_vr =
            !item &&
            (group == 0x0002 || (syntax.empty() ? letters : syntax != "1.2.840.10008.1.2"));
        std::uint32_t length = 0;
        std::uintmax_t header = 8;
        bool sequence = item;
        if (explicit_vr) {
            const char vr[3] = {static_cast<char>(h[4]), static_cast<char>(h[5]), '\0'};
            if (!letters) {
                problem = fmt::format(
                    "element ({:04X},{:04X}) at byte {} has VR bytes 0x{:02X}{:02X}, expected two "
                    "capital letters",
                    group, element, pos, h[4], h[5]);
                break;
            }
            const std::string_view v(vr, 2);
            // The VRs of PS3.5 table 6.2-1 (GDCM 3.0.21 knows them all); GDCM's reader of the
            // file meta group asserts on any other (gdcmFileMetaInformation.cxx:436: "KH" in
            // (0002,0013), fuzz_dicom).
            constexpr std::string_view VRS =
                "AE AS AT CS DA DS DT FD FL IS LO LT OB OD OF OL OV OW PN SH SL SQ SS ST SV TM UC "
                "UI UL UN UR US UT UV";
            if (VRS.find(v) == std::string_view::npos) {  // letters only: no match spans a space
                problem = fmt::format(
                    "element ({:04X},{:04X}) at byte {} has VR '{}', which DICOM does not define",
                    group, element, pos, v);
                break;
            }
            // The image attributes GDCM reads through gdcm::Attribute, which asserts that the
            // VR is the dictionary's (gdcmAttribute.h:210: Image Position with VR PN,
            // fuzz_dicom). UN is accepted as GDCM does.
            if (const std::string_view want = image_attribute_vr(group, element);
                !want.empty() && v != "UN" && want.find(v) == std::string_view::npos) {
                problem = fmt::format("element ({:04X},{:04X}) at byte {} has VR '{}', expected {}",
                                      group, element, pos, v, want);
                break;
            }
            if (v == "OB" || v == "OD" || v == "OF" || v == "OL" || v == "OV" || v == "OW" ||
                v == "SQ" || v == "SV" || v == "UC" || v == "UN" || v == "UR" || v == "UT" ||
                v == "UV") {
                if (pos + 12 > size) {
                    problem = fmt::format("element ({:04X},{:04X}) at byte {} is cut short", group,
                                          element, pos);
                    break;
                }
                length = u32(h.data() + 8);
                header = 12;
            } else {
                length = u16(h.data() + 6);
            }
            sequence = v == "SQ";
            if (v == "UN" && u32(h.data() + 8) == 0xFFFFFFFFU) {
                break;  // an unknown-VR sequence: implicit VR inside, not walked
            }
        } else {
            length = u32(h.data() + 4);
        }
        if (fragment >= 0) {
            // Encapsulated pixel data (PS3.5 A.4): items (FFFE,E000) of defined length (the
            // offset table, then the fragments) up to the delimiter (FFFE,E0DD); GDCM allocates
            // what any other tag there declares (a fragment tag (FFFE,9696) declaring 2.5 GB:
            // fuzz_dicom). For RLE (annex G) each fragment starts with a 64-byte header of the
            // segment count (1 to 15) and the segments' offsets (GDCM trusts them: 26,114
            // segments made it read out of bounds).
            if (item && element == 0xE0DD) {
                if (length != 0) {
                    // GDCM reads it as a fragment of that length (fuzz_dicom: 0xF7000000).
                    problem = fmt::format(
                        "the pixel data's delimiter (FFFE,E0DD) at byte {} declares {} bytes, "
                        "expected 0",
                        pos, length);
                    break;
                }
                fragment = -1;
                pos += header;
                continue;
            }
            if (!item || element != 0xE000) {
                problem = fmt::format(
                    "pixel data fragment {} at byte {} has tag ({:04X},{:04X}), expected an item "
                    "(FFFE,E000) or the delimiter (FFFE,E0DD)",
                    fragment, pos, group, element);
                break;
            }
            if (length == 0xFFFFFFFFU || length > size - pos - header) {
                problem = fmt::format(
                    "pixel data fragment {} at byte {} declares {} bytes, the file has {} left",
                    fragment, pos, length, size - pos - header);
                break;
            }
            if (jpeg_syntax && fragment == 1) {
                std::vector<unsigned char> jpeg(std::min<std::size_t>(length, 65536));
                if (std::fseek(f, static_cast<long>(pos + header), SEEK_SET) != 0 ||
                    std::fread(jpeg.data(), 1, jpeg.size(), f) != jpeg.size()) {
                    break;
                }
                if (const std::optional<std::string> why = jpeg_header_problem(jpeg)) {
                    problem = fmt::format("the JPEG pixel data fragment at byte {} {}", pos, *why);
                    break;
                }
            }
            if (rle_syntax && fragment > 0) {
                std::array<unsigned char, 64> rle{};
                if (length < rle.size() ||
                    std::fseek(f, static_cast<long>(pos + header), SEEK_SET) != 0 ||
                    std::fread(rle.data(), 1, rle.size(), f) != rle.size()) {
                    problem = fmt::format(
                        "RLE fragment at byte {} is shorter than its 64-byte header", pos);
                    break;
                }
                const std::uint32_t segments = u32(rle.data());
                std::uint32_t previous = 64;
                for (std::uint32_t i = 0; i < segments && i < 15 && !problem; ++i) {
                    const std::uint32_t offset = u32(rle.data() + 4 + std::size_t{4} * i);
                    if (offset < previous || offset >= length || (i == 0 && offset != 64)) {
                        problem = fmt::format(
                            "RLE fragment at byte {}: segment {} starts at {}, expected 64 for the "
                            "first, then increasing offsets below the fragment's {} bytes",
                            pos, i, offset, length);
                    }
                    previous = offset;
                }
                if (segments < 1 || segments > 15) {
                    problem = fmt::format(
                        "RLE fragment at byte {} declares {} segments, expected 1 to 15", pos,
                        segments);
                }
                if (problem) {
                    break;
                }
            }
            ++fragment;
            pos += header + length;
            continue;
        }
        if (length == 0xFFFFFFFFU) {
            if (group == 0x7FE0 && element == 0x0010) {
                fragment = 0;  // encapsulated pixel data: fragments follow
                pos += header;
                continue;
            }
            pos += header;  // an undefined-length sequence or item: its elements follow
            continue;
        }
        if (length > size - pos - header) {
            problem = fmt::format(
                "element ({:04X},{:04X}) at byte {} declares {} bytes, the file has {} left", group,
                element, pos, length, size - pos - header);
            break;
        }
        if (group == 0x0028 && (element == 0x0002 || element == 0x0100) && length >= 2) {
            // Samples per Pixel and Bits Allocated: GDCM asserts unless Samples per Pixel is 1, 3
            // or 4 (gdcmPixelFormat.h:96), and its RLE decoder unless they are 1 or 3 and 8, 16
            // or 32 (gdcmRLECodec.cxx:777-782; Bits Allocated 4624 gave a zero length: both
            // fuzz_dicom). PS3.5 8.1.1: Bits Allocated is 1 or a multiple of 8.
            std::array<unsigned char, 2> us{};
            if (std::fseek(f, static_cast<long>(pos + header), SEEK_SET) != 0 ||
                std::fread(us.data(), 1, us.size(), f) != us.size()) {
                break;
            }
            const unsigned value = u16(us.data());
            if (element == 0x0002 && value != 1 && value != 3 && (value != 4 || rle_syntax)) {
                problem =
                    fmt::format("Samples per Pixel (0028,0002) at byte {} is {}, expected 1, 3{}",
                                pos, value, rle_syntax ? " (RLE)" : " or 4");
                break;
            }
            const bool bits_ok = rle_syntax
                                     ? value == 8 || value == 16 || value == 32
                                     : value == 1 || (value % 8 == 0 && value >= 8 && value <= 64);
            if (element == 0x0100 && !bits_ok) {
                problem = fmt::format(
                    "Bits Allocated (0028,0100) at byte {} is {}, expected {}", pos, value,
                    rle_syntax ? "8, 16 or 32 (RLE)" : "1 or a multiple of 8 up to 64");
                break;
            }
        }
        if (group == 0x0008 && element == 0x0010) {
            // Recognition Code (retired, ACR-NEMA): GDCM asserts that it starts with "ACR-NEMA",
            // "ACRNEMA" or "MIPS 2.0" (gdcmPixmapReader.cxx:633; fuzz_dicom: a Study Time tag
            // mutated into it).
            std::array<char, 8> code{};
            const std::size_t n = std::min<std::size_t>(length, code.size());
            if (std::fseek(f, static_cast<long>(pos + header), SEEK_SET) != 0 ||
                std::fread(code.data(), 1, n, f) != n) {
                break;
            }
            const std::string_view c(code.data(), n);
            if (!c.starts_with("ACR-NEMA") && !c.starts_with("ACRNEMA") &&
                !c.starts_with("MIPS 2.0")) {
                problem = fmt::format(
                    "Recognition Code (0008,0010) at byte {} starts with '{}', expected ACR-NEMA",
                    pos, c);
                break;
            }
        }
        if (group == 0x0002 && element == 0x0010 && length <= 64) {
            std::string text(length, '\0');
            if (std::fseek(f, static_cast<long>(pos + header), SEEK_SET) != 0 ||
                std::fread(text.data(), 1, length, f) != length) {
                break;
            }
            while (!text.empty() && (text.back() == '\0' || text.back() == ' ')) {
                text.pop_back();
            }
            syntax = text;
            rle_syntax = syntax == "1.2.840.10008.1.2.5";
            // JPEG (ITU T.81) syntaxes: 1.2.840.10008.1.2.4.50 to .4.70, not JPEG-LS (.80, .81)
            // or JPEG 2000 (.90 and up).
            jpeg_syntax = syntax.starts_with("1.2.840.10008.1.2.4.") && syntax.size() == 22 &&
                          syntax.substr(20) >= "50" && syntax.substr(20) <= "70";
        }
        // A sequence's or item's contents are elements: walk into them.
        pos += header + (sequence ? 0 : length);
    }
    // 1 to 7 bytes after the last element: a header cut short. GDCM reads its tag, fails on the
    // VR at the end of the file, and its VR16 fallback seeks back on the failed stream and
    // asserts (gdcmVR16ExplicitDataElement.txx:46, "Should not happen"; fuzz_dicom).
    if (!problem && !ec && pos < size && pos + 8 > size) {
        problem = fmt::format(
            "the data element at byte {} is cut short: {} bytes left, a data element header has 8",
            pos, size - pos);
    }
    // A Part 10 file that ends with its meta group: GDCM's meta group reader asserts on the
    // missing next tag (gdcmFileMetaInformation.cxx:375, fuzz_dicom).
    if (!problem && !ec && part10 && !data_set && pos >= size) {
        problem =
            fmt::format("the file ends after its file meta group at byte {}: no data set", pos);
    }
    std::fclose(f);
    return problem;
}

// What GDCM may use in a child process (io/forked_call.hpp) beyond what the child inherits:
// room for GDCM and the C++ runtime (more under AddressSanitizer, whose quarantine keeps freed
// memory mapped), three times the largest file (GDCM holds its data elements, and copies while
// decoding) and twice the largest decoded image. `seconds` bounds the time GDCM takes over one
// file.
ForkLimits gdcm_limits(std::uintmax_t largest_file, std::uintmax_t decoded_bytes, double seconds) {
#if defined(__SANITIZE_ADDRESS__)
    constexpr std::size_t BASE = std::size_t{1536} << 20;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    constexpr std::size_t BASE = std::size_t{1536} << 20;
#else
    constexpr std::size_t BASE = std::size_t{512} << 20;
#endif
#else
    constexpr std::size_t BASE = std::size_t{512} << 20;
#endif
    ForkLimits limits;
    limits.max_address_space = BASE + 3 * static_cast<std::size_t>(largest_file) +
                               2 * static_cast<std::size_t>(decoded_bytes);
    limits.seconds_quiet = seconds;
    return limits;
}

std::uintmax_t largest_file(const std::vector<std::string>& names) {
    std::uintmax_t largest = 0;
    for (const std::string& name : names) {
        std::error_code ec;
        const std::uintmax_t size = name.empty() ? 0 : fs::file_size(name, ec);
        largest = std::max<std::uintmax_t>(largest, ec ? 0 : size);
    }
    return largest;
}

const std::array<gdcm::Tag, 13> SCANNED_TAGS{
    SERIES_UID,     SERIES_DESCRIPTION,   MODALITY,        ROWS,
    COLUMNS,        NUMBER_OF_FRAMES,     IMAGE_POSITION,  IMAGE_ORIENTATION,
    PIXEL_SPACING,  IMAGER_PIXEL_SPACING, INSTANCE_NUMBER, SPACING_BETWEEN_SLICES,
    SLICE_THICKNESS};

// One file's values of SCANNED_TAGS as gdcm::Scanner gives them (nullopt: absent); `parsed`
// false when GDCM could not parse the file.
struct ScannedTags {
    bool parsed = false;
    std::array<std::optional<std::string>, SCANNED_TAGS.size()> values;
};

// gdcm::Scanner over `names` (empty names are left out), in a child process: GDCM asserts on
// some hostile headers. A file on which the child dies is an IoError when `listed`, else skipped
// with a warning (its `parsed` false), and the files after it are scanned by a new child.
std::vector<ScannedTags> scan_tags(const std::vector<std::string>& names, bool listed,
                                   double seconds) {
    std::vector<ScannedTags> tags(names.size());
    const ForkLimits limits = gdcm_limits(largest_file(names), 0, seconds);
    std::size_t next = 0;  // the first file not scanned yet
    while (next < names.size()) {
        const std::size_t from = next;
        const ForkedResult run = run_forked(
            limits,
            [&](ForkChannel& channel) {
                quiet_gdcm();
                for (std::size_t n = from; n < names.size(); ++n) {
                    ByteWriter w;
                    if (names[n].empty()) {
                        w.put(false);
                        channel.send(w.bytes());
                        continue;
                    }
                    gdcm::Scanner scanner;
                    for (const gdcm::Tag& tag : SCANNED_TAGS) {
                        scanner.AddTag(tag);
                    }
                    scanner.Scan({names[n]});
                    const bool parsed = scanner.IsKey(names[n].c_str());
                    w.put(parsed);
                    for (const gdcm::Tag& tag : SCANNED_TAGS) {
                        const char* value =
                            parsed ? scanner.GetValue(names[n].c_str(), tag) : nullptr;
                        w.put(value != nullptr);
                        if (value != nullptr) {
                            w.put_string(value);
                        }
                    }
                    channel.send(w.bytes());
                }
            },
            [&](std::span<const std::byte> record) {
                ByteReader r(record, "the GDCM scan");
                ScannedTags& t = tags.at(next);
                t.parsed = r.get_bool("parsed");
                for (std::size_t i = 0; t.parsed && i < SCANNED_TAGS.size(); ++i) {
                    if (r.get_bool("present")) {
                        t.values[i] = r.get_string("value");
                    }
                }
                ++next;
            });
        if (run.completed) {
            break;
        }
        // The child died on file `next`.
        if (listed) {
            throw IoError(
                fmt::format("{}: GDCM could not parse it: {}", names.at(next), run.failure));
        }
        log_warning("{}: skipped, GDCM could not parse it: {}", names.at(next), run.failure);
        ++next;
    }
    return tags;
}

// Scans the headers (no pixel data). In a folder (`listed` false) files GDCM cannot parse and
// objects without an image are skipped; in an explicit list they are errors.
std::vector<Slice> scan(const std::vector<fs::path>& files, bool listed,
                        double seconds = DicomReadOptions{}.gdcm_seconds) {
    // Files GDCM must not see (element_length_problem) are left out of the scan: an error when
    // listed, skipped in a folder like the files GDCM cannot parse.
    std::vector<std::string> names;
    names.reserve(files.size());
    for (const fs::path& f : files) {
        if (const std::optional<std::string> problem = element_length_problem(f)) {
            if (listed) {
                throw IoError(
                    fmt::format("{}: not a DICOM file pliant can read: {}", f.string(), *problem));
            }
            log_debug("{}: skipped, not a readable DICOM file: {}", f.string(), *problem);
            names.emplace_back();
            continue;
        }
        names.push_back(f.string());
    }
    const std::vector<ScannedTags> scanned = scan_tags(names, listed, seconds);
    std::vector<Slice> slices;
    for (std::size_t n = 0; n < files.size(); ++n) {
        if (names[n].empty() || !scanned[n].parsed) {
            if (listed) {
                throw IoError(fmt::format("{}: not a DICOM file (GDCM cannot parse it)", names[n]));
            }
            continue;
        }
        const auto value = [&](const gdcm::Tag& tag) -> const char* {
            for (std::size_t i = 0; i < SCANNED_TAGS.size(); ++i) {
                if (SCANNED_TAGS[i] == tag) {
                    const std::optional<std::string>& v = scanned[n].values[i];
                    return v ? v->c_str() : nullptr;
                }
            }
            return nullptr;
        };
        Slice s;
        s.file = files[n];
        s.rows = integer(value(ROWS)).value_or(0);
        s.columns = integer(value(COLUMNS)).value_or(0);
        if (s.rows < 1 || s.columns < 1) {
            if (listed) {
                throw IoError(fmt::format(
                    "{}: a DICOM object without an image (Rows and Columns missing or 0)",
                    names[n]));
            }
            continue;
        }
        s.series_uid = text_of(value(SERIES_UID));
        s.description = text_of(value(SERIES_DESCRIPTION));
        s.modality = text_of(value(MODALITY));
        // GDCM asserts on a Number of Frames of 0 or one that is not a number
        // (gdcmPixmapReader.cxx, ReadImage).
        const char* frames = value(NUMBER_OF_FRAMES);
        if (frames != nullptr && integer(frames).value_or(0) < 1) {
            const std::string problem = fmt::format(
                "{}: not a DICOM file pliant can read: Number of Frames (0028,0008) is '{}', "
                "expected a positive integer",
                names[n], trim(frames));
            if (listed) {
                throw IoError(problem);
            }
            log_debug("skipped: {}", problem);
            continue;
        }
        s.frames = std::max<std::int64_t>(1, integer(frames).value_or(1));
        if (const auto p = numbers(value(IMAGE_POSITION), 3)) {
            s.position = Vec3d{(*p)[0], (*p)[1], (*p)[2]};
        }
        if (const auto o = numbers(value(IMAGE_ORIENTATION), 6)) {
            s.orientation = std::array<Vec3d, 2>{Vec3d{(*o)[0], (*o)[1], (*o)[2]},
                                                 Vec3d{(*o)[3], (*o)[4], (*o)[5]}};
        }
        if (const auto ps = numbers(value(PIXEL_SPACING), 2)) {
            s.pixel_spacing = std::array<double, 2>{(*ps)[0], (*ps)[1]};
        } else if (const auto ips = numbers(value(IMAGER_PIXEL_SPACING), 2)) {
            s.pixel_spacing = std::array<double, 2>{(*ips)[0], (*ips)[1]};
            s.imager_spacing = true;
        }
        s.instance = integer(value(INSTANCE_NUMBER));
        if (const auto sbs = numbers(value(SPACING_BETWEEN_SLICES), 1)) {
            s.spacing_between_slices = std::abs((*sbs)[0]);
        }
        if (const auto t = numbers(value(SLICE_THICKNESS), 1)) {
            s.slice_thickness = (*t)[0];
        }
        slices.push_back(std::move(s));
    }
    return slices;
}

std::map<std::string, std::vector<Slice>> by_series(std::vector<Slice> slices) {
    std::map<std::string, std::vector<Slice>> series;
    for (Slice& s : slices) {
        series[s.series_uid].push_back(std::move(s));
    }
    return series;
}

DicomSeriesInfo info_of(const std::vector<Slice>& slices) {
    DicomSeriesInfo info;
    const Slice& first = slices.front();
    info.uid = first.series_uid;
    info.description = first.description;
    info.modality = first.modality;
    info.num_files = static_cast<std::int64_t>(slices.size());
    std::int64_t depth = 0;
    for (const Slice& s : slices) {
        depth += s.frames;
    }
    info.dims = {first.columns, first.rows, depth};
    info.first_file = first.file;
    for (const Slice& s : slices) {
        info.first_file = std::min(info.first_file, s.file);
    }
    return info;
}

double voxels(const DicomSeriesInfo& info) {
    return static_cast<double>(info.dims[0]) * static_cast<double>(info.dims[1]) *
           static_cast<double>(info.dims[2]);
}

// Largest first: voxels, then files, then UID.
bool larger(const DicomSeriesInfo& a, const DicomSeriesInfo& b) {
    if (voxels(a) != voxels(b)) {
        return voxels(a) > voxels(b);
    }
    if (a.num_files != b.num_files) {
        return a.num_files > b.num_files;
    }
    return a.uid < b.uid;
}

std::string series_line(const DicomSeriesInfo& info) {
    return fmt::format("{} ({}{}{}, {} files, {}x{}x{})", info.uid.empty() ? "(no UID)" : info.uid,
                       info.modality.empty() ? "?" : info.modality,
                       info.description.empty() ? "" : " ", info.description, info.num_files,
                       info.dims[0], info.dims[1], info.dims[2]);
}

std::vector<DicomSeriesInfo> listing(const std::map<std::string, std::vector<Slice>>& series) {
    std::vector<DicomSeriesInfo> out;
    out.reserve(series.size());
    for (const auto& [uid, slices] : series) {
        out.push_back(info_of(slices));
    }
    std::sort(out.begin(), out.end(), larger);
    return out;
}

// The slices of the series to read: options.series_uid, else the largest.
std::vector<Slice> choose(const fs::path& where, std::map<std::string, std::vector<Slice>> series,
                          const std::string& series_uid, std::size_t num_candidates) {
    if (series.empty()) {
        throw IoError(
            fmt::format("{}: no DICOM image found ({} candidate files: *.dcm, *.dicom, "
                        "*.ima or with a DICM marker; none holds an image GDCM can "
                        "parse)",
                        where.string(), num_candidates));
    }
    const std::vector<DicomSeriesInfo> all = listing(series);
    if (!series_uid.empty()) {
        const auto it = series.find(series_uid);
        if (it == series.end()) {
            std::string known;
            for (const DicomSeriesInfo& info : all) {
                known += "\n  " + series_line(info);
            }
            throw InvalidInput(
                fmt::format("{}: no DICOM series with UID {}; the series there "
                            "are:{}",
                            where.string(), series_uid, known));
        }
        return std::move(it->second);
    }
    if (all.size() > 1) {
        std::string others;
        for (std::size_t i = 1; i < all.size(); ++i) {
            others += "\n  " + series_line(all[i]);
        }
        log_info(
            "{}: {} DICOM series; reading the largest, {}; the others (choose one with "
            "--series UID):{}",
            where.string(), all.size(), series_line(all.front()), others);
    }
    return std::move(series.at(all.front().uid));
}

// How the pixels of one file are stored.
struct StoredFormat {
    gdcm::PixelFormat::ScalarType scalar = gdcm::PixelFormat::UNKNOWN;
    std::size_t bytes = 0;  // per pixel
};

StoredFormat stored_format(const fs::path& file, const gdcm::Image& image) {
    const gdcm::PixelFormat& pf = image.GetPixelFormat();
    if (pf.GetSamplesPerPixel() != 1) {
        throw Unsupported(fmt::format(
            "{}: colour DICOM images ({} samples per pixel, {}) are not supported, expected "
            "grey-scale (1 sample per pixel)",
            file.string(), pf.GetSamplesPerPixel(),
            gdcm::PhotometricInterpretation::GetPIString(
                image.GetPhotometricInterpretation().GetType())));
    }
    StoredFormat f;
    f.scalar = pf.GetScalarType();
    switch (f.scalar) {
        case gdcm::PixelFormat::UINT8:
        case gdcm::PixelFormat::INT8:
            f.bytes = 1;
            break;
        case gdcm::PixelFormat::UINT12:
        case gdcm::PixelFormat::INT12:
        case gdcm::PixelFormat::UINT16:
        case gdcm::PixelFormat::INT16:
            f.bytes = 2;
            break;
        case gdcm::PixelFormat::UINT32:
        case gdcm::PixelFormat::INT32:
        case gdcm::PixelFormat::FLOAT32:
            f.bytes = 4;
            break;
        case gdcm::PixelFormat::FLOAT64:
            f.bytes = 8;
            break;
        default:
            throw Unsupported(fmt::format(
                "{}: DICOM pixel format {} ({} bits allocated) is not supported, expected 8, 16 "
                "or 32-bit integers or 32/64-bit floats",
                file.string(), pf.GetScalarTypeAsString(), pf.GetBitsAllocated()));
    }
    if (static_cast<std::size_t>(pf.GetPixelSize()) != f.bytes) {
        throw Unsupported(
            fmt::format("{}: DICOM pixel format {} with {} bytes per pixel is not "
                        "supported",
                        file.string(), pf.GetScalarTypeAsString(), pf.GetPixelSize()));
    }
    return f;
}

// The stored pixel at `index` of a raw buffer, as a double.
double stored_value(const std::byte* raw, std::size_t index, gdcm::PixelFormat::ScalarType s) {
    const auto read = [&]<typename T>(T) {
        T v{};
        std::memcpy(&v, raw + index * sizeof(T), sizeof(T));
        return static_cast<double>(v);
    };
    switch (s) {
        case gdcm::PixelFormat::UINT8:
            return read(std::uint8_t{});
        case gdcm::PixelFormat::INT8:
            return read(std::int8_t{});
        case gdcm::PixelFormat::UINT12:
        case gdcm::PixelFormat::UINT16:
            return read(std::uint16_t{});
        case gdcm::PixelFormat::INT12:
        case gdcm::PixelFormat::INT16:
            return read(std::int16_t{});
        case gdcm::PixelFormat::UINT32:
            return read(std::uint32_t{});
        case gdcm::PixelFormat::INT32:
            return read(std::int32_t{});
        case gdcm::PixelFormat::FLOAT32:
            return read(float{});
        default:
            return read(double{});
    }
}

// The pixel data of every file, in order, in one buffer of the stored format; with each
// file's rescale slope and intercept.
struct Pixels {
    SharedMemory memory;       // what the child process decoded into
    std::span<std::byte> raw;  // the stored pixels: files × pixels per file × format.bytes
    StoredFormat format;
    std::vector<double> slopes;
    std::vector<double> intercepts;
    std::vector<double> stored_min;  // per file
    std::vector<double> stored_max;
};

// One file's result of read_pixels' child process.
struct DecodedFile {
    StoredFormat format;
    double slope = 1.0;
    double intercept = 0.0;
    double lo = 0.0;  // stored values
    double hi = 0.0;
};

// GDCM reads and decodes every file in a child process (io/forked_call.hpp), into shared memory
// sized for 8 bytes a pixel (what is not written costs address space only): a GDCM assertion,
// crash, runaway allocation or hang on a file is an IoError naming it.
Pixels read_pixels(const std::vector<Slice>& slices, const volume::Dims& dims,
                   std::size_t max_bytes, const fs::path& where, double seconds) {
    Pixels px;
    const auto per_file = static_cast<std::size_t>(dims[0] * dims[1]) *
                          static_cast<std::size_t>(slices.front().frames);
    constexpr std::size_t MAX_PIXEL_BYTES = 8;
    px.memory = SharedMemory(per_file * slices.size() * MAX_PIXEL_BYTES);
    const std::span<std::byte> shared = px.memory.bytes();
    std::vector<std::string> names;
    names.reserve(slices.size());
    for (const Slice& s : slices) {
        names.push_back(s.file.string());
    }
    const ForkLimits limits =
        gdcm_limits(largest_file(names),
                    std::min<std::uintmax_t>(per_file * MAX_PIXEL_BYTES, max_bytes), seconds);
    // The child: each file decoded into its place, checked as it goes.
    const auto decode_all = [&](ForkChannel& channel) {
        quiet_gdcm();
        StoredFormat first;
        for (std::size_t n = 0; n < slices.size(); ++n) {
            const fs::path& file = slices[n].file;
            gdcm::ImageReader reader;
            reader.SetFileName(file.c_str());
            if (!reader.Read()) {
                throw IoError(
                    fmt::format("{}: cannot read the DICOM image (GDCM could not parse the "
                                "file or decode its pixel data)",
                                file.string()));
            }
            const gdcm::Image& image = reader.GetImage();
            const StoredFormat format = stored_format(file, image);
            if (n == 0) {
                first = format;
                // The stored data and the volume (at most 4 bytes a voxel) must both fit.
                const volume::Dims stored_dims{dims[0], dims[1],
                                               dims[2] * static_cast<std::int64_t>(format.bytes)};
                detail::check_declared_size(where, stored_dims, VoxelType::u8, max_bytes);
                detail::check_declared_size(where, dims, VoxelType::f32, max_bytes);
            } else if (format.scalar != first.scalar) {
                throw InvalidInput(
                    fmt::format("{}: mixed pixel formats in one series: {} stores {}, {} stores {}",
                                where.string(), slices.front().file.filename().string(),
                                gdcm::PixelFormat(first.scalar).GetScalarTypeAsString(),
                                file.filename().string(),
                                gdcm::PixelFormat(format.scalar).GetScalarTypeAsString()));
            }
            const std::int64_t frames = image.GetNumberOfDimensions() >= 3
                                            ? static_cast<std::int64_t>(image.GetDimension(2))
                                            : 1;
            if (static_cast<std::int64_t>(image.GetDimension(0)) != dims[0] ||
                static_cast<std::int64_t>(image.GetDimension(1)) != dims[1] ||
                frames != slices[n].frames) {
                throw InvalidInput(
                    fmt::format("{}: the image is {}x{}x{}, its header said {}x{}x{}",
                                file.string(), image.GetDimension(0), image.GetDimension(1), frames,
                                dims[0], dims[1], slices[n].frames));
            }
            const std::size_t bytes = per_file * format.bytes;
            if (image.GetBufferLength() != bytes) {
                throw IoError(fmt::format("{}: the decoded pixel data has {} bytes, expected {}",
                                          file.string(), image.GetBufferLength(), bytes));
            }
            std::byte* out = shared.data() + n * bytes;
            if (!image.GetBuffer(reinterpret_cast<char*>(out))) {
                const char* syntax = gdcm::TransferSyntax::GetTSString(
                    reader.GetFile().GetHeader().GetDataSetTransferSyntax());
                throw IoError(fmt::format(
                    "{}: cannot decode the DICOM pixel data (transfer syntax {}): this GDCM has "
                    "no codec for it, or the data is corrupt",
                    file.string(), syntax != nullptr ? syntax : "unknown"));
            }
            DecodedFile d;
            d.format = format;
            d.lo = std::numeric_limits<double>::infinity();
            d.hi = -d.lo;
            for (std::size_t i = 0; i < per_file; ++i) {
                const double v = stored_value(out, i, format.scalar);
                d.lo = std::min(d.lo, v);
                d.hi = std::max(d.hi, v);
            }
            d.slope = image.GetSlope();
            d.intercept = image.GetIntercept();
            if (!std::isfinite(d.slope) || d.slope == 0.0 || !std::isfinite(d.intercept)) {
                throw IoError(
                    fmt::format("{}: RescaleSlope {} / RescaleIntercept {}: expected finite "
                                "numbers, a slope other than 0",
                                file.string(), d.slope, d.intercept));
            }
            ByteWriter w;
            w.put(d);
            channel.send(w.bytes());
        }
    };
    const ForkedResult run = run_forked(limits, decode_all, [&](std::span<const std::byte> record) {
        ByteReader r(record, "the GDCM decoding");
        const auto d = r.get<DecodedFile>("file");
        if (px.slopes.empty()) {
            px.format = d.format;
        }
        px.slopes.push_back(d.slope);
        px.intercepts.push_back(d.intercept);
        px.stored_min.push_back(d.lo);
        px.stored_max.push_back(d.hi);
    });
    if (!run.completed) {
        throw IoError(fmt::format("{}: GDCM could not parse it: {}",
                                  slices.at(px.slopes.size()).file.string(), run.failure));
    }
    px.raw = shared.first(per_file * slices.size() * px.format.bytes);
    return px;
}

// The voxel type of the rescaled values (see dicom.hpp) and fills the volume.
volume::Volume rescaled(const Pixels& px, const volume::Dims& dims, std::size_t files,
                        std::size_t max_bytes) {
    bool identity = true;
    bool integral = true;
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (std::size_t n = 0; n < files; ++n) {
        const double s = px.slopes[n];
        const double b = px.intercepts[n];
        identity = identity && s == 1.0 && b == 0.0;
        integral = integral && s == std::round(s) && b == std::round(b);
        for (const double v : {px.stored_min[n], px.stored_max[n]}) {
            lo = std::min(lo, v * s + b);
            hi = std::max(hi, v * s + b);
        }
    }
    const auto scalar = px.format.scalar;
    const bool stored_integer =
        scalar != gdcm::PixelFormat::FLOAT32 && scalar != gdcm::PixelFormat::FLOAT64;
    VoxelType type = VoxelType::f32;
    if (identity && scalar == gdcm::PixelFormat::UINT8) {
        type = VoxelType::u8;
    } else if (stored_integer && integral && lo >= -32768.0 && hi <= 32767.0) {
        type = VoxelType::i16;
    } else if (identity &&
               (scalar == gdcm::PixelFormat::UINT16 || scalar == gdcm::PixelFormat::UINT12)) {
        type = VoxelType::u16;
    }
    volume::Volume v = volume::Volume::allocate(dims, type, {1, 1, 1}, {0, 0, 0}, max_bytes);
    const auto count = static_cast<std::size_t>(v.num_voxels());
    const std::size_t per = count / files;
    const auto fill = [&]<typename T>(std::span<T> out) {
        for (std::size_t n = 0; n < files; ++n) {
            const double s = px.slopes[n];
            const double b = px.intercepts[n];
            for (std::size_t i = n * per; i < (n + 1) * per; ++i) {
                const double value = stored_value(px.raw.data(), i, scalar) * s + b;
                out[i] = static_cast<T>(value);
            }
        }
    };
    switch (type) {
        case VoxelType::u8:
            fill(v.values<VoxelType::u8>());
            break;
        case VoxelType::i16:
            fill(v.values<VoxelType::i16>());
            break;
        case VoxelType::u16:
            fill(v.values<VoxelType::u16>());
            break;
        default:
            fill(v.values<VoxelType::f32>());
            break;
    }
    return v;
}

std::string name_of(const Slice& s) {
    return s.file.filename().string();
}

// Checks that the slices make one regular grid, sorts them along the normal, and returns where
// the grid lies (LPS → RAS) with its slice step.
volume::GridPlacement slice_geometry(const fs::path& where, std::vector<Slice>& slices) {
    const Slice& first = slices.front();
    for (const Slice& s : slices) {
        if (s.frames != 1) {
            throw InvalidInput(fmt::format(
                "{}: a multi-frame file ({}, {} frames) in a series of {} files: expected single "
                "slices or one multi-frame file",
                where.string(), name_of(s), s.frames, slices.size()));
        }
        if (s.rows != first.rows || s.columns != first.columns) {
            throw InvalidInput(fmt::format(
                "{}: slices of mixed sizes in one series: {} is {}x{}, {} is {}x{} (columns x "
                "rows)",
                where.string(), name_of(first), first.columns, first.rows, name_of(s), s.columns,
                s.rows));
        }
    }
    // In-plane spacing.
    std::array<double, 2> pixel_spacing{1.0, 1.0};
    if (first.pixel_spacing) {
        pixel_spacing = *first.pixel_spacing;
        if (!(pixel_spacing[0] > 0) || !(pixel_spacing[1] > 0)) {
            throw IoError(fmt::format("{}: PixelSpacing {}\\{}: expected numbers > 0",
                                      first.file.string(), pixel_spacing[0], pixel_spacing[1]));
        }
        if (first.imager_spacing) {
            log_warning("{}: no PixelSpacing; using ImagerPixelSpacing {}\\{} mm", where.string(),
                        pixel_spacing[0], pixel_spacing[1]);
        }
    } else {
        log_warning("{}: no PixelSpacing; using 1 mm", where.string());
    }
    for (const Slice& s : slices) {
        const std::array<double, 2> ps = s.pixel_spacing.value_or(std::array<double, 2>{1, 1});
        if (std::abs(ps[0] - pixel_spacing[0]) > 1e-4 * pixel_spacing[0] ||
            std::abs(ps[1] - pixel_spacing[1]) > 1e-4 * pixel_spacing[1]) {
            throw InvalidInput(fmt::format(
                "{}: slices with different pixel spacings in one series: {} has {}\\{} mm, {} "
                "has {}\\{} mm",
                where.string(), name_of(first), pixel_spacing[0], pixel_spacing[1], name_of(s),
                ps[0], ps[1]));
        }
    }
    // Orientation.
    std::array<Vec3d, 2> cosines{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};
    if (first.orientation) {
        cosines = *first.orientation;
    } else {
        log_warning(R"({}: no ImageOrientationPatient; assuming axial slices (1\0\0\0\1\0))",
                    where.string());
    }
    for (const Slice& s : slices) {
        const std::array<Vec3d, 2> o = s.orientation.value_or(cosines);
        if (norm(o[0] - cosines[0]) > ORIENTATION_TOLERANCE ||
            norm(o[1] - cosines[1]) > ORIENTATION_TOLERANCE) {
            throw InvalidInput(fmt::format(
                "{}: slices with different orientations in one series: {} has {} {}, {} has {} "
                "{} (ImageOrientationPatient)",
                where.string(), name_of(first), vec_text(cosines[0]), vec_text(cosines[1]),
                name_of(s), vec_text(o[0]), vec_text(o[1])));
        }
    }
    const double row_length = norm(cosines[0]);
    const double column_length = norm(cosines[1]);
    if (!(row_length > 0.5) || !(column_length > 0.5) ||
        std::abs(dot(cosines[0], cosines[1])) / (row_length * column_length) >
            volume::MAX_AXIS_COSINE) {
        throw IoError(
            fmt::format("{}: ImageOrientationPatient {} {}: expected two orthogonal "
                        "unit vectors",
                        first.file.string(), vec_text(cosines[0]), vec_text(cosines[1])));
    }
    const Vec3d row = cosines[0] / row_length;
    const Vec3d column = cosines[1] / column_length;
    const Vec3d normal = cross(row, column) / norm(cross(row, column));

    // Order along the normal.
    std::size_t with_position = 0;
    for (const Slice& s : slices) {
        with_position += s.position ? 1 : 0;
    }
    double step = 1.0;
    Vec3d position0{0, 0, 0};
    if (with_position == 0) {
        std::stable_sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) {
            return a.instance.value_or(0) < b.instance.value_or(0);
        });
        step = first.spacing_between_slices.value_or(first.slice_thickness.value_or(1.0));
        if (!(step > 0)) {
            step = 1.0;
        }
        if (slices.size() > 1) {
            log_warning(
                "{}: no ImagePositionPatient: slices ordered by InstanceNumber, {} mm "
                "apart (SpacingBetweenSlices, else SliceThickness, else 1)",
                where.string(), step);
        }
    } else {
        for (const Slice& s : slices) {
            if (!s.position) {
                throw InvalidInput(fmt::format(
                    "{}: {} has no ImagePositionPatient (the other slices have one): its place "
                    "in the volume is unknown",
                    where.string(), name_of(s)));
            }
        }
        for (Slice& s : slices) {
            s.along = dot(*s.position, normal);
        }
        std::stable_sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) {
            if (a.along != b.along) {
                return a.along < b.along;
            }
            return a.file < b.file;
        });
        position0 = *slices.front().position;
        if (slices.size() > 1) {
            std::vector<double> gaps;
            for (std::size_t n = 0; n + 1 < slices.size(); ++n) {
                gaps.push_back(slices[n + 1].along - slices[n].along);
            }
            for (std::size_t n = 0; n < gaps.size(); ++n) {
                if (gaps[n] <= POSITION_TOLERANCE_MM) {
                    throw InvalidInput(fmt::format(
                        "{}: two slices at one position ({:g} mm along the normal): {} and {} "
                        "(several phases, echoes or acquisitions in one series are not "
                        "supported; choose another series with --series UID)",
                        where.string(), slices[n].along, name_of(slices[n]),
                        name_of(slices[n + 1])));
                }
            }
            std::vector<double> sorted = gaps;
            std::nth_element(sorted.begin(),
                             sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                             sorted.end());
            const double typical = sorted[sorted.size() / 2];
            const double tolerance =
                std::max(POSITION_TOLERANCE_MM, RELATIVE_GAP_TOLERANCE * typical);
            std::size_t regular = 0;  // a gap of the typical size, for messages
            for (std::size_t n = 0; n < gaps.size(); ++n) {
                if (std::abs(gaps[n] - typical) <= tolerance) {
                    regular = n;
                    break;
                }
            }
            for (std::size_t n = 0; n < gaps.size(); ++n) {
                if (std::abs(gaps[n] - typical) <= tolerance) {
                    continue;
                }
                const double multiple = std::round(gaps[n] / typical);
                if (multiple >= 2 &&
                    std::abs(gaps[n] - multiple * typical) <= multiple * tolerance) {
                    const auto missing = static_cast<std::int64_t>(multiple) - 1;
                    throw InvalidInput(fmt::format(
                        "{}: {} slice{} missing between {} (at {:g} mm) and {} (at {:g} mm): they "
                        "are {:g} mm apart, the other slices {:g} mm",
                        where.string(), missing, missing == 1 ? "" : "s", name_of(slices[n]),
                        slices[n].along, name_of(slices[n + 1]), slices[n + 1].along, gaps[n],
                        typical));
                }
                throw InvalidInput(fmt::format(
                    "{}: uneven slice spacing: {:g} mm between {} and {}, {:g} mm between {} and "
                    "{} (a volume needs one spacing)",
                    where.string(), gaps[regular], name_of(slices[regular]),
                    name_of(slices[regular + 1]), gaps[n], name_of(slices[n]),
                    name_of(slices[n + 1])));
            }
            step = (slices.back().along - slices.front().along) /
                   static_cast<double>(slices.size() - 1);
            // Slices offset within their plane (gantry tilt): placed along the normal.
            const Vec3d span = *slices.back().position - *slices.front().position;
            const double cosine = std::min(1.0, std::abs(dot(span, normal)) / norm(span));
            const double degrees = std::acos(cosine) * 180.0 / 3.14159265358979323846;
            if (degrees > GANTRY_TILT_WARNING_DEGREES) {
                log_warning(
                    "{}: the slices are offset within their plane (gantry tilt of "
                    "{:.2f}°): placed along the slice normal, so in-plane positions are "
                    "off by up to {:.3g} mm",
                    where.string(), degrees, norm(span) * std::sin(std::acos(cosine)));
            }
        } else {
            step = first.spacing_between_slices.value_or(first.slice_thickness.value_or(1.0));
            if (!(step > 0)) {
                step = 1.0;
            }
        }
    }
    volume::GridPlacement grid;
    grid.centre0 = ras(position0);
    grid.steps = {ras(row) * pixel_spacing[1], ras(column) * pixel_spacing[0], ras(normal) * step};
    grid.lengths = {pixel_spacing[1], pixel_spacing[0], step};
    return grid;
}

// One multi-frame file: GDCM's own geometry (it reads the functional groups of enhanced files),
// read in a child process like the pixels.
volume::GridPlacement multiframe_geometry(const fs::path& file, double seconds) {
    std::array<double, 12> g{};  // origin, direction cosines (row, column), spacing
    bool received = false;
    const ForkedResult run = run_forked(
        gdcm_limits(largest_file({file.string()}), 0, seconds),
        [&](ForkChannel& channel) {
            quiet_gdcm();
            gdcm::ImageReader reader;
            reader.SetFileName(file.c_str());
            if (!reader.Read()) {
                throw IoError(fmt::format("{}: cannot read the DICOM image", file.string()));
            }
            const gdcm::Image& image = reader.GetImage();
            std::array<double, 12> out{};
            std::copy_n(image.GetOrigin(), 3, out.begin());
            std::copy_n(image.GetDirectionCosines(), 6, out.begin() + 3);
            std::copy_n(image.GetSpacing(), 3, out.begin() + 9);
            ByteWriter w;
            w.put(out);
            channel.send(w.bytes());
        },
        [&](std::span<const std::byte> record) {
            ByteReader r(record, "the GDCM geometry");
            g = r.get<std::array<double, 12>>("geometry");
            received = true;
        });
    if (!run.completed || !received) {
        throw IoError(fmt::format("{}: GDCM could not parse it: {}", file.string(),
                                  run.failure.empty() ? "no geometry" : run.failure));
    }
    const double* o = g.data();
    const double* d = g.data() + 3;
    const double* s = g.data() + 9;
    const Vec3d row{d[0], d[1], d[2]};
    const Vec3d column{d[3], d[4], d[5]};
    const Vec3d normal = cross(row, column);
    if (!(norm(normal) > 0.5)) {
        throw IoError(fmt::format("{}: the image orientation {} {} is degenerate", file.string(),
                                  vec_text(row), vec_text(column)));
    }
    volume::GridPlacement grid;
    grid.centre0 = ras({o[0], o[1], o[2]});
    const std::array<double, 3> spacing{s[0] > 0 ? s[0] : 1.0, s[1] > 0 ? s[1] : 1.0,
                                        s[2] > 0 ? s[2] : 1.0};
    grid.steps = {ras(row / norm(row)) * spacing[0], ras(column / norm(column)) * spacing[1],
                  ras(normal / norm(normal)) * spacing[2]};
    grid.lengths = spacing;
    return grid;
}

volume::Volume read_slices(const fs::path& where, std::vector<Slice> slices,
                           const DicomReadOptions& options) {
    const std::size_t max_bytes = options.max_bytes;
    const double seconds = options.gdcm_seconds;
    const DicomSeriesInfo info = info_of(slices);
    volume::GridPlacement grid;
    if (slices.size() == 1 && slices.front().frames > 1) {
        grid = multiframe_geometry(slices.front().file, seconds);
    } else {
        grid = slice_geometry(where, slices);
    }
    const volume::Dims dims = info.dims;
    detail::check_declared_size(where, dims, VoxelType::u8, max_bytes);
    const Pixels px = read_pixels(slices, dims, max_bytes, where, seconds);
    volume::Volume v = rescaled(px, dims, slices.size(), max_bytes);
    return volume::place_nearest_axes(std::move(v), grid);
}

}  // namespace

bool has_dicom_support() {
    return true;
}

std::vector<DicomSeriesInfo> list_dicom_series(const fs::path& path) {
    std::error_code ec;
    const fs::path dir = fs::is_directory(path, ec) ? path : path.parent_path();
    return listing(by_series(scan(candidate_files(dir), false)));
}

std::vector<DicomSeriesInfo> list_dicom_series(std::span<const fs::path> files) {
    return listing(by_series(scan({files.begin(), files.end()}, true)));
}

std::string chosen_dicom_series(const fs::path& path, const std::string& series_uid) {
    if (!series_uid.empty()) {
        return series_uid;
    }
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        const std::vector<DicomSeriesInfo> all = list_dicom_series(path);
        return all.empty() ? std::string() : all.front().uid;
    }
    return scan({path}, true).front().series_uid;
}

volume::Volume read_dicom_series(const fs::path& path, const DicomReadOptions& options) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        const std::vector<fs::path> files = candidate_files(path);
        return read_slices(path,
                           choose(path, by_series(scan(files, false, options.gdcm_seconds)),
                                  options.series_uid, files.size()),
                           options);
    }
    if (!fs::exists(path, ec)) {
        throw IoError(fmt::format("{}: no such file or folder", path.string()));
    }
    // One file: the series it belongs to, from its folder (itself alone when multi-frame).
    const std::vector<Slice> own = scan({path}, true, options.gdcm_seconds);
    const Slice& self = own.front();
    if (self.frames > 1) {
        return read_slices(path, own, options);
    }
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const std::vector<fs::path> files = candidate_files(dir);
    std::map<std::string, std::vector<Slice>> series =
        by_series(scan(files, false, options.gdcm_seconds));
    const std::string uid = options.series_uid.empty() ? self.series_uid : options.series_uid;
    if (series.count(uid) == 0) {
        series[self.series_uid].push_back(self);  // the file's folder did not list it
    }
    return read_slices(dir, choose(dir, std::move(series), uid, files.size()), options);
}

volume::Volume read_dicom_series(std::span<const fs::path> files, const DicomReadOptions& options) {
    if (files.empty()) {
        throw InvalidInput("read_dicom_series: no files given");
    }
    const fs::path where = files.front().parent_path();
    return read_slices(
        where,
        choose(where, by_series(scan({files.begin(), files.end()}, true, options.gdcm_seconds)),
               options.series_uid, files.size()),
        options);
}

#endif

}  // namespace pliant::io
