#include "mesh_drawer.hpp"

#include "pliant/geometry/normals.hpp"

namespace pliant::viewer {
namespace {

constexpr GLuint POSITION = 0;
constexpr GLuint NORMAL = 1;

constexpr const char* VERTEX_SHADER = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 clip_from_world;
uniform mat4 world_from_model;
out vec3 v_normal;
out vec3 v_world;
void main() {
    vec4 world = world_from_model * vec4(position, 1.0);
    v_world = world.xyz;
    v_normal = mat3(world_from_model) * normal;
    gl_Position = clip_from_world * world;
}
)";

// The rasterizer's shading (render/mesh_rasterizer.cpp, step 6). The face normal from screen
// derivatives, cross(dFdx, dFdy), points towards the viewer for front and back faces alike, as
// the rasterizer's face normal does once flipped on back faces.
constexpr const char* FRAGMENT_SHADER = R"(#version 330 core
in vec3 v_normal;
in vec3 v_world;
uniform vec3 key_direction;
uniform vec3 view_direction;
uniform float key_intensity;
uniform float fill_intensity;
uniform float ambient;
uniform vec3 front_color;
uniform vec3 back_color;
uniform bool smooth_shading;
out vec4 color;
void main() {
    vec3 base = gl_FrontFacing ? front_color : back_color;
    vec3 n = smooth_shading ? v_normal : vec3(0.0);
    float len = length(n);
    if (len > 1e-6) {
        n = gl_FrontFacing ? n / len : -n / len;
    } else {
        vec3 face = cross(dFdx(v_world), dFdy(v_world));
        float face_len = length(face);
        n = face_len > 0.0 ? face / face_len : view_direction;
    }
    float light = ambient + key_intensity * max(0.0, dot(n, key_direction)) +
                  fill_intensity * max(0.0, dot(n, view_direction));
    color = vec4(base * light, 1.0);
}
)";

void set_vec3(GLint location, const Vec3d& v) {
    glUniform3f(location, static_cast<float>(v.x), static_cast<float>(v.y),
                static_cast<float>(v.z));
}

void set_color(GLint location, const render::Color& c) {
    glUniform3f(location, c.r, c.g, c.b);
}

}  // namespace

