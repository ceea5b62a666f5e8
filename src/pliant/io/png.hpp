// PNG images (8-bit RGB) through stb (Debian's libstb: stb_image_write to encode, stb_image to
// decode).
//
// write_png(path, image) encodes `image` (render::Image: width × height, RGB8, top-left origin)
// as an 8-bit truecolour PNG with the values as given (no gamma chunk) and replaces `path`
// atomically (see atomic_file.hpp). Throws InvalidInput, before touching the file, for an empty
// image (width or height 0) or one whose pixel buffer is not 3·width·height bytes, and IoError
// "<path>: …" when the file cannot be written (missing directory, no permission, …).
//
// read_png(path) decodes any PNG stb_image supports (greyscale, grey+alpha, RGB, RGBA, palette;
// 8 or 16 bits, interlaced or not) to RGB8: grey is replicated into R, G and B, 16-bit samples are
// reduced to 8 bits, and alpha is dropped (not composited). Throws IoError "<path>: …" for a
// missing or unreadable file, a file that does not start with the PNG signature ("not a PNG
// file"), and a corrupt or truncated PNG (with stb's reason).
//
// Thread safety: both functions may run concurrently on different paths (stb's failure reason is
// a process-wide string, so a concurrent failure may report another call's reason).
#pragma once

#include <filesystem>

#include "pliant/render/image.hpp"

namespace pliant::io {

void write_png(const std::filesystem::path& path, const render::Image& image);

render::Image read_png(const std::filesystem::path& path);

}  // namespace pliant::io
