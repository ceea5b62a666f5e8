#include "pliant/io/openvdb.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/volume_data.hpp"
#include "pliant/volume/reorient.hpp"

#ifdef PLIANT_HAS_OPENVDB
#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#endif

namespace pliant::io {

namespace fs = std::filesystem;

#ifndef PLIANT_HAS_OPENVDB

namespace {
[[noreturn]] void no_openvdb(const fs::path& path) {
    throw Unsupported(fmt::format(
        "{}: this pliant was built without OpenVDB, so it cannot read or write .vdb files: "
        "install libopenvdb-dev and libboost-iostreams-dev (scripts/install-deps), reconfigure "
        "and rebuild, or convert the volume to NRRD first",
        path.string()));
}
}  // namespace

bool has_openvdb_support() {
    return false;
}
std::vector<OpenVdbGridInfo> list_openvdb_grids(const fs::path& path) {
    no_openvdb(path);
}
volume::Volume read_openvdb(const fs::path& path, std::size_t, const std::string&) {
    no_openvdb(path);
}
void write_openvdb(const fs::path& path, const volume::Volume&) {
    no_openvdb(path);
}

#else

namespace {

using volume::Volume;
using volume::VoxelType;

constexpr std::uint32_t OLDEST_VERSION = openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION;
constexpr std::uint32_t NEWEST_VERSION = openvdb::OPENVDB_FILE_VERSION;
constexpr std::size_t UUID_CHARS = 36;
// Names of grids, metadata and types longer than this are refused (OpenVDB's are short).
constexpr std::uint32_t MAX_NAME_BYTES = 1U << 20;

constexpr const char* DIMS_KEY = "pliant_dims";
constexpr const char* TYPE_KEY = "pliant_voxel_type";
constexpr const char* ORIGIN_KEY = "pliant_origin";
constexpr const char* SPACING_KEY = "pliant_spacing";

void initialize_openvdb() {
    // openvdb::initialize is thread safe and idempotent.
    openvdb::initialize();
}

// ---------------------------------------------------------------------------------------------
// The file's layout, checked before OpenVDB parses it: OpenVDB sizes its allocations and seeks
// from these fields without checking them against the file.

class LayoutReader {
public:
    LayoutReader(const fs::path& path, std::ifstream& in, std::uint64_t size)
        : m_path(path), m_in(in), m_size(size) {}

    std::uint64_t position() const { return m_pos; }
    std::uint64_t size() const { return m_size; }

    void seek(std::uint64_t pos, std::string_view what) {
        if (pos > m_size) {
            fail(fmt::format("{} at byte {} lies beyond the end of the file ({} bytes)", what, pos,
                             m_size));
        }
        m_pos = pos;
        m_in.clear();
        m_in.seekg(static_cast<std::streamoff>(pos));
    }