Matrix4 identity_matrix() {
    return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

Matrix4 rigid_matrix(const Vec3d (&rotation_rows)[3], const Vec3d& pivot, const Vec3d& translate) {
    // p' = R p + (pivot + translate − R pivot).
    const Vec3d r_pivot{dot(rotation_rows[0], pivot), dot(rotation_rows[1], pivot),
                        dot(rotation_rows[2], pivot)};
    const Vec3d offset = pivot + translate - r_pivot;
    Matrix4 m{};
    for (int row = 0; row < 3; ++row) {
        const Vec3d& r = rotation_rows[row];
        m[static_cast<std::size_t>(row)] = static_cast<float>(r.x);
        m[4 + static_cast<std::size_t>(row)] = static_cast<float>(r.y);
        m[8 + static_cast<std::size_t>(row)] = static_cast<float>(r.z);
        m[12 + static_cast<std::size_t>(row)] = static_cast<float>(offset[row]);
    }
    m[15] = 1.0f;
    return m;
}

MeshBuffers::MeshBuffers() {
    glBindVertexArray(m_vao.id());
    glBindBuffer(GL_ARRAY_BUFFER, m_positions.id());
    glVertexAttribPointer(POSITION, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
    glEnableVertexAttribArray(POSITION);
    glBindBuffer(GL_ARRAY_BUFFER, m_normals.id());
    glVertexAttribPointer(NORMAL, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
    glEnableVertexAttribArray(NORMAL);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m_indices.id());
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void MeshBuffers::upload(std::span<const Vec3d> positions,
                         std::span<const geometry::Triangle> triangles, bool smooth) {
    static_assert(sizeof(Vec3f) == 3 * sizeof(float));
    static_assert(sizeof(geometry::Triangle) == 3 * sizeof(GLint));
    m_smooth = smooth;
    m_float_positions.resize(positions.size());
    for (std::size_t v = 0; v < positions.size(); ++v) {
        m_float_positions[v] = vec3_cast<float>(positions[v]);
    }
    if (smooth) {
        geometry::vertex_normals(positions, triangles, m_vertex_normals, m_normal_sums);
    } else {
        m_vertex_normals.assign(positions.size(), Vec3f{});  // the shader uses face normals
    }
    const auto bytes = static_cast<GLsizeiptr>(positions.size() * sizeof(Vec3f));
    glBindBuffer(GL_ARRAY_BUFFER, m_positions.id());
    glBufferData(GL_ARRAY_BUFFER, bytes, m_float_positions.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, m_normals.id());
    glBufferData(GL_ARRAY_BUFFER, bytes, m_vertex_normals.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    if (triangles.size() != m_uploaded_triangles) {
        glBindVertexArray(m_vao.id());
        glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                     static_cast<GLsizeiptr>(triangles.size() * sizeof(geometry::Triangle)),
                     triangles.data(), GL_STATIC_DRAW);
        glBindVertexArray(0);
        m_uploaded_triangles = triangles.size();
        m_num_indices = static_cast<GLsizei>(3 * triangles.size());
    }
}

MeshDrawer::MeshDrawer()
    : m_program("mesh", VERTEX_SHADER, FRAGMENT_SHADER),
      m_clip_from_world(m_program.uniform("clip_from_world")),
      m_world_from_model(m_program.uniform("world_from_model")),
      m_key(m_program.uniform("key_direction")),
      m_view(m_program.uniform("view_direction")),
      m_key_intensity(m_program.uniform("key_intensity")),
      m_fill_intensity(m_program.uniform("fill_intensity")),
      m_ambient(m_program.uniform("ambient")),
      m_front_color(m_program.uniform("front_color")),
      m_back_color(m_program.uniform("back_color")),
      m_smooth(m_program.uniform("smooth_shading")) {}

void MeshDrawer::begin(const render::Camera& camera, const DepthRange& depth,
                       const render::RasterOptions& options) {
    m_options = options;
    glViewport(0, 0, camera.width(), camera.height());
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glClearColor(options.background.r, options.background.g, options.background.b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(m_program.id());
    const Matrix4 clip = clip_from_world(camera, depth.near, depth.far);
    glUniformMatrix4fv(m_clip_from_world, 1, GL_FALSE, clip.data());
    // The key light is fixed in the camera frame (x right, y up, z towards the viewer).
    const Vec3d k = options.key_direction / norm(options.key_direction);
    set_vec3(m_key, k.x * camera.right() + k.y * camera.up() - k.z * camera.forward());
    set_vec3(m_view, -camera.forward());
    glUniform1f(m_key_intensity, options.key_intensity);
    glUniform1f(m_fill_intensity, options.fill_intensity);
    glUniform1f(m_ambient, options.ambient);
}

void MeshDrawer::draw(const MeshBuffers& mesh, const render::Color& color,
                      const Matrix4& world_from_model) const {
    if (mesh.num_indices() == 0) {
        return;
    }
    const float w = m_options.back_tint_weight;
    const render::Color back{(1.0f - w) * color.r + w * m_options.back_tint.r,
                             (1.0f - w) * color.g + w * m_options.back_tint.g,
                             (1.0f - w) * color.b + w * m_options.back_tint.b};
    glUniformMatrix4fv(m_world_from_model, 1, GL_FALSE, world_from_model.data());
    set_color(m_front_color, color);
    set_color(m_back_color, back);
    glUniform1i(m_smooth, mesh.smooth() ? 1 : 0);
    glBindVertexArray(mesh.vertex_array());
    glDrawElements(GL_TRIANGLES, mesh.num_indices(), GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
}

}  // namespace pliant::viewer
