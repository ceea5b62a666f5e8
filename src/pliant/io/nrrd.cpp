#include "pliant/io/nrrd.hpp"

#include <fmt/format.h>

#include <algorithm>
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

struct Header {
    std::map<std::string, std::string> fields;  // lower-case field name → value
    std::uint64_t data_offset = 0;              // attached data starts here
};

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
    throw IoError(fmt::format("{}: {}", path.string(), message));
}

Header read_header(const std::filesystem::path& path) {
    const std::uint64_t size = detail::file_size(path);
    if (size == 0) {
        fail(path, "empty file, expected a NRRD header starting with 'NRRD000'");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        fail(path, "cannot open for reading");
    }
    Header header;
    std::string line;
    std::uint64_t consumed = 0;
    bool first = true;
    bool ended = false;
    while (std::getline(in, line)) {
        consumed += line.size() + 1;
        if (consumed > MAX_HEADER_BYTES) {
            fail(path, fmt::format("NRRD header longer than {} bytes without its blank line",
                                   MAX_HEADER_BYTES));
        }
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (first) {
            first = false;
            if (line.size() != 8 || line.rfind("NRRD000", 0) != 0 || line[7] < '1' ||
                line[7] > '5') {
                fail(path, fmt::format("not a NRRD file, expected a first line 'NRRD0001' to "
                                       "'NRRD0005', got {}",
                                       detail::quote(line)));
            }
            continue;
        }
        if (line.empty()) {
            ended = true;
            break;
        }
        if (line[0] == '#') {
            continue;
        }
        if (line.find(":=") != std::string::npos) {
            continue;  // key/value pair
        }
        const std::size_t colon = line.find(": ");
        if (colon == std::string::npos) {
            fail(path, fmt::format("malformed NRRD header line, expected 'field: value', got {}",
                                   detail::quote(line)));
        }
        std::string key = lower(trim(line.substr(0, colon)));
        if (key == "datafile") {
            key = "data file";
        } else if (key == "byteskip") {
            key = "byte skip";
        } else if (key == "lineskip") {
            key = "line skip";
        }
        header.fields[key] = trim(line.substr(colon + 2));
    }
    if (first) {
        fail(path, "not a NRRD file, expected a first line 'NRRD0001' to 'NRRD0005'");
    }
    // Attached data must follow a blank line; a detached header may simply end.
    if (!ended && header.fields.count("data file") == 0) {
        fail(path, "NRRD header has no blank line before the data, and no 'data file' field");
    }
    header.data_offset = consumed;
    return header;
}

const std::string& required(const Header& header, const std::filesystem::path& path,
                            const std::string& key) {
    const auto it = header.fields.find(key);
    if (it == header.fields.end()) {
        fail(path, fmt::format("NRRD header has no '{}' field", key));
    }
    return it->second;
}

std::optional<VoxelType> scalar_type(std::string type) {
    type = lower(type);
    if (type == "uchar" || type == "unsigned char" || type == "uint8" || type == "uint8_t") {
        return VoxelType::u8;
    }
    if (type == "short" || type == "short int" || type == "signed short" ||
        type == "signed short int" || type == "int16" || type == "int16_t") {
        return VoxelType::i16;
    }
    if (type == "ushort" || type == "unsigned short" || type == "unsigned short int" ||
        type == "uint16" || type == "uint16_t") {
        return VoxelType::u16;
    }
    if (type == "float") {
        return VoxelType::f32;
    }
    return std::nullopt;
}

double parse_double(const std::filesystem::path& path, const std::string& field,
                    const std::string& token) {
    double value = 0;
    if (detail::parse_real(token, value) != detail::ParseStatus::ok) {
        fail(path,
             fmt::format("NRRD '{}': expected a number, got {}", field, detail::quote(token)));
    }
    return value;
}