    void read(void* out, std::uint64_t n, std::string_view what, std::uint64_t limit) {
        if (n > limit || m_pos > limit - n) {
            fail(fmt::format("{} at byte {} needs {} bytes, but only {} are left", what, m_pos, n,
                             limit - std::min(limit, m_pos)));
        }
        m_in.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
        if (!m_in) {
            fail(fmt::format("reading {} at byte {} failed", what, m_pos));
        }
        m_pos += n;
    }
    template <typename T>
    T value(std::string_view what, std::uint64_t limit) {
        T v{};
        read(&v, sizeof(T), what, limit);
        return v;
    }
    std::string string(std::string_view what, std::uint64_t limit) {
        const auto n = value<std::uint32_t>(what, limit);
        if (n > MAX_NAME_BYTES) {
            fail(fmt::format("{} at byte {} is {} bytes long, expected at most {}", what, m_pos - 4,
                             n, MAX_NAME_BYTES));
        }
        std::string s(n, '\0');
        if (n > 0) {
            read(s.data(), n, what, limit);
        }
        return s;
    }
    void skip(std::uint64_t n, std::string_view what, std::uint64_t limit) {
        if (n > limit || m_pos > limit - n) {
            fail(fmt::format("{} at byte {} needs {} bytes, but only {} are left", what, m_pos, n,
                             limit - std::min(limit, m_pos)));
        }
        seek(m_pos + n, what);
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw IoError(fmt::format("{}: broken OpenVDB file: {}", m_path.string(), what));
    }

private:
    const fs::path& m_path;
    std::ifstream& m_in;
    std::uint64_t m_size;
    std::uint64_t m_pos = 0;
};

// Bytes of the fixed-size metadata types OpenVDB registers (others are skipped by size).
std::uint64_t fixed_metadata_size(const std::string& type) {
    static const std::map<std::string, std::uint64_t, std::less<>> SIZES = {
        {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},  {"double", 8}, {"vec2i", 8},
        {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
        {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
    const auto it = SIZES.find(type);
    return it == SIZES.end() ? 0 : it->second;
}

// OpenVDB's DelayedLoadMetadata (io/DelayedLoadMetadata.cc readValue) reads its value by the
// sizes inside it, not by `bytes`: a leaf count, then the mask (a size, then that many
// Blosc-compressed bytes, or one byte per leaf when the size is 0), then the leaves' compressed
// sizes the same way (8 bytes per leaf), or none when that size is 0xFFFFFFFF (as written without
// compression). Each part must lie within `bytes`, and every leaf takes at least its 64-byte
// value mask in the file. A Blosc part's header (its bytes 4 to 7) holds the uncompressed size
// OpenVDB reserves before decompressing: it must be at most the part's count × size (or the 128
// bytes OpenVDB pads a smaller part to).
void check_delayed_load(LayoutReader& r, std::uint64_t bytes, const std::string& what,
                        std::uint64_t limit) {
    const std::uint64_t end = r.position() + bytes;
    if (end > limit) {
        r.fail(fmt::format("{} needs {} bytes, but only {} are left", what, bytes,
                           limit - std::min(limit, r.position())));
    }
    const auto leaves = r.value<std::uint32_t>(fmt::format("the leaf count of {}", what), end);
    if (leaves > r.size() / 64) {
        r.fail(fmt::format("{} declares {} leaves, more than a file of {} bytes can hold", what,
                           leaves, r.size()));
    }
    const auto part = [&](std::uint64_t bytes_per_leaf, const char* name) {
        const auto compressed =
            r.value<std::uint32_t>(fmt::format("the {} size of {}", name, what), end);
        if (compressed == std::numeric_limits<std::uint32_t>::max() && bytes_per_leaf == 8) {
            return;  // no compressed sizes
        }
        if (compressed == 0) {
            r.skip(bytes_per_leaf * leaves, fmt::format("the {} of {}", name, what), end);
            return;
        }
        constexpr std::uint64_t BLOSC_HEADER = 16;
        const std::uint64_t at = r.position();
        if (compressed < BLOSC_HEADER) {
            r.fail(fmt::format("the {} of {} at byte {} is {} bytes, less than a Blosc header",
                               name, what, at, compressed));
        }
        std::array<unsigned char, BLOSC_HEADER> header{};
        r.read(header.data(), header.size(), fmt::format("the {} of {}", name, what), end);
        const std::uint64_t nbytes = std::uint64_t{header[4]} | std::uint64_t{header[5]} << 8 |
                                     std::uint64_t{header[6]} << 16 |
                                     std::uint64_t{header[7]} << 24;
        // OpenVDB pads a part of up to 128 bytes to 128 before compressing it (io/Blosc.cc).
        const std::uint64_t most = std::max<std::uint64_t>(bytes_per_leaf * leaves, 128);
        if (nbytes > most) {
            r.fail(
                fmt::format("the {} of {} at byte {} decompresses to {} bytes, expected at "
                            "most {} ({} leaves)",
                            name, what, at, nbytes, most, leaves));
        }
        r.skip(compressed - BLOSC_HEADER, fmt::format("the {} of {}", name, what), end);
    };
    part(1, "mask");
    part(8, "compressed sizes");
    r.seek(end, what);
}

void check_metadata(LayoutReader& r, std::uint64_t limit, std::string_view where) {
    const auto count = r.value<std::uint32_t>(fmt::format("the {} metadata count", where), limit);
    // Each entry takes at least 12 bytes (two string lengths and a value size).
    if (count > (limit - std::min(limit, r.position())) / 12) {
        r.fail(fmt::format("the {} metadata count {} is more than the {} bytes left can hold",
                           where, count, limit - std::min(limit, r.position())));
    }
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string name = r.string(fmt::format("a {} metadata name", where), limit);
        const std::string type =
            r.string(fmt::format("the type of {} metadata '{}'", where, name), limit);
        const auto bytes =
            r.value<std::uint32_t>(fmt::format("the size of {} metadata '{}'", where, name), limit);
        const std::uint64_t fixed = fixed_metadata_size(type);
        if (fixed != 0 && bytes != fixed) {
            r.fail(fmt::format("{} metadata '{}' of type {} has {} bytes, expected {}", where, name,
                               type, bytes, fixed));
        }
        if (type == "__delayedload" && bytes > 0) {
            check_delayed_load(r, bytes, fmt::format("{} metadata '{}'", where, name), limit);
            continue;
        }
        if (type == "bool") {
            // TypedMetadata<bool>::readValue reads the byte straight into a bool.
            const auto value = r.value<std::uint8_t>(
                fmt::format("the value of {} metadata '{}'", where, name), limit);
            if (value > 1) {
                r.fail(fmt::format("{} metadata '{}' at byte {} is bool {}, expected 0 or 1", where,
                                   name, r.position() - 1, value));
            }
            continue;
        }
        r.skip(bytes, fmt::format("the value of {} metadata '{}'", where, name), limit);
    }
}

struct DescriptorLayout {
    std::string name;
    std::uint64_t grid_pos = 0;
    // Whether the tree's root (tile and child counts) was checked: true for float, double and
    // vec3s grids with a linear transform (the grids pliant reads).
    bool root_checked = false;
};

// Bytes of one value of the standard trees pliant reads; 0 for other grid types.
std::uint64_t value_bytes(std::string type) {
    constexpr std::string_view HALF = "_HalfFloat";
    if (type.size() > HALF.size() && type.ends_with(HALF)) {
        type.resize(type.size() - HALF.size());
    }
    if (type == "Tree_float_5_4_3") {
        return 4;
    }
    if (type == "Tree_double_5_4_3") {
        return 8;
    }
    if (type == "Tree_vec3s_5_4_3") {
        return 12;
    }
    return 0;
}

// Bytes of the linear maps OpenVDB 10 writes (math/Maps.h read()); 0 for other maps.
std::uint64_t linear_map_bytes(const std::string& type) {
    if (type == "AffineMap" || type == "UnitaryMap") {
        return 128;  // a Mat4d
    }
    if (type == "ScaleMap" || type == "UniformScaleMap") {
        return std::uint64_t{5} * 24;  // five Vec3d
    }
    if (type == "ScaleTranslateMap" || type == "UniformScaleTranslateMap") {
        return std::uint64_t{6} * 24;
    }
    if (type == "TranslationMap") {
        return 24;
    }
    return 0;
}

// How a grid's tree stores its values: the bytes of one value, of one value as written
// (half floats for "_HalfFloat" grids), and the grid's compression flags.
struct TreeFormat {
    std::uint64_t value_bytes = 0;
    std::uint64_t stored_bytes = 0;
    std::uint32_t compression = 0;
};

// Bits set in `mask` (a node's value or child mask as stored: little-endian 64-bit words).
std::uint64_t bits_on(const std::vector<unsigned char>& mask) {
    std::uint64_t n = 0;
    for (const unsigned char byte : mask) {
        n += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(byte)));
    }
    return n;
}

// One node's values as io::readCompressedValues (io/Compression.h, file format >= 222) reads
// them: a metadata byte (0 to 6), then per its value one or two inactive values, a selection
// mask, and the values: all `count`, or only the `active` ones when the grid's flags have
// COMPRESS_ACTIVE_MASK and the byte is not 6 (NO_MASK_AND_ALL_VALS). Zip and Blosc chunks start
// with their size (io::unzipFromStream, io::bloscFromStream: an int64, negative for raw bytes,
// which must then be the values' bytes); OpenVDB allocates a positive size before reading it, so
// it must fit in the bytes left, and Blosc reads a raw chunk into the values' buffer before
// comparing its size.
void check_values(LayoutReader& r, const TreeFormat& f, std::uint64_t count, std::uint64_t active,
                  std::uint64_t limit, const std::string& what) {
    const auto metadata = r.value<std::uint8_t>(fmt::format("the value layout of {}", what), limit);
    if (metadata > 6) {
        r.fail(fmt::format("{} at byte {} has value layout {}, expected 0 to 6", what,
                           r.position() - 1, metadata));
    }
    if (metadata == 2 || metadata == 4 || metadata == 5) {
        r.skip(f.value_bytes * (metadata == 5 ? 2 : 1),
               fmt::format("the inactive values of {}", what), limit);
    }
    if (metadata >= 3 && metadata <= 5) {
        r.skip(count / 8, fmt::format("the selection mask of {}", what), limit);
    }
    const bool only_active =
        (f.compression & openvdb::io::COMPRESS_ACTIVE_MASK) != 0 && metadata != 6;
    const std::uint64_t n = only_active ? active : count;
    const bool half = f.stored_bytes != f.value_bytes;
    if (half && n == 0) {
        return;  // io::HalfReader reads nothing
    }
    const std::uint64_t bytes = n * f.stored_bytes;
    if ((f.compression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP)) == 0) {
        r.skip(bytes, fmt::format("the values of {}", what), limit);
        return;
    }
    const std::uint64_t at = r.position();
    const auto chunk = r.value<std::int64_t>(fmt::format("the chunk size of {}", what), limit);
    if (chunk <= 0) {
        const std::uint64_t raw = chunk == std::numeric_limits<std::int64_t>::min()
                                      ? std::uint64_t{1} << 63
                                      : static_cast<std::uint64_t>(-chunk);
        if (raw != bytes) {
            r.fail(
                fmt::format("{}: the uncompressed chunk at byte {} has {} bytes, expected {} "
                            "({} values of {} bytes)",
                            what, at, raw, bytes, n, f.stored_bytes));
        }
        r.skip(raw, fmt::format("the values of {}", what), limit);
        return;
    }
    r.skip(static_cast<std::uint64_t>(chunk), fmt::format("the compressed chunk of {}", what),
           limit);
}

// An internal node's topology (tree/InternalNode.h readTopology): its child and value masks, its
// values, then its children in the child mask's order: internal nodes of 16³ under the 32³ ones,
// leaves (their 64-byte value mask) under those. Returns the leaves below it.
std::uint64_t check_internal(LayoutReader& r, const TreeFormat& f, int log2dim, std::uint64_t limit,
                             const std::string& what) {
    const std::uint64_t count = std::uint64_t{1} << (3 * log2dim);
    std::vector<unsigned char> children(count / 8);
    std::vector<unsigned char> values(count / 8);
    r.read(children.data(), children.size(), fmt::format("the child mask of {}", what), limit);
    r.read(values.data(), values.size(), fmt::format("the value mask of {}", what), limit);
    check_values(r, f, count, bits_on(values), limit, what);
    const std::uint64_t n = bits_on(children);
    if (log2dim == 4) {
        r.skip(n * 64, fmt::format("the {} leaf masks under {}", n, what), limit);
        return n;
    }
    std::uint64_t leaves = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        leaves += check_internal(r, f, 4, limit, fmt::format("internal node {} under {}", i, what));
    }
    return leaves;
}

