#include "screenshot.hpp"

#include <algorithm>
#include <vector>

#include "gl_resources.hpp"
#include "pliant/io/png.hpp"

namespace pliant::viewer {

render::Image read_back_buffer(int x, int y, int width, int height) {
    render::Image image(width, height);
    std::vector<std::uint8_t> rows(image.pixels.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(x, y, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
    check_gl("glReadPixels");
    // OpenGL's rows go upwards from the bottom; the image's downwards from the top.
    const auto row_bytes = 3 * static_cast<std::size_t>(width);
    for (int row = 0; row < height; ++row) {
        const auto from =
            rows.begin() +
            static_cast<std::ptrdiff_t>(static_cast<std::size_t>(height - 1 - row) * row_bytes);
        std::copy(from, from + static_cast<std::ptrdiff_t>(row_bytes),
                  image.pixels.begin() +
                      static_cast<std::ptrdiff_t>(static_cast<std::size_t>(row) * row_bytes));
    }
    return image;
}

void save_screenshot(const std::filesystem::path& path, int x, int y, int width, int height) {
    io::write_png(path, read_back_buffer(x, y, width, height));
}

}  // namespace pliant::viewer