// "(1,0,0)" → the three numbers; "none" → nullopt.
std::optional<std::array<double, 3>> parse_vector(const std::filesystem::path& path,
                                                  const std::string& field, std::string text) {
    if (lower(text) == "none") {
        return std::nullopt;
    }
    if (text.size() < 2 || text.front() != '(' || text.back() != ')') {
        fail(path, fmt::format("NRRD '{}': expected a vector '(x,y,z)', got {}", field,
                               detail::quote(text)));
    }
    text = text.substr(1, text.size() - 2);
    std::array<double, 3> v{};
    std::size_t start = 0;
    for (int c = 0; c < 3; ++c) {
        const std::size_t comma = text.find(',', start);
        if ((c < 2) != (comma != std::string::npos)) {
            fail(path, fmt::format("NRRD '{}': expected a vector of 3 components, got {}", field,
                                   detail::quote(text)));
        }
        v[static_cast<std::size_t>(c)] =
            parse_double(path, field, trim(text.substr(start, comma - start)));
        start = comma + 1;
    }
    return v;
}

// Vectors in "(a,b,c) (d,e,f) none" text (vectors contain no spaces in NRRD files we write;
// spaces after commas are tolerated).
std::vector<std::string> split_vectors(const std::string& text) {
    std::vector<std::string> out;
    std::string current;
    int depth = 0;
    for (const char c : text) {
        if (c == '(') {
            ++depth;
        } else if (c == ')') {
            --depth;
        }
        if (std::isspace(static_cast<unsigned char>(c)) != 0 && depth == 0) {
            if (!current.empty()) {
                out.push_back(current);
                current.clear();
            }
            continue;
        }
        if (std::isspace(static_cast<unsigned char>(c)) == 0) {
            current.push_back(c);
        }
    }
    if (!current.empty()) {
        out.push_back(current);
    }
    return out;
}

std::string nrrd_type_name(VoxelType type) {
    switch (type) {
        case VoxelType::u8:
        case VoxelType::rgba8:
            return "uint8";
        case VoxelType::i16:
            return "int16";
        case VoxelType::u16:
            return "uint16";
        case VoxelType::f32:
        case VoxelType::rgba32f:
            return "float";
    }
    return "?";
}

}  // namespace