// After a grid's metadata: its transform, the tree's buffer count, and the root node's
// background, tile count and child count, which OpenVDB loops over without a bound. A tile takes
// 12 + value + 1 bytes; a child at least 12 + two 4096-byte masks (a 32³ internal node). Then the
// whole tree as OpenVDB reads it: the topology up to the block position (each child at its own
// origin, a multiple of 4096: a second child at the same origin is dropped by OpenVDB without
// being freed), and each leaf's buffer (its value mask and values) from there to the grid's end.
bool check_root(LayoutReader& r, const DescriptorLayout& d, const TreeFormat& f,
                std::uint64_t block, std::uint64_t end) {
    const std::string map = r.string(fmt::format("the transform of grid '{}'", d.name), block);
    const std::uint64_t map_bytes = linear_map_bytes(map);
    if (map_bytes == 0) {
        return false;  // frustum or unknown: pliant does not read the grid
    }
    r.skip(map_bytes, fmt::format("the {} of grid '{}'", map, d.name), block);
    r.value<std::int32_t>(fmt::format("the buffer count of grid '{}'", d.name), block);
    const std::uint64_t vbytes = f.value_bytes;
    r.skip(vbytes, fmt::format("the background of grid '{}'", d.name), block);
    const auto tiles =
        r.value<std::uint32_t>(fmt::format("the tile count of grid '{}'", d.name), block);
    const auto children =
        r.value<std::uint32_t>(fmt::format("the child count of grid '{}'", d.name), block);
    const std::uint64_t needed =
        std::uint64_t{tiles} * (12 + vbytes + 1) + std::uint64_t{children} * (12 + 2 * 4096);
    const std::uint64_t left = block - std::min(block, r.position());
    if (needed > left) {
        r.fail(fmt::format(
            "grid '{}' declares {} root tiles and {} children ({} bytes at least), but its "
            "topology has {} bytes left",
            d.name, tiles, children, needed, left));
    }
    for (std::uint32_t t = 0; t < tiles; ++t) {
        const std::string what = fmt::format("root tile {} of grid '{}'", t, d.name);
        r.skip(12 + vbytes, what, block);
        // RootNode::readTopology reads the active flag straight into a bool.
        const auto active = r.value<std::uint8_t>(what, block);
        if (active > 1) {
            r.fail(fmt::format("{} at byte {} has active flag {}, expected 0 or 1", what,
                               r.position() - 1, active));
        }
    }
    std::vector<std::array<std::int32_t, 3>> origins;
    origins.reserve(children);
    std::uint64_t leaves = 0;
    for (std::uint32_t c = 0; c < children; ++c) {
        const std::uint64_t at = r.position();
        std::array<std::int32_t, 3> origin{};
        r.read(origin.data(), sizeof(origin),
               fmt::format("the origin of root child {} of grid '{}'", c, d.name), block);
        for (const std::int32_t o : origin) {
            if (o % 4096 != 0) {
                r.fail(
                    fmt::format("root child {} of grid '{}' at byte {} has origin ({}, {}, {}), "
                                "expected multiples of 4096",
                                c, d.name, at, origin[0], origin[1], origin[2]));
            }
        }
        if (std::find(origins.begin(), origins.end(), origin) != origins.end()) {
            r.fail(
                fmt::format("root child {} of grid '{}' at byte {} has origin ({}, {}, {}), "
                            "the same as an earlier child",
                            c, d.name, at, origin[0], origin[1], origin[2]));
        }
        origins.push_back(origin);
        leaves +=
            check_internal(r, f, 5, block, fmt::format("root child {} of grid '{}'", c, d.name));
    }
    r.seek(block, fmt::format("the leaf buffers of grid '{}'", d.name));
    std::vector<unsigned char> mask(64);
    for (std::uint64_t l = 0; l < leaves; ++l) {
        const std::string what = fmt::format("leaf {} of grid '{}'", l, d.name);
        r.read(mask.data(), mask.size(), fmt::format("the value mask of {}", what), end);
        check_values(r, f, 512, bits_on(mask), end, what);
    }
    return true;
}

