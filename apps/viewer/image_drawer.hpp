// Shows a render::Image (the ray caster's output) as a texture on a full-window triangle.
// At the window's size with nearest filtering every image pixel lands on exactly one window
// pixel, so a screenshot of the window is the image itself; a smaller image (the progressive
// preview) is stretched with linear filtering.
#pragma once

#include "gl_resources.hpp"
#include "pliant/render/image.hpp"

namespace pliant::viewer {

class ImageDrawer {
public:
    ImageDrawer();
    // Uploads `image` (top-left origin, RGB8) into the texture.
    void upload(const render::Image& image);
    // Draws the texture over the viewport of width × height pixels whose bottom-left corner is
    // (x, y); nearest filtering when the texture has that size, linear otherwise.
    void draw(int x, int y, int width, int height) const;

private:
    ShaderProgram m_program;
    GlTexture m_texture;
    GlVertexArray m_vao;  // empty: core profiles need one bound to draw
    int m_width = 0, m_height = 0;
};

}  // namespace pliant::viewer