volume::Volume read_nrrd(const std::filesystem::path& path, std::size_t max_bytes) {
    const Header header = read_header(path);

    // Type and dimension.
    const std::string& type_text = required(header, path, "type");
    const std::optional<VoxelType> scalar = scalar_type(type_text);
    if (!scalar) {
        throw Unsupported(fmt::format(
            "{}: NRRD type {} is not supported, expected uchar, short, ushort or float (or a "
            "synonym: uint8, int16, uint16, …)",
            path.string(), detail::quote(type_text)));
    }
    std::int64_t dimension = 0;
    if (detail::parse_integer(required(header, path, "dimension"), dimension) !=
        detail::ParseStatus::ok) {
        fail(path, fmt::format("NRRD 'dimension': expected an integer, got {}",
                               detail::quote(required(header, path, "dimension"))));
    }
    if (dimension != 3 && dimension != 4) {
        throw Unsupported(fmt::format(
            "{}: NRRD dimension {} is not supported, expected 3 (scalar volume) or 4 (RGBA "
            "volume with a leading axis of size 4)",
            path.string(), dimension));
    }
    const std::vector<std::string> size_words = words(required(header, path, "sizes"));
    if (static_cast<std::int64_t>(size_words.size()) != dimension) {
        fail(path, fmt::format("NRRD 'sizes': expected {} sizes (the dimension), got {}", dimension,
                               size_words.size()));
    }
    std::vector<std::int64_t> sizes;
    for (const std::string& w : size_words) {
        std::int64_t s = 0;
        if (detail::parse_integer(w, s) != detail::ParseStatus::ok) {
            fail(path, fmt::format("NRRD 'sizes': expected integers, got {}", detail::quote(w)));
        }
        sizes.push_back(s);
    }
    VoxelType type = *scalar;
    const std::size_t first_spatial = dimension == 4 ? 1 : 0;
    if (dimension == 4) {
        if (sizes[0] != 4) {
            throw Unsupported(
                fmt::format("{}: NRRD with 4 axes needs a leading RGBA axis of size 4, got size {}",
                            path.string(), sizes[0]));
        }
        if (type == VoxelType::u8) {
            type = VoxelType::rgba8;
        } else if (type == VoxelType::f32) {
            type = VoxelType::rgba32f;
        } else {
            throw Unsupported(fmt::format("{}: NRRD RGBA volumes must be uchar or float, got {}",
                                          path.string(), detail::quote(type_text)));
        }
    }
    const volume::Dims dims{sizes[first_spatial], sizes[first_spatial + 1],
                            sizes[first_spatial + 2]};

    // Encoding and byte order.
    std::string encoding = "raw";
    if (const auto it = header.fields.find("encoding"); it != header.fields.end()) {
        encoding = lower(it->second);
    } else {
        fail(path, "NRRD header has no 'encoding' field");
    }
    const bool gzip = encoding == "gzip" || encoding == "gz";
    if (!gzip && encoding != "raw") {
        throw Unsupported(fmt::format("{}: NRRD encoding {} is not supported, expected raw or gzip",
                                      path.string(), detail::quote(encoding)));
    }
    bool big_endian = false;
    if (const auto it = header.fields.find("endian"); it != header.fields.end()) {
        const std::string endian = lower(it->second);
        if (endian != "little" && endian != "big") {
            fail(path, fmt::format("NRRD 'endian': expected little or big, got {}",
                                   detail::quote(endian)));
        }
        big_endian = endian == "big";
    } else if (volume::bytes_per_channel(type) > 1) {
        fail(path, "NRRD header has no 'endian' field, required for multi-byte types");
    }

    // Placement: the steps along i, j, k and the first voxel's centre, in the file's space,
    // converted to pliant's RAS+ world (LPS: x and y negated; LAS: x negated).
    std::string space;
    if (const auto it = header.fields.find("space"); it != header.fields.end()) {
        space = lower(it->second);
    }
    const bool negate_x = space == "left-posterior-superior" || space == "lps" ||
                          space == "left-anterior-superior" || space == "las";
    const bool negate_y = space == "left-posterior-superior" || space == "lps";
    const auto to_world = [&](std::array<double, 3> v) {
        return Vec3d{negate_x ? -v[0] : v[0], negate_y ? -v[1] : v[1], v[2]};
    };
    volume::GridPlacement grid;
    bool has_centre0 = false;
    if (const auto it = header.fields.find("space directions"); it != header.fields.end()) {
        const std::vector<std::string> vectors = split_vectors(it->second);
        if (static_cast<std::int64_t>(vectors.size()) != dimension) {
            fail(path, fmt::format("NRRD 'space directions': expected {} entries, got {}",
                                   dimension, vectors.size()));
        }
        for (std::size_t a = 0; a < 3; ++a) {
            const auto v = parse_vector(path, "space directions", vectors[first_spatial + a]);
            if (!v) {
                fail(path, fmt::format("NRRD 'space directions': spatial axis {} is 'none'", a));
            }
            for (std::size_t c = 0; c < 3; ++c) {
                if (!std::isfinite((*v)[c])) {
                    fail(path, fmt::format("NRRD 'space directions': axis {} has a non-finite "
                                           "component, expected finite numbers, got {}",
                                           a, (*v)[c]));
                }
            }
            if ((*v)[0] == 0.0 && (*v)[1] == 0.0 && (*v)[2] == 0.0) {
                fail(path, fmt::format("NRRD 'space directions': axis {} has zero length", a));
            }
            grid.steps[a] = to_world(*v);
        }
        const double cosine = volume::max_axis_cosine(grid);
        if (!(cosine <= volume::MAX_AXIS_COSINE)) {
            throw Unsupported(fmt::format(
                "{}: NRRD 'space directions' {} are sheared (not orthogonal: largest |cosine| "
                "{:.3g}, expected at most {}): a sheared grid cannot be placed without resampling",
                path.string(), it->second, cosine, volume::MAX_AXIS_COSINE));
        }
    } else if (const auto sp = header.fields.find("spacings"); sp != header.fields.end()) {
        const std::vector<std::string> values = words(sp->second);
        if (static_cast<std::int64_t>(values.size()) != dimension) {
            fail(path, fmt::format("NRRD 'spacings': expected {} values, got {}", dimension,
                                   values.size()));
        }
        for (std::size_t a = 0; a < 3; ++a) {
            const double spacing = parse_double(path, "spacings", values[first_spatial + a]);
            if (!std::isfinite(spacing) || spacing <= 0) {
                fail(path,
                     fmt::format("NRRD spacing of axis {}: expected a finite number > 0, got {}", a,
                                 spacing));
            }
            grid.steps[a] = {};
            grid.steps[a][static_cast<int>(a)] = spacing;
        }
    }
    if (const auto it = header.fields.find("space origin"); it != header.fields.end()) {
        const auto v = parse_vector(path, "space origin", it->second);
        if (v) {
            for (std::size_t c = 0; c < 3; ++c) {
                if (!std::isfinite((*v)[c])) {
                    fail(path, fmt::format("NRRD 'space origin': expected finite numbers, got {}",
                                           it->second));
                }
            }
            grid.centre0 = to_world(*v);
            has_centre0 = true;
        }
    }

    // Data location.
    std::filesystem::path data_path = path;
    std::uint64_t offset = header.data_offset;
    if (const auto it = header.fields.find("data file"); it != header.fields.end()) {
        const std::string& name = it->second;
        if (name.rfind("LIST", 0) == 0 || words(name).size() > 1) {
            throw Unsupported(
                fmt::format("{}: NRRD 'data file' lists several files ({}), expected one file name",
                            path.string(), detail::quote(name)));
        }
        data_path = std::filesystem::path(name).is_absolute() ? std::filesystem::path(name)
                                                              : path.parent_path() / name;
        offset = 0;
        std::error_code ec;
        if (!std::filesystem::exists(data_path, ec)) {
            fail(path, fmt::format("NRRD 'data file' {} does not exist", data_path.string()));
        }
    }
    if (const auto it = header.fields.find("line skip"); it != header.fields.end()) {
        std::int64_t skip = 0;
        if (detail::parse_integer(it->second, skip) != detail::ParseStatus::ok || skip != 0) {
            throw Unsupported(fmt::format("{}: NRRD 'line skip' {} is not supported, expected 0",
                                          path.string(), detail::quote(it->second)));
        }
    }
    std::int64_t byte_skip = 0;
    if (const auto it = header.fields.find("byte skip"); it != header.fields.end()) {
        if (detail::parse_integer(it->second, byte_skip) != detail::ParseStatus::ok ||
            byte_skip < -1) {
            fail(path, fmt::format("NRRD 'byte skip': expected an integer ≥ -1, got {}",
                                   detail::quote(it->second)));
        }
        if (byte_skip == -1 && gzip) {
            fail(path, "NRRD 'byte skip: -1' is only valid with raw encoding");
        }
    }

    // Size checks before allocating, then the data straight into the volume.
    const std::size_t bytes = detail::check_declared_size(path, dims, type, max_bytes);
    if (byte_skip == -1) {
        const std::uint64_t size = detail::file_size(data_path);
        if (size < bytes) {
            fail(data_path,
                 fmt::format("truncated voxel data, expected {} bytes, got {}", bytes, size));
        }
        offset = size - bytes;
    } else {
        offset += static_cast<std::uint64_t>(byte_skip);
    }
    if (!gzip) {
        const std::uint64_t size = detail::file_size(data_path);
        if (size < offset || size - offset < bytes) {
            fail(data_path,
                 fmt::format("truncated voxel data: the header declares {} {} voxels ({} bytes), "
                             "the file has {} bytes after byte offset {}",
                             detail::dims_text(dims), volume::name(type), bytes,
                             size > offset ? size - offset : 0, offset));
        }
    }
    volume::Volume volume = volume::Volume::allocate(dims, type, {1, 1, 1}, {0, 0, 0}, max_bytes);
    if (gzip) {
        detail::read_gzip_data(data_path, offset, volume.bytes());
    } else {
        // Attached or detached raw data must end with the voxels (byte skip: -1 reads the tail).
        detail::read_raw_data(data_path, offset, volume.bytes(), true);
    }
    if (big_endian) {
        detail::swap_channel_bytes(volume);
    }
    volume = volume::place_nearest_axes(std::move(volume), grid);
    if (!has_centre0) {
        volume.set_origin({0, 0, 0});  // no 'space origin': the box corner at the world origin
    }
    return volume;
}