// Checks the header, the file metadata and the grid descriptors; returns the descriptors.
std::vector<DescriptorLayout> check_layout(const fs::path& path) {
    const std::uint64_t size = detail::file_size(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw IoError(fmt::format("{}: cannot open the file for reading", path.string()));
    }
    LayoutReader r(path, in, size);
    if (size < 8) {
        throw IoError(fmt::format(
            "{}: not an OpenVDB file: {} bytes, expected at least the 8-byte magic number",
            path.string(), size));
    }
    const auto magic = r.value<std::int64_t>("the magic number", size);
    if (magic != openvdb::OPENVDB_MAGIC) {
        throw IoError(fmt::format(
            "{}: not an OpenVDB file: the first 8 bytes are not the magic number 0x{:x} ("
            "' BDV' little endian), got 0x{:x}",
            path.string(), openvdb::OPENVDB_MAGIC, static_cast<std::uint64_t>(magic)));
    }
    const auto version = r.value<std::uint32_t>("the file format version", size);
    if (version < OLDEST_VERSION || version > NEWEST_VERSION) {
        throw Unsupported(
            fmt::format("{}: OpenVDB file format version {}, expected {} to {} (pliant is built "
                        "with OpenVDB {})",
                        path.string(), version, OLDEST_VERSION, NEWEST_VERSION,
                        OPENVDB_LIBRARY_VERSION_STRING));
    }
    r.value<std::uint32_t>("the library major version", size);
    r.value<std::uint32_t>("the library minor version", size);
    const auto has_offsets = r.value<std::uint8_t>("the grid offsets flag", size);
    if (has_offsets > 1) {
        r.fail(fmt::format("the grid offsets flag is {}, expected 0 or 1", has_offsets));
    }
    if (has_offsets == 0) {
        throw Unsupported(fmt::format(
            "{}: the OpenVDB file was written as a stream, without grid offsets; pliant reads "
            "files written by openvdb::io::File (rewrite it with vdb_print/Houdini/Blender, or "
            "io::File::write)",
            path.string()));
    }
    r.skip(UUID_CHARS, "the file UUID", size);
    check_metadata(r, size, "file");
    const auto count = r.value<std::int32_t>("the grid count", size);
    // A descriptor takes at least 36 bytes: three string lengths and three offsets.
    if (count < 0 || static_cast<std::uint64_t>(count) > (size - r.position()) / 36) {
        r.fail(fmt::format("the grid count is {}, expected 0 to {} for the bytes left", count,
                           (size - r.position()) / 36));
    }
    std::vector<DescriptorLayout> grids;
    for (std::int32_t g = 0; g < count; ++g) {
        const std::uint64_t start = r.position();
        DescriptorLayout d;
        d.name = r.string(fmt::format("the name of grid {}", g), size);
        const std::string type = r.string(fmt::format("the type of grid '{}'", d.name), size);
        if (type.empty()) {
            r.fail(fmt::format("grid '{}' has an empty type name", d.name));
        }
        const std::string parent =
            r.string(fmt::format("the instance parent of grid '{}'", d.name), size);
        const auto grid_pos = r.value<std::int64_t>("a grid position", size);
        const auto block_pos = r.value<std::int64_t>("a block position", size);
        const auto end_pos = r.value<std::int64_t>("an end position", size);
        const auto after = static_cast<std::int64_t>(r.position());
        if (grid_pos < after || block_pos < grid_pos || end_pos < block_pos ||
            static_cast<std::uint64_t>(end_pos) > size) {
            r.fail(fmt::format(
                "grid '{}' (descriptor at byte {}): its positions grid {} ≤ block {} ≤ end {} "
                "must lie between the descriptor's end ({}) and the file's end ({})",
                d.name, start, grid_pos, block_pos, end_pos, after, size));
        }
        d.grid_pos = static_cast<std::uint64_t>(grid_pos);
        // The grid's compression flags and metadata lie between its grid and block positions.
        r.seek(d.grid_pos, "the grid's data");
        const auto block = static_cast<std::uint64_t>(block_pos);
        const auto compression = r.value<std::uint32_t>(
            fmt::format("the compression flags of grid '{}'", d.name), block);
        if (compression > 7) {
            r.fail(fmt::format("grid '{}' has compression flags {}, expected 0 to 7", d.name,
                               compression));
        }
        check_metadata(r, block, fmt::format("grid '{}'", d.name));
        const std::uint64_t vbytes = value_bytes(type);
        if (vbytes != 0 && parent.empty()) {
            TreeFormat f;
            f.value_bytes = vbytes;
            // Half floats: float and double as 2 bytes, vec3s as 3 × 2.
            f.stored_bytes = type.ends_with("_HalfFloat") ? (vbytes == 12 ? 6 : 2) : vbytes;
            f.compression = compression;
            d.root_checked = check_root(r, d, f, block, static_cast<std::uint64_t>(end_pos));
        }
        grids.push_back(std::move(d));
        r.seek(static_cast<std::uint64_t>(end_pos), "the next grid descriptor");
    }
    return grids;
}

