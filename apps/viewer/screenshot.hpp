// Screenshots: the back buffer of the current frame read with glReadPixels (before the overlay
// is drawn, so screenshots show the scene alone), turned into a render::Image (rows flipped to
// the top-left origin) and written as a PNG through io::write_png, atomically (a failed write
// leaves no partial file). Multisampled windows are resolved by the read.
#pragma once

#include <filesystem>

#include "pliant/render/image.hpp"

namespace pliant::viewer {

// The width × height pixels of the back buffer whose bottom-left corner is (x, y) (OpenGL
// window coordinates, y upwards): the view's viewport.
render::Image read_back_buffer(int x, int y, int width, int height);

void save_screenshot(const std::filesystem::path& path, int x, int y, int width, int height);

}  // namespace pliant::viewer
