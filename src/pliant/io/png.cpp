#include "pliant/io/png.hpp"

#include <fmt/format.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <cstring>
#include <limits>
#include <memory>
#include <ostream>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

namespace {

constexpr unsigned char PNG_SIGNATURE[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// stb_image_write's sink: appends to the std::ostream passed as context.
void write_to_stream(void* context, void* data, int size) {
    static_cast<std::ostream*>(context)->write(static_cast<const char*>(data), size);
}

std::string hex_prefix(const std::string& bytes) {
    std::string out;
    for (std::size_t i = 0; i < bytes.size() && i < 8; ++i) {
        out += fmt::format("{}{:02X}", i == 0 ? "" : " ",
                           static_cast<unsigned>(static_cast<unsigned char>(bytes[i])));
    }
    return out.empty() ? "an empty file" : out;
}

}  // namespace

void write_png(const std::filesystem::path& path, const render::Image& image) {
    if (image.width <= 0 || image.height <= 0) {
        throw InvalidInput(
            fmt::format("write_png: {}: image size {} x {}, expected width and "
                        "height >= 1",
                        path.string(), image.width, image.height));
    }
    if (!image.is_consistent()) {
        throw InvalidInput(fmt::format(
            "write_png: {}: image has {} bytes of pixels, expected "
            "3 * {} * {} = {}",
            path.string(), image.pixels.size(), image.width, image.height, 3 * image.num_pixels()));
    }
    if (image.width > std::numeric_limits<int>::max() / 3) {
        throw InvalidInput(
            fmt::format("write_png: {}: image width {} too large, expected at most "
                        "{}",
                        path.string(), image.width, std::numeric_limits<int>::max() / 3));
    }
    write_file_atomically(path, [&](std::ostream& out) {
        const int ok = stbi_write_png_to_func(&write_to_stream, &out, image.width, image.height, 3,
                                              image.pixels.data(), 3 * image.width);
        if (ok == 0) {
            throw IoError(fmt::format("{}: PNG encoding failed (stb_image_write)", path.string()));
        }
    });
}

render::Image read_png(const std::filesystem::path& path) {
    const std::string bytes = read_file(path);
    if (bytes.size() < sizeof(PNG_SIGNATURE) ||
        std::memcmp(bytes.data(), PNG_SIGNATURE, sizeof(PNG_SIGNATURE)) != 0) {
        throw IoError(
            fmt::format("{}: not a PNG file, expected the signature 89 50 4E 47 0D 0A "
                        "1A 0A, got {}",
                        path.string(), hex_prefix(bytes)));
    }
    if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
        throw IoError(fmt::format("{}: PNG file of {} bytes, at most {} supported", path.string(),
                                  bytes.size(), std::numeric_limits<int>::max()));
    }
    int width = 0, height = 0, channels_in_file = 0;
    const std::unique_ptr<stbi_uc, decltype(&stbi_image_free)> data(
        stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                              static_cast<int>(bytes.size()), &width, &height, &channels_in_file,
                              3),
        &stbi_image_free);
    if (!data) {
        const char* reason = stbi_failure_reason();
        throw IoError(fmt::format("{}: corrupt or truncated PNG: {}", path.string(),
                                  reason != nullptr ? reason : "unknown reason"));
    }
    render::Image image(width, height);
    std::memcpy(image.pixels.data(), data.get(), image.pixels.size());
    return image;
}

}  // namespace pliant::io