void write_nrrd(const std::filesystem::path& path, const volume::Volume& volume, bool gzip,
                bool detached) {
    if (volume.empty()) {
        throw InvalidInput(fmt::format("write_nrrd: {}: the volume is empty", path.string()));
    }
    const bool rgba = volume::channels(volume.type()) == 4;
    const Vec3d& s = volume.spacing();
    const Vec3d& o = volume.origin();
    const volume::Dims& d = volume.dims();
    std::string header =
        "NRRD0004\n# written by pliant; space origin is the first voxel's centre\n";
    header += fmt::format("type: {}\n", nrrd_type_name(volume.type()));
    header += fmt::format("dimension: {}\n", rgba ? 4 : 3);
    header += "space dimension: 3\n";
    header += fmt::format("sizes: {}{} {} {}\n", rgba ? "4 " : "", d[0], d[1], d[2]);
    header += fmt::format("kinds: {}domain domain domain\n", rgba ? "RGBA-color " : "");
    if (volume.is_axis_aligned()) {
        header += fmt::format("space directions: {}({},0,0) (0,{},0) (0,0,{})\n",
                              rgba ? "none " : "", s.x, s.y, s.z);
        header += fmt::format("space origin: ({},{},{})\n", o.x + 0.5 * s.x, o.y + 0.5 * s.y,
                              o.z + 0.5 * s.z);
    } else {
        // Columns direction × spacing; the first voxel's centre. 17 significant digits: the
        // directions read back bit for bit.
        const volume::Direction& direction = volume.direction();
        const std::array<double, 3> spacing{s.x, s.y, s.z};
        header += fmt::format("space directions: {}", rgba ? "none " : "");
        for (std::size_t a = 0; a < 3; ++a) {
            const Vec3d step = direction[a] * spacing[a];
            header += fmt::format("({:.17g},{:.17g},{:.17g}){}", step.x, step.y, step.z,
                                  a < 2 ? " " : "\n");
        }
        const Vec3d c = volume.world_from_grid({0.5, 0.5, 0.5});
        header += fmt::format("space origin: ({:.17g},{:.17g},{:.17g})\n", c.x, c.y, c.z);
    }
    header += "endian: little\n";
    header += fmt::format("encoding: {}\n", gzip ? "gzip" : "raw");
    const std::span<const std::byte> bytes = volume.bytes();
    auto write_data = [&](std::ostream& out) {
        if (gzip) {
            detail::write_gzip(out, bytes);
        } else {
            out.write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
        }
    };
    std::filesystem::path data_path;
    if (detached) {
        data_path = path;
        data_path.replace_extension(gzip ? ".raw.gz" : ".raw");
        header += fmt::format("data file: {}\n", data_path.filename().string());
    } else {
        header += "\n";
    }
    detail::write_header_and_data(path, header, data_path, write_data);
}

}  // namespace pliant::io