// Unsupported unless check_layout checked the root of the grid named `name` (the tree of an
// instance grid is its parent's).
void require_checked_root(const fs::path& path, const std::vector<DescriptorLayout>& layout,
                          const std::string& name) {
    for (const DescriptorLayout& d : layout) {
        // OpenVDB names a descriptor "<name>" or "<name>\x1e<n>" when names repeat.
        if (d.name == name || d.name.starts_with(name + '\x1e')) {
            if (d.root_checked) {
                return;
            }
        }
    }
    throw Unsupported(fmt::format(
        "{}: grid '{}' is an instance of another grid or has a transform other than a linear "
        "map (scale, translation, affine): pliant reads float, double and vec3s grids with "
        "linear transforms",
        path.string(), name));
}

// ---------------------------------------------------------------------------------------------
// Reading.

[[noreturn]] void rethrow_as_io_error(const fs::path& path, const std::exception& e) {
    throw IoError(fmt::format("{}: OpenVDB could not read the file: {}", path.string(), e.what()));
}

std::string grid_list(const openvdb::GridPtrVec& grids) {
    std::string out;
    for (const auto& g : grids) {
        if (!out.empty()) {
            out += ", ";
        }
        out += fmt::format("'{}' ({})", g->getName(), g->valueType());
    }
    return out.empty() ? "none" : out;
}

bool is_scalar_float(const openvdb::GridBase& g) {
    return g.isType<openvdb::FloatGrid>() || g.isType<openvdb::DoubleGrid>();
}

openvdb::GridBase::Ptr choose_grid(const fs::path& path, const openvdb::GridPtrVec& grids,
                                   const std::string& wanted) {
    if (!wanted.empty()) {
        for (const auto& g : grids) {
            if (g->getName() == wanted) {
                if (!is_scalar_float(*g)) {
                    throw InvalidInput(fmt::format(
                        "{}: grid '{}' holds {} values, expected a float or double grid",
                        path.string(), wanted, g->valueType()));
                }
                return g;
            }
        }
        throw InvalidInput(fmt::format("{}: no grid named '{}'; the file has {}", path.string(),
                                       wanted, grid_list(grids)));
    }
    openvdb::GridBase::Ptr only;
    int scalar_count = 0;
    for (const auto& g : grids) {
        if (is_scalar_float(*g)) {
            if (g->getName() == "density") {
                return g;
            }
            only = g;
            ++scalar_count;
        }
    }
    if (scalar_count == 1) {
        return only;
    }
    if (scalar_count == 0) {
        throw InvalidInput(fmt::format(
            "{}: no float grid to read, expected a FloatGrid or DoubleGrid (\"density\" or the "
            "only one); the file has {}",
            path.string(), grid_list(grids)));
    }
    throw InvalidInput(fmt::format(
        "{}: {} float grids and none named \"density\": name the one to read (--grid NAME); the "
        "file has {}",
        path.string(), scalar_count, grid_list(grids)));
}

openvdb::GridBase::Ptr colour_grid_for(const openvdb::GridPtrVec& grids,
                                       const openvdb::GridBase& scalar) {
    for (const char* name : {"color", "Cd"}) {
        for (const auto& g : grids) {
            if (g->getName() == name && g->isType<openvdb::Vec3SGrid>()) {
                if (g->transform() == scalar.transform()) {
                    return g;
                }
                log_warning("OpenVDB grid '{}' has another transform than '{}': read as scalar",
                            name, scalar.getName());
            }
        }
    }
    return nullptr;
}

template <typename T>
std::optional<T> meta_value(const openvdb::GridBase& g, const char* key) {
    const auto m = g.getMetadata<openvdb::TypedMetadata<T>>(key);
    if (!m) {
        return std::nullopt;
    }
    return m->value();
}

std::optional<VoxelType> pliant_type(const openvdb::GridBase& g) {
    const auto name = meta_value<std::string>(g, TYPE_KEY);
    if (!name) {
        return std::nullopt;
    }
    for (const VoxelType t : {VoxelType::u8, VoxelType::i16, VoxelType::u16, VoxelType::f32,
                              VoxelType::rgba8, VoxelType::rgba32f}) {
        if (volume::name(t) == *name) {
            return t;
        }
    }
    return std::nullopt;
}

// The index box recorded in the grid's metadata before its tree is read: pliant_dims, else
// OpenVDB's file_bbox_min/max. Empty (min > max) when neither is there.
openvdb::CoordBBox recorded_box(const openvdb::GridBase& g) {
    if (const auto dims = meta_value<openvdb::Vec3i>(g, DIMS_KEY)) {
        return {openvdb::Coord(0, 0, 0),
                openvdb::Coord((*dims)[0] - 1, (*dims)[1] - 1, (*dims)[2] - 1)};
    }
    const auto lo = meta_value<openvdb::Vec3i>(g, "file_bbox_min");
    const auto hi = meta_value<openvdb::Vec3i>(g, "file_bbox_max");
    if (lo && hi) {
        return {openvdb::Coord(*lo), openvdb::Coord(*hi)};
    }
    return {};
}

volume::Dims box_dims(const openvdb::CoordBBox& box) {
    return {static_cast<std::int64_t>(box.max().x()) - box.min().x() + 1,
            static_cast<std::int64_t>(box.max().y()) - box.min().y() + 1,
            static_cast<std::int64_t>(box.max().z()) - box.min().z() + 1};
}

