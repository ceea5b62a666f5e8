#include "pliant/io/metaimage.hpp"

#include <fmt/format.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/detail/volume_data.hpp"
#include "pliant/volume/reorient.hpp"

namespace pliant::io {

namespace {

using detail::lower;
using detail::trim;
using detail::words;

using volume::VoxelType;

constexpr std::size_t MAX_HEADER_BYTES = std::size_t{1} << 20;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
    throw IoError(fmt::format("{}: {}", path.string(), message));
}

struct Header {
    std::map<std::string, std::string> fields;  // key as written → value
    std::uint64_t data_offset = 0;              // LOCAL data starts here
};

// `Key = Value` lines up to and including ElementDataFile.
Header read_header(const std::filesystem::path& path) {
    const std::uint64_t size = detail::file_size(path);
    if (size == 0) {
        fail(path,
             "empty file, expected a MetaImage header ('ObjectType = Image', 'NDims = 3', …)");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        fail(path, "cannot open for reading");
    }
    Header header;
    std::string line;
    std::uint64_t consumed = 0;
    int number = 0;
    while (std::getline(in, line)) {
        consumed += line.size() + 1;
        ++number;
        if (consumed > MAX_HEADER_BYTES) {
            fail(path, fmt::format("MetaImage header longer than {} bytes without ElementDataFile",
                                   MAX_HEADER_BYTES));
        }
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (trim(line).empty()) {
            continue;
        }
        const std::size_t equals = line.find('=');
        const std::string key = equals == std::string::npos ? "" : trim(line.substr(0, equals));
        if (key.empty()) {
            if (header.fields.empty()) {
                fail(path, fmt::format("not a MetaImage header: expected 'Key = Value' lines "
                                       "('ObjectType = Image', 'NDims = 3', …), got {}",
                                       detail::quote(line)));
            }
            fail(path, fmt::format("MetaImage header line {}: expected 'Key = Value', got {}",
                                   number, detail::quote(line)));
        }
        for (const char c : key) {
            if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '_' && c != '-' &&
                c != ' ') {
                fail(path, fmt::format("MetaImage header line {}: expected a key of letters and "
                                       "digits, got {}",
                                       number, detail::quote(key)));
            }
        }
        if (header.fields.count(key) != 0) {
            fail(path, fmt::format("MetaImage key {} appears twice (line {})", key, number));
        }
        header.fields[key] = trim(line.substr(equals + 1));
        if (key == "ElementDataFile") {
            header.data_offset = consumed;
            return header;
        }
    }
    if (header.fields.empty()) {
        fail(path, "not a MetaImage header: expected 'Key = Value' lines");
    }
    fail(path,
         "MetaImage header has no ElementDataFile key (it ends the header and says where "
         "the voxels are)");
}

// The value of the first of `keys` present (aliases), with the key found.
std::optional<std::pair<std::string, std::string>> find(const Header& header,
                                                        std::initializer_list<const char*> keys) {
    for (const char* key : keys) {
        if (const auto it = header.fields.find(key); it != header.fields.end()) {
            return std::make_pair(it->first, it->second);
        }
    }
    return std::nullopt;
}

const std::string& required(const Header& header, const std::filesystem::path& path,
                            const char* key) {
    const auto it = header.fields.find(key);
    if (it == header.fields.end()) {
        fail(path, fmt::format("MetaImage header has no {} key", key));
    }
    return it->second;
}

bool parse_bool(const std::filesystem::path& path, const std::string& key,
                const std::string& value) {
    const std::string v = lower(value);
    if (v == "true" || v == "t" || v == "1") {
        return true;
    }
    if (v == "false" || v == "f" || v == "0") {
        return false;
    }
    fail(path, fmt::format("{}: expected True or False, got {}", key, detail::quote(value)));
}

std::int64_t parse_int(const std::filesystem::path& path, const std::string& key,
                       const std::string& value) {
    std::int64_t v = 0;
    if (detail::parse_integer(trim(value), v) != detail::ParseStatus::ok) {
        fail(path, fmt::format("{}: expected an integer, got {}", key, detail::quote(value)));
    }
    return v;
}

