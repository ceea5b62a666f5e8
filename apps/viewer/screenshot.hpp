// Screenshots: the back buffer of the current frame read with glReadPixels (before the overlay
// is drawn, so screenshots show the scene alone), turned into a render::Image (rows flipped to
// the top-left origin) and written as a PNG through io::write_png, atomically (a failed write
// leaves no partial file). Multisampled windows are resolved by the read.
#pragma once

#include <filesystem>

#include "pliant/render/image.hpp"

namespace pliant::viewer {

// The width × height pixels at the bottom-left of the back buffer.
render::Image read_back_buffer(int width, int height);

void save_screenshot(const std::filesystem::path& path, int width, int height);

}  // namespace pliant::viewer