// The placement of dense voxel (0, 0, 0) = index `lo` and the steps, from a linear transform.
volume::GridPlacement placement_of(const fs::path& path, const openvdb::GridBase& g,
                                   const openvdb::Coord& lo) {
    const openvdb::math::Transform& xform = g.transform();
    if (!xform.isLinear()) {
        throw Unsupported(fmt::format(
            "{}: grid '{}' has a {} transform, expected a linear one (scale, translation, "
            "rotation): frustum and other non-linear maps are not read",
            path.string(), g.getName(), xform.mapType()));
    }
    volume::GridPlacement p;
    const openvdb::math::MapBase& map = *xform.baseMap();
    // Scale maps give their scales exactly; the affine matrix of one carries rounding.
    std::optional<openvdb::Vec3d> scale;
    if (map.isType<openvdb::math::ScaleTranslateMap>() ||
        map.isType<openvdb::math::UniformScaleTranslateMap>()) {
        scale = static_cast<const openvdb::math::ScaleTranslateMap&>(map).getScale();
    } else if (map.isType<openvdb::math::ScaleMap>() ||
               map.isType<openvdb::math::UniformScaleMap>()) {
        scale = static_cast<const openvdb::math::ScaleMap&>(map).getScale();
    } else if (map.isType<openvdb::math::TranslationMap>()) {
        scale = openvdb::Vec3d(1.0, 1.0, 1.0);
    }
    if (scale) {
        p.steps = {Vec3d{(*scale)[0], 0.0, 0.0}, Vec3d{0.0, (*scale)[1], 0.0},
                   Vec3d{0.0, 0.0, (*scale)[2]}};
    } else {
        const openvdb::math::Mat4d m = map.getAffineMap()->getMat4();
        for (int a = 0; a < 3; ++a) {
            p.steps[static_cast<std::size_t>(a)] = {m(a, 0), m(a, 1), m(a, 2)};
        }
    }
    const openvdb::Vec3d c = xform.indexToWorld(lo);
    p.centre0 = {c[0], c[1], c[2]};
    const double cosine = volume::max_axis_cosine(p);
    if (!(cosine <= volume::MAX_AXIS_COSINE)) {
        throw Unsupported(fmt::format(
            "{}: grid '{}' has a sheared or degenerate transform (largest cosine between its "
            "index axes {:.3g}, expected at most {:g}); pliant reads orthogonal grids",
            path.string(), g.getName(), cosine, volume::MAX_AXIS_COSINE));
    }
    return p;
}

template <VoxelType T>
void store(Volume& v, std::int64_t index, int channel, double value) {
    using C = volume::channel_t<T>;
    auto values = v.values<T>();
    const auto at = static_cast<std::size_t>(index * volume::channels(T) + channel);
    if constexpr (std::is_floating_point_v<C>) {
        values[at] = static_cast<C>(value);
    } else {
        const double lo = std::numeric_limits<C>::lowest();
        const double hi = std::numeric_limits<C>::max();
        const double r = std::isnan(value) ? 0.0 : std::clamp(std::round(value), lo, hi);
        values[at] = static_cast<C>(r);
    }
}

// Writes one voxel of the dense volume from the grid's value (and colour for RGBA).
struct VoxelWriter {
    Volume* volume;
    VoxelType type;

    void scalar(std::int64_t index, double value) const {
        switch (type) {
            case VoxelType::u8:
                store<VoxelType::u8>(*volume, index, 0, value);
                return;
            case VoxelType::i16:
                store<VoxelType::i16>(*volume, index, 0, value);
                return;
            case VoxelType::u16:
                store<VoxelType::u16>(*volume, index, 0, value);
                return;
            case VoxelType::f32:
                store<VoxelType::f32>(*volume, index, 0, value);
                return;
            case VoxelType::rgba8:
            case VoxelType::rgba32f:
                return;
        }
    }
    void rgba(std::int64_t index, const openvdb::Vec3s& rgb, double alpha) const {
        const std::array<double, 4> c{rgb[0], rgb[1], rgb[2], alpha};
        for (int ch = 0; ch < 4; ++ch) {
            if (type == VoxelType::rgba8) {
                store<VoxelType::rgba8>(*volume, index, ch,
                                        c[static_cast<std::size_t>(ch)] * 255.0);
            } else {
                store<VoxelType::rgba32f>(*volume, index, ch, c[static_cast<std::size_t>(ch)]);
            }
        }
    }
};

template <typename GridT>
void fill_dense(const GridT& grid, const openvdb::Vec3SGrid* colour, const openvdb::CoordBBox& box,
                const VoxelWriter& out) {
    const Volume& v = *out.volume;
    std::optional<openvdb::Vec3SGrid::ConstAccessor> colours;
    if (colour != nullptr) {
        colours.emplace(colour->getConstAccessor());
    }
    const auto put = [&](const openvdb::Coord& ijk, double value) {
        const std::int64_t index = v.index(static_cast<std::int64_t>(ijk.x()) - box.min().x(),
                                           static_cast<std::int64_t>(ijk.y()) - box.min().y(),
                                           static_cast<std::int64_t>(ijk.z()) - box.min().z());
        if (colours) {
            out.rgba(index, colours->getValue(ijk), value);
        } else {
            out.scalar(index, value);
        }
    };
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
        const auto value = static_cast<double>(*it);
        if (it.isVoxelValue()) {
            if (box.isInside(it.getCoord())) {
                put(it.getCoord(), value);
            }
            continue;
        }
        openvdb::CoordBBox tile;
        it.getBoundingBox(tile);
        tile.intersect(box);
        if (tile.empty()) {
            continue;
        }
        for (auto k = tile.min().z(); k <= tile.max().z(); ++k) {
            for (auto j = tile.min().y(); j <= tile.max().y(); ++j) {
                for (auto i = tile.min().x(); i <= tile.max().x(); ++i) {
                    put(openvdb::Coord(i, j, k), value);
                }
            }
        }
    }
}