std::vector<double> parse_reals(const std::filesystem::path& path, const std::string& key,
                                const std::string& value, std::size_t count) {
    const std::vector<std::string> tokens = words(value);
    if (tokens.size() != count) {
        fail(path, fmt::format("{}: expected {} numbers, got {} ({})", key, count, tokens.size(),
                               detail::quote(value)));
    }
    std::vector<double> out;
    for (const std::string& t : tokens) {
        double v = 0;
        if (detail::parse_real(t, v) != detail::ParseStatus::ok || !std::isfinite(v)) {
            fail(path, fmt::format("{}: expected finite numbers, got {}", key, detail::quote(t)));
        }
        out.push_back(v);
    }
    return out;
}

const char* element_type_name(VoxelType type) {
    switch (type) {
        case VoxelType::u8:
        case VoxelType::rgba8:
            return "MET_UCHAR";
        case VoxelType::i16:
            return "MET_SHORT";
        case VoxelType::u16:
            return "MET_USHORT";
        case VoxelType::f32:
        case VoxelType::rgba32f:
            return "MET_FLOAT";
    }
    return "?";
}

// +0 for −0, so that written headers never show "-0".
double positive_zero(double v) {
    return v + 0.0;
}

}  // namespace

volume::Volume read_metaimage(const std::filesystem::path& path, std::size_t max_bytes) {
    const Header header = read_header(path);

    // Object and dimensions.
    if (const auto object = find(header, {"ObjectType"});
        object && lower(object->second) != "image") {
        throw Unsupported(fmt::format("{}: ObjectType: expected Image, got {}", path.string(),
                                      detail::quote(object->second)));
    }
    const std::int64_t ndims = parse_int(path, "NDims", required(header, path, "NDims"));
    if (ndims != 2 && ndims != 3) {
        throw Unsupported(fmt::format("{}: NDims: expected 2 or 3 (an image or a volume), got {}",
                                      path.string(), ndims));
    }
    const auto n = static_cast<std::size_t>(ndims);
    const std::vector<std::string> size_words = words(required(header, path, "DimSize"));
    if (size_words.size() != n) {
        fail(path,
             fmt::format("DimSize: expected {} sizes (NDims), got {} ({})", n, size_words.size(),
                         detail::quote(required(header, path, "DimSize"))));
    }
    volume::Dims dims{1, 1, 1};
    for (std::size_t a = 0; a < n; ++a) {
        dims[a] = parse_int(path, "DimSize", size_words[a]);
    }

    // Voxel type.
    std::int64_t channels = 1;
    if (const auto c = find(header, {"ElementNumberOfChannels"})) {
        channels = parse_int(path, c->first, c->second);
    }
    const std::string& element = required(header, path, "ElementType");
    std::optional<VoxelType> type;
    if (channels == 1) {
        type = element == "MET_UCHAR"    ? std::optional(VoxelType::u8)
               : element == "MET_SHORT"  ? std::optional(VoxelType::i16)
               : element == "MET_USHORT" ? std::optional(VoxelType::u16)
               : element == "MET_FLOAT"  ? std::optional(VoxelType::f32)
                                         : std::nullopt;
    } else if (channels == 4) {
        type = element == "MET_UCHAR"   ? std::optional(VoxelType::rgba8)
               : element == "MET_FLOAT" ? std::optional(VoxelType::rgba32f)
                                        : std::nullopt;
    } else {
        throw Unsupported(
            fmt::format("{}: ElementNumberOfChannels: expected 1 (scalar) or 4 (RGBA), got {}",
                        path.string(), channels));
    }
    if (!type) {
        throw Unsupported(fmt::format(
            "{}: ElementType: expected MET_UCHAR, MET_SHORT, MET_USHORT or MET_FLOAT (MET_UCHAR "
            "or MET_FLOAT with 4 channels), got {}{}",
            path.string(), detail::quote(element), channels == 4 ? " with 4 channels" : ""));
    }

    // Encoding.
    if (const auto binary = find(header, {"BinaryData"});
        binary && !parse_bool(path, binary->first, binary->second)) {
        throw Unsupported(
            fmt::format("{}: BinaryData = False (voxels as text) is not supported, expected True",
                        path.string()));
    }
    bool big_endian = false;
    if (const auto msb = find(header, {"BinaryDataByteOrderMSB", "ElementByteOrderMSB"})) {
        big_endian = parse_bool(path, msb->first, msb->second);
    }
    bool compressed = false;
    if (const auto c = find(header, {"CompressedData"})) {
        compressed = parse_bool(path, c->first, c->second);
    }
    std::optional<std::int64_t> compressed_size;
    if (const auto c = find(header, {"CompressedDataSize"})) {
        compressed_size = parse_int(path, c->first, c->second);
        if (*compressed_size < 1) {
            fail(path,
                 fmt::format("CompressedDataSize: expected a size ≥ 1, got {}", *compressed_size));
        }
    }

    // Placement: TransformMatrix columns × ElementSpacing, Offset the first voxel's centre; LPS
    // (ITK) → RAS+ (pliant): x and y negated.
    std::array<double, 3> spacing{1, 1, 1};
    if (const auto s = find(header, {"ElementSpacing", "ElementSize"})) {
        const std::vector<double> v = parse_reals(path, s->first, s->second, n);
        for (std::size_t a = 0; a < n; ++a) {
            if (!(v[a] > 0)) {
                fail(path, fmt::format("{}: expected numbers > 0, got {} for axis {}", s->first,
                                       v[a], a));
            }
            spacing[a] = v[a];
        }
    }
    volume::GridPlacement grid;
    if (const auto o = find(header, {"Offset", "Origin", "Position"})) {
        const std::vector<double> v = parse_reals(path, o->first, o->second, n);
        grid.centre0 = {-v[0], -v[1], n == 3 ? v[2] : 0.0};
    }
    volume::Direction direction = volume::IDENTITY_DIRECTION;
    if (const auto m = find(header, {"TransformMatrix", "Rotation", "Orientation"})) {
        const std::vector<double> v = parse_reals(path, m->first, m->second, n * n);
        for (std::size_t a = 0; a < n; ++a) {
            Vec3d column{v[a * n], v[a * n + 1], n == 3 ? v[a * n + 2] : 0.0};
            const double length = norm(column);
            if (!(length > 0)) {
                fail(path, fmt::format("{}: the direction of axis {} is zero", m->first, a));
            }
            direction[a] = column / length;
        }
    }
    for (std::size_t a = 0; a < 3; ++a) {
        const Vec3d d = direction[a];
        grid.steps[a] = Vec3d{-d.x, -d.y, d.z} * spacing[a];
        grid.lengths[a] = spacing[a];
    }
    if (const double cosine = volume::max_axis_cosine(grid); !(cosine <= volume::MAX_AXIS_COSINE)) {
        throw Unsupported(fmt::format(
            "{}: TransformMatrix is sheared (its axes are not orthogonal: largest |cosine| "
            "{:.3g}, expected at most {}): a sheared grid cannot be placed without resampling",
            path.string(), cosine, volume::MAX_AXIS_COSINE));
    }

    // Data location.
    const std::string& data_file = required(header, path, "ElementDataFile");
    std::int64_t header_size = 0;
    if (const auto h = find(header, {"HeaderSize"})) {
        header_size = parse_int(path, h->first, h->second);
        if (header_size < -1) {
            fail(path, fmt::format("HeaderSize: expected a size ≥ 0 or -1, got {}", header_size));
        }
    }
    std::filesystem::path data_path = path;
    std::uint64_t offset = header.data_offset;
    if (data_file == "LOCAL" || lower(data_file) == "local") {
        if (header_size != 0) {
            throw Unsupported(fmt::format(
                "{}: HeaderSize {} with ElementDataFile = LOCAL is not supported, expected 0",
                path.string(), header_size));
        }
    } else {
        if (data_file.empty() || data_file.rfind("LIST", 0) == 0 ||
            data_file.find('%') != std::string::npos) {
            throw Unsupported(fmt::format(
                "{}: ElementDataFile {}: lists and file patterns (one file per slice) are not "
                "supported, expected LOCAL or one file name",
                path.string(), detail::quote(data_file)));
        }
        const std::filesystem::path name(data_file);
        data_path = name.is_absolute() ? name : path.parent_path() / name;
        std::error_code ec;
        if (!std::filesystem::exists(data_path, ec)) {
            fail(path, fmt::format("ElementDataFile: {} does not exist", data_path.string()));
        }
        offset = header_size > 0 ? static_cast<std::uint64_t>(header_size) : 0;
    }

    // Size checks before allocating, then the data straight into the volume.
    const std::size_t bytes = detail::check_declared_size(path, dims, *type, max_bytes);
    const std::uint64_t file_bytes = detail::file_size(data_path);
    if (header_size == -1) {
        if (compressed) {
            fail(path, "HeaderSize = -1 (data at the end of the file) needs uncompressed data");
        }
        if (file_bytes < bytes) {
            fail(data_path, fmt::format("truncated voxel data: DimSize {} of {} declares {} "
                                        "bytes, the file has {}",
                                        detail::dims_text(dims), element, bytes, file_bytes));
        }
        offset = file_bytes - bytes;
    }
    if (!compressed && (file_bytes < offset || file_bytes - offset < bytes)) {
        fail(data_path, fmt::format("truncated voxel data: DimSize {} of {} declares {} bytes, "
                                    "the file has {} after byte offset {}",
                                    detail::dims_text(dims), element, bytes,
                                    file_bytes > offset ? file_bytes - offset : 0, offset));
    }
    if (compressed && compressed_size &&
        (file_bytes < offset ||
         file_bytes - offset < static_cast<std::uint64_t>(*compressed_size))) {
        fail(data_path,
             fmt::format("truncated compressed data: CompressedDataSize is {}, the "
                         "file has {} bytes after byte offset {}",
                         *compressed_size, file_bytes > offset ? file_bytes - offset : 0, offset));
    }
    volume::Volume volume = volume::Volume::allocate(dims, *type, {1, 1, 1}, {0, 0, 0}, max_bytes);
    if (compressed) {
        detail::read_gzip_data(data_path, offset, volume.bytes());
    } else {
        detail::read_raw_data(data_path, offset, volume.bytes(), true);
    }
    if (big_endian) {
        detail::swap_channel_bytes(volume);
    }
    return volume::place_nearest_axes(std::move(volume), grid);
}

