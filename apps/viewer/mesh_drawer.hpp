// Drawing triangle meshes with OpenGL, shaded exactly as render::MeshRasterizer shades them
// (render/mesh_rasterizer.hpp, step 6), so that the viewer and the offline previews look alike:
//   per pixel, n = the interpolated area-weighted vertex normal (geometry/normals.hpp),
//   normalized — or, for flat meshes and where smooth normals cancel, the face normal —
//   two-sided: a back face uses −n and the base colour mixed with the back tint;
//   colour = base · (ambient + key · max(0, n · key_dir) + fill · max(0, n · view_dir)),
// with key_dir fixed in the camera frame (RasterOptions::key_direction) and view_dir towards the
// eye (a headlight). Anti-aliasing comes from the window's multisampling.
//
//   MeshDrawer drawer;                              // compiles the program
//   MeshBuffers cloth;                              // one per mesh
//   cloth.upload(positions, triangles, /*smooth=*/true);      // every frame for the cloth
//   drawer.begin(camera, near_far, options);        // clears to options.background
//   drawer.draw(cloth, CLOTH_COLOR, identity);
#pragma once

#include <span>
#include <vector>

#include "clip_transform.hpp"
#include "gl_resources.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/mesh_rasterizer.hpp"

namespace pliant::viewer {

// A mesh's GPU buffers: float positions and (smooth meshes) vertex normals, and the triangles.
class MeshBuffers {
public:
    MeshBuffers();
    // Replaces the vertex data; the index buffer is uploaded when the triangles change size or on
    // the first call (topology is fixed for the cloth and the obstacles).
    void upload(std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles,
                bool smooth);
    bool smooth() const { return m_smooth; }
    GLsizei num_indices() const { return m_num_indices; }
    GLuint vertex_array() const { return m_vao.id(); }

private:
    GlVertexArray m_vao;
    GlBuffer m_positions, m_normals, m_indices;
    std::vector<Vec3f> m_float_positions;
    std::vector<Vec3f> m_vertex_normals;
    std::vector<Vec3d> m_normal_sums;
    GLsizei m_num_indices = 0;
    std::size_t m_uploaded_triangles = static_cast<std::size_t>(-1);
    bool m_smooth = true;
};

class MeshDrawer {
public:
    MeshDrawer();
    // Sets the viewport to the camera's size, clears colour and depth to the background, and the
    // camera and lighting uniforms for the draws that follow.
    void begin(const render::Camera& camera, const DepthRange& depth,
               const render::RasterOptions& options);
    // world_from_model: a rigid transform (moving obstacles), column-major.
    void draw(const MeshBuffers& mesh, const render::Color& color,
              const Matrix4& world_from_model) const;

private:
    ShaderProgram m_program;
    GLint m_clip_from_world, m_world_from_model, m_key, m_view, m_key_intensity, m_fill_intensity,
        m_ambient, m_front_color, m_back_color, m_smooth;
    render::RasterOptions m_options;
};

// The identity, and the rigid transform p ↦ rotation (p − pivot) + pivot + translate of a pose
// given as its rotation rows, pivot and translation.
Matrix4 identity_matrix();
Matrix4 rigid_matrix(const Vec3d (&rotation_rows)[3], const Vec3d& pivot, const Vec3d& translate);

}  // namespace pliant::viewer
