#include "image_drawer.hpp"

namespace pliant::viewer {
namespace {

// A triangle covering the viewport; texture row 0 is the image's top row.
constexpr const char* VERTEX_SHADER = R"(#version 330 core
out vec2 uv;
void main() {
    vec2 corner = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    uv = vec2(0.5 * (corner.x + 1.0), 1.0 - 0.5 * (corner.y + 1.0));
    gl_Position = vec4(corner, 0.0, 1.0);
}
)";

constexpr const char* FRAGMENT_SHADER = R"(#version 330 core
in vec2 uv;
uniform sampler2D image;
out vec4 color;
void main() {
    color = vec4(texture(image, uv).rgb, 1.0);
}
)";

}  // namespace

ImageDrawer::ImageDrawer() : m_program("image", VERTEX_SHADER, FRAGMENT_SHADER) {
    glBindTexture(GL_TEXTURE_2D, m_texture.id());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);
}

void ImageDrawer::upload(const render::Image& image) {
    glBindTexture(GL_TEXTURE_2D, m_texture.id());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (image.width != m_width || image.height != m_height) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.width, image.height, 0, GL_RGB,
                     GL_UNSIGNED_BYTE, image.pixels.data());
        m_width = image.width;
        m_height = image.height;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE,
                        image.pixels.data());
    }
    glBindTexture(GL_TEXTURE_2D, 0);
}

void ImageDrawer::draw(int x, int y, int width, int height) const {
    glViewport(x, y, width, height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glUseProgram(m_program.id());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, m_texture.id());
    const GLint filter = m_width == width && m_height == height ? GL_NEAREST : GL_LINEAR;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    glUniform1i(m_program.uniform("image"), 0);
    glBindVertexArray(m_vao.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glBindTexture(GL_TEXTURE_2D, 0);
}

}  // namespace pliant::viewer