Volume read_grid(const fs::path& path, std::size_t max_bytes, const std::string& wanted) {
    const std::vector<DescriptorLayout> layout = check_layout(path);
    initialize_openvdb();
    openvdb::io::File file(path.string());
    // No delayed loading: every buffer is read (and every error raised) here, not later while
    // iterating.
    file.open(false);
    const openvdb::GridPtrVec headers = *file.readAllGridMetadata();
    const openvdb::GridBase::Ptr chosen = choose_grid(path, headers, wanted);
    const openvdb::GridBase::Ptr colour_header = colour_grid_for(headers, *chosen);
    const std::optional<VoxelType> written_type = pliant_type(*chosen);
    VoxelType type = VoxelType::f32;
    if (colour_header) {
        type = written_type == VoxelType::rgba8 ? VoxelType::rgba8 : VoxelType::rgba32f;
    } else if (written_type && volume::channels(*written_type) == 1) {
        type = *written_type;
    }

    // The size recorded in the metadata, checked before the tree is read.
    const openvdb::CoordBBox recorded = recorded_box(*chosen);
    if (!recorded.empty()) {
        detail::check_declared_size(path, box_dims(recorded), type, max_bytes);
    }
    if (const auto mem = meta_value<std::int64_t>(*chosen, "file_mem_bytes");
        mem && *mem > 0 && static_cast<std::uint64_t>(*mem) > max_bytes) {
        throw IoError(fmt::format(
            "{}: grid '{}' needs {} bytes in memory (file_mem_bytes), more than the memory limit "
            "of {} bytes; refused before reading it (raise the limit with --max-memory)",
            path.string(), chosen->getName(), *mem, max_bytes));
    }

    require_checked_root(path, layout, chosen->getName());
    if (colour_header) {
        require_checked_root(path, layout, colour_header->getName());
    }
    const openvdb::GridBase::Ptr grid = file.readGrid(chosen->getName());
    openvdb::Vec3SGrid::Ptr colour;
    if (colour_header) {
        colour = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid(colour_header->getName()));
    }
    file.close();

    const openvdb::CoordBBox active = grid->evalActiveVoxelBoundingBox();
    openvdb::CoordBBox box = active;
    if (const auto dims = meta_value<openvdb::Vec3i>(*chosen, DIMS_KEY)) {
        box = recorded;
        if (!active.empty() && !box.isInside(active)) {
            log_warning(
                "{}: grid '{}' has active voxels outside its pliant_dims {}x{}x{}: read "
                "the active bounding box instead",
                path.string(), chosen->getName(), (*dims)[0], (*dims)[1], (*dims)[2]);
            box = active;
        }
    }
    if (box.empty()) {
        throw InvalidInput(
            fmt::format("{}: grid '{}' has no active voxels, so it has no bounding box to read",
                        path.string(), chosen->getName()));
    }
    const volume::Dims dims = box_dims(box);
    detail::check_declared_size(path, dims, type, max_bytes);

    const volume::GridPlacement placement = placement_of(path, *grid, box.min());
    Volume v = Volume::allocate(dims, type, {1, 1, 1}, {0, 0, 0}, max_bytes);
    const VoxelWriter writer{&v, type};
    if (grid->isType<openvdb::FloatGrid>()) {
        fill_dense(*openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid), colour.get(), box, writer);
    } else {
        fill_dense(*openvdb::gridConstPtrCast<openvdb::DoubleGrid>(grid), colour.get(), box,
                   writer);
    }
    v = volume::place_nearest_axes(std::move(v), placement);
    // pliant_spacing and pliant_origin restore spacing and origin bit for bit when they agree
    // with the transform (OpenVDB rounds a scale map's scales when it builds the transform).
    const auto spacing = meta_value<openvdb::Vec3d>(*chosen, SPACING_KEY);
    const auto origin = meta_value<openvdb::Vec3d>(*chosen, ORIGIN_KEY);
    if (spacing && origin && box.min() == openvdb::Coord(0, 0, 0)) {
        const Vec3d s{(*spacing)[0], (*spacing)[1], (*spacing)[2]};
        const Vec3d o{(*origin)[0], (*origin)[1], (*origin)[2]};
        const double scale = 1.0 + std::max({std::abs(o.x), std::abs(o.y), std::abs(o.z),
                                             std::abs(s.x), std::abs(s.y), std::abs(s.z)});
        const auto close = [&](const Vec3d& a, const Vec3d& b) {
            const Vec3d d = a - b;
            return std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}) <= 1e-9 * scale;
        };
        if (close(s, v.spacing()) && close(o, v.origin())) {
            v.set_spacing(s);
            v.set_origin(o);
        }
    }
    return v;
}

// ---------------------------------------------------------------------------------------------
// Writing.

// openvdb::io::File writes to a path it opens itself; this writes the same seekable layout (with
// grid offsets, what io::File::open expects) to the stream of write_file_atomically.
class StreamArchive : public openvdb::io::Archive {
public:
    void write_to(std::ostream& os, const openvdb::GridCPtrVec& grids,
                  const openvdb::MetaMap& meta) const {
        openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
    }
};

template <VoxelType T>
double channel_value(const Volume& v, std::int64_t index, int channel) {
    const auto values = v.values<T>();
    return static_cast<double>(
        values[static_cast<std::size_t>(index * volume::channels(T) + channel)]);
}

double value_at(const Volume& v, std::int64_t index, int channel) {
    switch (v.type()) {
        case VoxelType::u8:
            return channel_value<VoxelType::u8>(v, index, channel);
        case VoxelType::i16:
            return channel_value<VoxelType::i16>(v, index, channel);
        case VoxelType::u16:
            return channel_value<VoxelType::u16>(v, index, channel);
        case VoxelType::f32:
            return channel_value<VoxelType::f32>(v, index, channel);
        case VoxelType::rgba8:
            return channel_value<VoxelType::rgba8>(v, index, channel) / 255.0;
        case VoxelType::rgba32f:
            return channel_value<VoxelType::rgba32f>(v, index, channel);
    }
    return 0.0;
}

