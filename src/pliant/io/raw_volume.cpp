#include "pliant/io/raw_volume.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <set>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/volume_data.hpp"
#include "pliant/io/json_text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

namespace {

using nlohmann::json;
using volume::VoxelType;

constexpr std::size_t MAX_SIDECAR_BYTES = std::size_t{1} << 20;
constexpr const char* FORMAT = "pliant-raw-volume";

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
    throw IoError(fmt::format("{}: {}", path.string(), message));
}

std::string ends_with_lower(const std::filesystem::path& path, std::size_t n) {
    std::string name = path.filename().string();
    for (char& c : name) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return name.size() >= n ? name.substr(name.size() - n) : name;
}

const json& field(const json& doc, const std::filesystem::path& path, const char* key) {
    const auto it = doc.find(key);
    if (it == doc.end()) {
        fail(path, fmt::format("sidecar has no \"{}\"", key));
    }
    return *it;
}

std::array<double, 3> triple(const json& doc, const std::filesystem::path& path, const char* key) {
    const json& v = field(doc, path, key);
    if (!v.is_array() || v.size() != 3) {
        fail(path, fmt::format("\"{}\": expected an array of 3 numbers, got {}", key, v.dump()));
    }
    std::array<double, 3> out{};
    for (std::size_t i = 0; i < 3; ++i) {
        if (!v[i].is_number()) {
            fail(path, fmt::format("\"{}\"[{}]: expected a number, got {}", key, i, v[i].dump()));
        }
        out[i] = v[i].get<double>();
    }
    return out;
}

}  // namespace

std::filesystem::path raw_volume_sidecar(const std::filesystem::path& path) {
    if (ends_with_lower(path, 5) == ".json") {
        return path;
    }
    std::filesystem::path sidecar = path;
    if (ends_with_lower(path, 7) == ".raw.gz") {
        sidecar.replace_extension();  // drop .gz
    }
    sidecar.replace_extension(".json");
    return sidecar;
}

