#include "pliant/io/detail/volume_data.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <system_error>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"

namespace pliant::io::detail {

namespace {

constexpr std::int64_t MAX_DIM = std::numeric_limits<std::int32_t>::max();

struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_at(const std::filesystem::path& path, std::uint64_t offset) {
    File file(std::fopen(path.c_str(), "rb"));
    if (!file) {
        throw IoError(
            fmt::format("{}: cannot open for reading: {}", path.string(), std::strerror(errno)));
    }
    if (::fseeko(file.get(), static_cast<off_t>(offset), SEEK_SET) != 0) {
        throw IoError(fmt::format("{}: cannot seek to byte {}", path.string(), offset));
    }
    return file;
}

}  // namespace

std::string dims_text(const volume::Dims& dims) {
    return fmt::format("{}×{}×{}", dims[0], dims[1], dims[2]);
}

std::size_t check_declared_size(const std::filesystem::path& path, const volume::Dims& dims,
                                volume::VoxelType type, std::size_t max_bytes) {
    for (int axis = 0; axis < 3; ++axis) {
        if (dims[axis] < 1 || dims[axis] > MAX_DIM) {
            throw IoError(
                fmt::format("{}: size of axis {} is out of range, expected 1 to {}, got {}",
                            path.string(), axis, MAX_DIM, dims[axis]));
        }
    }
    // Multiply step by step against the limit: the product never overflows size_t.
    const std::size_t bpv = volume::bytes_per_voxel(type);
    std::size_t bytes = bpv;
    bool too_big = false;
    for (int axis = 0; axis < 3; ++axis) {
        const auto d = static_cast<std::size_t>(dims[axis]);
        if (bytes > max_bytes / d) {
            too_big = true;
            break;
        }
        bytes *= d;
    }
    if (too_big || bytes > max_bytes) {
        const long double needed = static_cast<long double>(dims[0]) * dims[1] * dims[2] * bpv;
        throw IoError(fmt::format(
            "{}: the header declares {} voxels of {} ({:.4g} bytes), more than the memory limit "
            "of {} bytes; refused before allocating (raise the limit with --max-memory if the "
            "file is genuine)",
            path.string(), dims_text(dims), volume::name(type), static_cast<double>(needed),
            max_bytes));
    }
    return bytes;
}

std::uint64_t file_size(const std::filesystem::path& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) {
        throw IoError(fmt::format("{}: no such file", path.string()));
    }
    if (!std::filesystem::is_regular_file(status)) {
        throw IoError(fmt::format("{}: not a regular file", path.string()));
    }
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) {
        throw IoError(fmt::format("{}: cannot get the file size: {}", path.string(), ec.message()));
    }
    return size;
}

void read_raw_data(const std::filesystem::path& path, std::uint64_t offset,
                   std::span<std::byte> out, bool exact) {
    const std::uint64_t size = detail::file_size(path);
    const std::uint64_t available = size > offset ? size - offset : 0;
    if (available < out.size()) {
        throw IoError(
            fmt::format("{}: truncated voxel data, expected {} bytes after byte offset {}, got {}",
                        path.string(), out.size(), offset, available));
    }
    if (exact && available > out.size()) {
        throw IoError(fmt::format(
            "{}: more voxel data than the header declares, expected {} bytes after byte offset "
            "{}, got {}",
            path.string(), out.size(), offset, available));
    }
    const File file = open_at(path, offset);
    if (!out.empty() && std::fread(out.data(), 1, out.size(), file.get()) != out.size()) {
        throw IoError(fmt::format("{}: read error in the voxel data", path.string()));
    }
}