void add_pliant_metadata(openvdb::GridBase& g, const Volume& v) {
    const volume::Dims& d = v.dims();
    g.insertMeta(DIMS_KEY,
                 openvdb::Vec3IMetadata(openvdb::Vec3i(
                     static_cast<int>(d[0]), static_cast<int>(d[1]), static_cast<int>(d[2]))));
    g.insertMeta(TYPE_KEY, openvdb::StringMetadata(std::string(volume::name(v.type()))));
    g.insertMeta(ORIGIN_KEY,
                 openvdb::Vec3DMetadata(openvdb::Vec3d(v.origin().x, v.origin().y, v.origin().z)));
    g.insertMeta(SPACING_KEY, openvdb::Vec3DMetadata(
                                  openvdb::Vec3d(v.spacing().x, v.spacing().y, v.spacing().z)));
    g.setGridClass(openvdb::GRID_FOG_VOLUME);
    g.setCreator("pliant");
}

openvdb::math::Transform::Ptr transform_of(const Volume& v) {
    const volume::Direction& dir = v.direction();
    const Vec3d& s = v.spacing();
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    for (int a = 0; a < 3; ++a) {
        const Vec3d step = dir[static_cast<std::size_t>(a)] * s[a];
        m(a, 0) = step.x;
        m(a, 1) = step.y;
        m(a, 2) = step.z;
    }
    const Vec3d c = v.world_from_grid({0.5, 0.5, 0.5});
    m(3, 0) = c.x;
    m(3, 1) = c.y;
    m(3, 2) = c.z;
    if (v.is_axis_aligned()) {
        // Exactly a scale and a translation (createLinearTransform would simplify to it too).
        const openvdb::math::Vec3d scale(s.x, s.y, s.z);
        const openvdb::math::Vec3d t(c.x, c.y, c.z);
        return std::make_shared<openvdb::math::Transform>(
            std::make_shared<openvdb::math::ScaleTranslateMap>(scale, t));
    }
    return openvdb::math::Transform::createLinearTransform(m);
}

}  // namespace

bool has_openvdb_support() {
    return true;
}

std::vector<OpenVdbGridInfo> list_openvdb_grids(const fs::path& path) {
    check_layout(path);
    try {
        initialize_openvdb();
        openvdb::io::File file(path.string());
        file.open(false);
        const openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
        std::vector<OpenVdbGridInfo> out;
        for (const auto& g : *grids) {
            out.push_back({g->getName(), g->valueType()});
        }
        file.close();
        std::sort(out.begin(), out.end(), [](const OpenVdbGridInfo& a, const OpenVdbGridInfo& b) {
            return a.name < b.name;
        });
        return out;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        rethrow_as_io_error(path, e);
    }
}

volume::Volume read_openvdb(const fs::path& path, std::size_t max_bytes, const std::string& grid) {
    try {
        return read_grid(path, max_bytes, grid);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {  // openvdb::Exception, std::bad_alloc, boost's
        rethrow_as_io_error(path, e);
    }
}

void write_openvdb(const fs::path& path, const volume::Volume& v) {
    const volume::Dims& d = v.dims();
    constexpr std::int64_t MAX_INDEX = std::numeric_limits<std::int32_t>::max();
    if (v.empty() || d[0] > MAX_INDEX || d[1] > MAX_INDEX || d[2] > MAX_INDEX) {
        throw InvalidInput(fmt::format(
            "write_openvdb: {}: dims {}x{}x{} do not fit OpenVDB's index range, expected 1 to {} "
            "per axis",
            path.string(), d[0], d[1], d[2], MAX_INDEX));
    }
    initialize_openvdb();
    const bool rgba = volume::channels(v.type()) == 4;
    const int alpha_channel = rgba ? 3 : 0;

    openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.0F);
    density->setName("density");
    openvdb::Vec3SGrid::Ptr colour;
    if (rgba) {
        colour = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0F));
        colour->setName("color");
    }
    {
        auto dacc = density->getAccessor();
        std::optional<openvdb::Vec3SGrid::Accessor> cacc;
        if (colour) {
            cacc.emplace(colour->getAccessor());
        }
        for (std::int64_t k = 0; k < d[2]; ++k) {
            for (std::int64_t j = 0; j < d[1]; ++j) {
                for (std::int64_t i = 0; i < d[0]; ++i) {
                    const std::int64_t index = v.index(i, j, k);
                    const double a = value_at(v, index, alpha_channel);
                    if (a == 0.0) {
                        continue;
                    }
                    const openvdb::Coord ijk(static_cast<int>(i), static_cast<int>(j),
                                             static_cast<int>(k));
                    dacc.setValueOn(ijk, static_cast<float>(a));
                    if (cacc) {
                        cacc->setValueOn(ijk,
                                         openvdb::Vec3s(static_cast<float>(value_at(v, index, 0)),
                                                        static_cast<float>(value_at(v, index, 1)),
                                                        static_cast<float>(value_at(v, index, 2))));
                    }
                }
            }
        }
    }
    const openvdb::math::Transform::Ptr xform = transform_of(v);
    openvdb::GridCPtrVec grids;
    density->setTransform(xform);
    add_pliant_metadata(*density, v);
    grids.push_back(density);
    if (colour) {
        colour->setTransform(xform->copy());
        add_pliant_metadata(*colour, v);
        colour->setVectorType(openvdb::VEC_INVARIANT);
        grids.push_back(colour);
    }
    openvdb::MetaMap file_meta;
    file_meta.insertMeta("creator", openvdb::StringMetadata("pliant"));
    write_file_atomically(path, [&](std::ostream& out) {
        try {
            StreamArchive().write_to(out, grids, file_meta);
        } catch (const openvdb::Exception& e) {
            throw IoError(
                fmt::format("{}: OpenVDB could not write the file: {}", path.string(), e.what()));
        }
    });
}

#endif

}  // namespace pliant::io