volume::Volume read_raw_volume(const std::filesystem::path& path, std::size_t max_bytes) {
    const std::filesystem::path sidecar = raw_volume_sidecar(path);
    if (detail::file_size(sidecar) > MAX_SIDECAR_BYTES) {
        fail(sidecar, fmt::format("sidecar larger than {} bytes: not a pliant raw-volume sidecar",
                                  MAX_SIDECAR_BYTES));
    }
    const std::string text = read_file(sidecar);
    const json doc = parse_json(text, sidecar.string());
    if (!doc.is_object()) {
        fail(sidecar, "expected a JSON object");
    }
    static const std::set<std::string> KEYS = {"format", "version", "data_file", "dims",
                                               "type",   "spacing", "origin",    "direction",
                                               "endian", "encoding"};
    for (const auto& item : doc.items()) {
        if (KEYS.count(item.key()) == 0) {
            fail(sidecar, fmt::format("unknown key \"{}\", expected one of format, version, "
                                      "data_file, dims, type, spacing, origin, direction, endian, "
                                      "encoding",
                                      item.key()));
        }
    }
    const json& format = field(doc, sidecar, "format");
    if (format != FORMAT) {
        fail(sidecar, fmt::format(R"("format": expected "{}", got {})", FORMAT, format.dump()));
    }
    const json& version = field(doc, sidecar, "version");
    if (version != 1) {
        throw Unsupported(
            fmt::format("{}: \"version\": expected 1, got {}", sidecar.string(), version.dump()));
    }
    const json& dims_json = field(doc, sidecar, "dims");
    if (!dims_json.is_array() || dims_json.size() != 3) {
        fail(sidecar,
             fmt::format("\"dims\": expected an array of 3 integers, got {}", dims_json.dump()));
    }
    volume::Dims dims{};
    for (std::size_t i = 0; i < 3; ++i) {
        if (!dims_json[i].is_number_integer()) {
            fail(sidecar,
                 fmt::format("\"dims\"[{}]: expected an integer, got {}", i, dims_json[i].dump()));
        }
        dims[i] = dims_json[i].get<std::int64_t>();
    }
    const json& type_json = field(doc, sidecar, "type");
    std::optional<VoxelType> type;
    for (const VoxelType t : {VoxelType::u8, VoxelType::i16, VoxelType::u16, VoxelType::f32,
                              VoxelType::rgba8, VoxelType::rgba32f}) {
        if (type_json.is_string() && type_json.get<std::string>() == volume::name(t)) {
            type = t;
        }
    }
    if (!type) {
        throw Unsupported(
            fmt::format("{}: \"type\": expected one of u8, i16, u16, f32, rgba8, rgba32f, got {}",
                        sidecar.string(), type_json.dump()));
    }
    const std::array<double, 3> spacing = triple(doc, sidecar, "spacing");
    const std::array<double, 3> origin = triple(doc, sidecar, "origin");
    for (std::size_t i = 0; i < 3; ++i) {
        if (!std::isfinite(spacing[i]) || spacing[i] <= 0) {
            fail(sidecar, fmt::format("\"spacing\"[{}]: expected a finite number > 0, got {}", i,
                                      spacing[i]));
        }
    }
    volume::Direction direction = volume::IDENTITY_DIRECTION;
    if (const auto it = doc.find("direction"); it != doc.end()) {
        const auto bad = [&] {
            fail(sidecar, fmt::format("\"direction\": expected 3 columns of 3 finite numbers "
                                      "(unit, orthogonal: the world directions of the i, j, k "
                                      "axes), got {}",
                                      it->dump()));
        };
        if (!it->is_array() || it->size() != 3) {
            bad();
        }
        for (std::size_t a = 0; a < 3; ++a) {
            const json& column = (*it)[a];
            if (!column.is_array() || column.size() != 3) {
                bad();
            }
            for (std::size_t c = 0; c < 3; ++c) {
                if (!column[c].is_number()) {
                    bad();
                }
                direction[a][static_cast<int>(c)] = column[c].get<double>();
            }
        }
        try {
            volume::Volume probe;
            probe.set_direction(direction);
        } catch (const InvalidInput& e) {
            fail(sidecar, fmt::format("\"direction\": {}", e.what()));
        }
    }
    const json& endian = field(doc, sidecar, "endian");
    if (endian != "little" && endian != "big") {
        fail(sidecar,
             fmt::format(R"("endian": expected "little" or "big", got {})", endian.dump()));
    }
    const json& encoding = field(doc, sidecar, "encoding");
    if (encoding != "raw" && encoding != "gzip") {
        fail(sidecar,
             fmt::format(R"("encoding": expected "raw" or "gzip", got {})", encoding.dump()));
    }
    const json& data_file = field(doc, sidecar, "data_file");
    if (!data_file.is_string() || data_file.get<std::string>().empty()) {
        fail(sidecar, fmt::format("\"data_file\": expected a file name, got {}", data_file.dump()));
    }
    const std::filesystem::path data_path = sidecar.parent_path() / data_file.get<std::string>();

    const std::size_t bytes = detail::check_declared_size(sidecar, dims, *type, max_bytes);
    const bool gzip = encoding == "gzip";
    if (!gzip) {
        const std::uint64_t size = detail::file_size(data_path);
        if (size != bytes) {
            fail(data_path, fmt::format("{} voxel data: the sidecar declares {} {} voxels, "
                                        "expected {} bytes, got {}",
                                        size < bytes ? "truncated" : "wrong size of",
                                        detail::dims_text(dims), volume::name(*type), bytes, size));
        }
    }
    volume::Volume volume =
        volume::Volume::allocate(dims, *type, {spacing[0], spacing[1], spacing[2]},
                                 {origin[0], origin[1], origin[2]}, max_bytes);
    if (gzip) {
        detail::read_gzip_data(data_path, 0, volume.bytes());
    } else {
        detail::read_raw_data(data_path, 0, volume.bytes(), true);
    }
    if (endian == "big") {
        detail::swap_channel_bytes(volume);
    }
    volume.set_direction(direction);
    return volume;
}

void write_raw_volume(const std::filesystem::path& path, const volume::Volume& volume, bool gzip) {
    if (volume.empty()) {
        throw InvalidInput(fmt::format("write_raw_volume: {}: the volume is empty", path.string()));
    }
    const std::filesystem::path sidecar = raw_volume_sidecar(path);
    std::filesystem::path data_path = sidecar;
    data_path.replace_extension(gzip ? ".raw.gz" : ".raw");
    const std::span<const std::byte> bytes = volume.bytes();
    write_file_atomically(data_path, [&](std::ostream& out) {
        if (gzip) {
            detail::write_gzip(out, bytes);
        } else {
            out.write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
        }
    });
    const Vec3d& s = volume.spacing();
    const Vec3d& o = volume.origin();
    json doc = json::object();
    doc["format"] = FORMAT;
    doc["version"] = 1;
    doc["data_file"] = data_path.filename().string();
    doc["dims"] = {volume.dims()[0], volume.dims()[1], volume.dims()[2]};
    doc["type"] = std::string(volume::name(volume.type()));
    doc["spacing"] = {s.x, s.y, s.z};
    doc["origin"] = {o.x, o.y, o.z};
    if (!volume.is_axis_aligned()) {
        const volume::Direction& d = volume.direction();
        doc["direction"] = {
            {d[0].x, d[0].y, d[0].z}, {d[1].x, d[1].y, d[1].z}, {d[2].x, d[2].y, d[2].z}};
    }
    doc["endian"] = "little";
    doc["encoding"] = gzip ? "gzip" : "raw";
    const std::string text = doc.dump(2) + "\n";
    write_file_atomically(sidecar, [&](std::ostream& out) { out << text; });
}

}  // namespace pliant::io