void read_gzip_data(const std::filesystem::path& path, std::uint64_t offset,
                    std::span<std::byte> out) {
    const std::uint64_t size = detail::file_size(path);
    const std::uint64_t compressed = size > offset ? size - offset : 0;
    if (compressed == 0) {
        throw IoError(
            fmt::format("{}: no compressed voxel data after byte offset {}, expected {} "
                        "bytes once inflated",
                        path.string(), offset, out.size()));
    }
    if (compressed * MAX_INFLATE_RATIO + 1024 < out.size()) {
        throw IoError(fmt::format(
            "{}: the header declares {} bytes of voxel data but {} compressed bytes cannot hold "
            "that much (deflate inflates at most {}:1): truncated file or lying header",
            path.string(), out.size(), compressed, MAX_INFLATE_RATIO));
    }
    const File file = open_at(path, offset);
    z_stream stream{};
    // 15 + 32: zlib or gzip header, detected automatically.
    if (inflateInit2(&stream, 15 + 32) != Z_OK) {
        throw IoError(fmt::format("{}: cannot initialize zlib", path.string()));
    }
    struct End {
        z_stream* s;
        ~End() { inflateEnd(s); }
    } end{&stream};
    std::vector<unsigned char> input(std::size_t{1} << 16);
    std::size_t produced = 0;
    bool finished = false;
    std::array<unsigned char, 4096> spill{};
    while (!finished) {
        const std::size_t n = std::fread(input.data(), 1, input.size(), file.get());
        if (n == 0) {
            break;
        }
        stream.next_in = input.data();
        stream.avail_in = static_cast<uInt>(n);
        while (stream.avail_in > 0 && !finished) {
            const std::size_t room = out.size() - produced;
            if (room > 0) {
                stream.next_out = reinterpret_cast<unsigned char*>(out.data()) + produced;
                stream.avail_out = static_cast<uInt>(std::min<std::size_t>(room, 1u << 30));
            } else {
                stream.next_out = spill.data();
                stream.avail_out = static_cast<uInt>(spill.size());
            }
            const uInt before = stream.avail_out;
            const int status = inflate(&stream, Z_NO_FLUSH);
            const std::size_t wrote = before - stream.avail_out;
            if (room == 0 && wrote > 0) {
                throw IoError(fmt::format(
                    "{}: more voxel data than the header declares, expected {} bytes once "
                    "inflated, got more",
                    path.string(), out.size()));
            }
            produced += wrote;
            if (status == Z_STREAM_END) {
                finished = true;
            } else if (status != Z_OK && status != Z_BUF_ERROR) {
                throw IoError(fmt::format("{}: corrupt gzip data after {} bytes: {}", path.string(),
                                          produced,
                                          stream.msg != nullptr ? stream.msg : "zlib error"));
            } else if (status == Z_BUF_ERROR && wrote == 0 && stream.avail_in > 0) {
                throw IoError(
                    fmt::format("{}: corrupt gzip data after {} bytes", path.string(), produced));
            }
        }
    }
    if (produced < out.size()) {
        throw IoError(
            fmt::format("{}: truncated gzip voxel data, expected {} bytes once inflated, got {}",
                        path.string(), out.size(), produced));
    }
    if (!finished) {
        throw IoError(fmt::format("{}: truncated gzip stream (no end marker after {} bytes)",
                                  path.string(), produced));
    }
}

namespace {

// Deflates `bytes` into `out` with zlib's window bits (15 + 16: gzip wrapper; 15: zlib).
void write_deflate(std::ostream& out, std::span<const std::byte> bytes, int window_bits) {
    z_stream stream{};
    if (deflateInit2(&stream, 6, Z_DEFLATED, window_bits, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        throw IoError("deflate: cannot initialize zlib");
    }
    struct End {
        z_stream* s;
        ~End() { deflateEnd(s); }
    } end{&stream};
    std::vector<unsigned char> buffer(std::size_t{1} << 16);
    std::size_t consumed = 0;
    int status = Z_OK;
    do {
        const std::size_t chunk = std::min<std::size_t>(bytes.size() - consumed, 1u << 30);
        stream.next_in = const_cast<unsigned char*>(
            reinterpret_cast<const unsigned char*>(bytes.data()) + consumed);
        stream.avail_in = static_cast<uInt>(chunk);
        const bool last = consumed + chunk == bytes.size();
        do {
            stream.next_out = buffer.data();
            stream.avail_out = static_cast<uInt>(buffer.size());
            status = deflate(&stream, last ? Z_FINISH : Z_NO_FLUSH);
            out.write(reinterpret_cast<const char*>(buffer.data()),
                      static_cast<std::streamsize>(buffer.size() - stream.avail_out));
        } while (stream.avail_out == 0);
        consumed += chunk;
    } while (status != Z_STREAM_END);
}

}  // namespace

void write_gzip(std::ostream& out, std::span<const std::byte> bytes) {
    write_deflate(out, bytes, 15 + 16);
}

void write_zlib(std::ostream& out, std::span<const std::byte> bytes) {
    write_deflate(out, bytes, 15);
}

void swap_channel_bytes(volume::Volume& volume) {
    const std::size_t width = volume::bytes_per_channel(volume.type());
    if (width == 1) {
        return;
    }
    std::span<std::byte> bytes = volume.bytes();
    for (std::size_t i = 0; i + width <= bytes.size(); i += width) {
        std::reverse(bytes.begin() + static_cast<std::ptrdiff_t>(i),
                     bytes.begin() + static_cast<std::ptrdiff_t>(i + width));
    }
}

void write_header_and_data(const std::filesystem::path& path, const std::string& header,
                           const std::filesystem::path& data_file,
                           const std::function<void(std::ostream&)>& write_data) {
    if (!data_file.empty()) {
        write_file_atomically(data_file, write_data);
        write_file_atomically(path, [&](std::ostream& out) { out << header; });
        return;
    }
    write_file_atomically(path, [&](std::ostream& out) {
        out << header;
        write_data(out);
    });
}

}  // namespace pliant::io::detail
