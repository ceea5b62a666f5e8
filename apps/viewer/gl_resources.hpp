// Small RAII owners of OpenGL objects (programs, buffers, vertex arrays, textures) and shader
// compilation with the driver's log in the error. Every function needs a current context.
#pragma once

#include <string>

#include "gl.hpp"

namespace pliant::viewer {

// Compiles and links a vertex + fragment shader pair; InternalError with the compiler's or
// linker's log (a shader that does not compile is a bug of the viewer, not bad input).
class ShaderProgram {
public:
    ShaderProgram(const char* name, const char* vertex_source, const char* fragment_source);
    ~ShaderProgram();
    ShaderProgram(const ShaderProgram&) = delete;
    ShaderProgram& operator=(const ShaderProgram&) = delete;

    GLuint id() const { return m_program; }
    // The location of a uniform; InternalError when the program has no such active uniform.
    GLint uniform(const char* name) const;

private:
    std::string m_name;
    GLuint m_program = 0;
};

// Generic owner: CREATE/DESTROY are the glGen*/glDelete* pair.
template <void (*CREATE)(GLsizei, GLuint*), void (*DESTROY)(GLsizei, const GLuint*)>
class GlName {
public:
    GlName() { CREATE(1, &m_id); }
    ~GlName() { DESTROY(1, &m_id); }
    GlName(const GlName&) = delete;
    GlName& operator=(const GlName&) = delete;
    GLuint id() const { return m_id; }

private:
    GLuint m_id = 0;
};

using GlBuffer = GlName<glGenBuffers, glDeleteBuffers>;
using GlVertexArray = GlName<glGenVertexArrays, glDeleteVertexArrays>;
using GlTexture = GlName<glGenTextures, glDeleteTextures>;

// InternalError naming `where` and the GL error code when glGetError reports one.
void check_gl(const char* where);

}  // namespace pliant::viewer