void write_metaimage(const std::filesystem::path& path, const volume::Volume& volume,
                     bool compressed, bool detached) {
    if (volume.empty()) {
        throw InvalidInput(fmt::format("write_metaimage: {}: the volume is empty", path.string()));
    }
    const std::span<const std::byte> bytes = volume.bytes();
    std::string packed;
    if (compressed) {
        std::ostringstream out;
        detail::write_zlib(out, bytes);
        packed = std::move(out).str();
    }
    // pliant's RAS+ → ITK's LPS: x and y negated.
    const auto lps = [](const Vec3d& v) {
        return Vec3d{positive_zero(-v.x), positive_zero(-v.y), positive_zero(v.z)};
    };
    const volume::Direction& d = volume.direction();
    const Vec3d c = lps(volume.voxel_center(0, 0, 0));
    const Vec3d& s = volume.spacing();
    const volume::Dims& n = volume.dims();
    std::string header =
        "ObjectType = Image\nNDims = 3\nBinaryData = True\n"
        "BinaryDataByteOrderMSB = False\n";
    header += fmt::format("CompressedData = {}\n", compressed ? "True" : "False");
    if (compressed) {
        header += fmt::format("CompressedDataSize = {}\n", packed.size());
    }
    header += "TransformMatrix =";
    for (std::size_t a = 0; a < 3; ++a) {
        const Vec3d column = lps(d[a]);
        header += fmt::format(" {} {} {}", column.x, column.y, column.z);
    }
    header += fmt::format("\nOffset = {} {} {}\n", c.x, c.y, c.z);
    header += "CenterOfRotation = 0 0 0\n";
    header += fmt::format("ElementSpacing = {} {} {}\n", s.x, s.y, s.z);
    header += fmt::format("DimSize = {} {} {}\n", n[0], n[1], n[2]);
    if (volume::channels(volume.type()) == 4) {
        header += "ElementNumberOfChannels = 4\n";
    }
    header += fmt::format("ElementType = {}\n", element_type_name(volume.type()));
    auto write_data = [&](std::ostream& out) {
        if (compressed) {
            out.write(packed.data(), static_cast<std::streamsize>(packed.size()));
        } else {
            out.write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
        }
    };
    std::filesystem::path data_path;
    if (detached) {
        data_path = path;
        data_path.replace_extension(compressed ? ".zraw" : ".raw");
        header += fmt::format("ElementDataFile = {}\n", data_path.filename().string());
    } else {
        header += "ElementDataFile = LOCAL\n";
    }
    detail::write_header_and_data(path, header, data_path, write_data);
}

}  // namespace pliant::io
