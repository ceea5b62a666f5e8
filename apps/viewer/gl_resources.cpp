#include "gl_resources.hpp"

#include <fmt/format.h>

#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::viewer {
namespace {

std::string shader_log(GLuint shader) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> text(static_cast<std::size_t>(length) + 1, '\0');
    glGetShaderInfoLog(shader, length, nullptr, text.data());
    return text.data();
}

GLuint compile(const std::string& name, GLenum kind, const char* source) {
    const GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
        const std::string log = shader_log(shader);
        glDeleteShader(shader);
        throw InternalError(fmt::format("viewer: {} {} shader: {}", name,
                                        kind == GL_VERTEX_SHADER ? "vertex" : "fragment", log));
    }
    return shader;
}

}  // namespace

ShaderProgram::ShaderProgram(const char* name, const char* vertex_source,
                             const char* fragment_source)
    : m_name(name) {
    const GLuint vertex = compile(m_name, GL_VERTEX_SHADER, vertex_source);
    GLuint fragment = 0;
    try {
        fragment = compile(m_name, GL_FRAGMENT_SHADER, fragment_source);
    } catch (...) {
        glDeleteShader(vertex);
        throw;
    }
    m_program = glCreateProgram();
    glAttachShader(m_program, vertex);
    glAttachShader(m_program, fragment);
    glLinkProgram(m_program);
    glDeleteShader(vertex);
    glDeleteShader(fragment);
    GLint ok = GL_FALSE;
    glGetProgramiv(m_program, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
        GLint length = 0;
        glGetProgramiv(m_program, GL_INFO_LOG_LENGTH, &length);
        std::vector<char> text(static_cast<std::size_t>(length) + 1, '\0');
        glGetProgramInfoLog(m_program, length, nullptr, text.data());
        glDeleteProgram(m_program);
        throw InternalError(fmt::format("viewer: {} program: {}", m_name, text.data()));
    }
}

ShaderProgram::~ShaderProgram() {
    glDeleteProgram(m_program);
}

GLint ShaderProgram::uniform(const char* name) const {
    const GLint location = glGetUniformLocation(m_program, name);
    if (location < 0) {
        throw InternalError(fmt::format("viewer: {} program has no uniform '{}'", m_name, name));
    }
    return location;
}

void check_gl(const char* where) {
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
        throw InternalError(fmt::format("viewer: OpenGL error 0x{:x} in {}", error, where));
    }
}

}  // namespace pliant::viewer
