// The shaded preview of a cloth run: every frame rasterized (render/mesh_rasterizer.hpp) from a
// fixed camera that frames the cloth's start and the obstacles, streamed into DIR/preview.mp4
// through ffmpeg (io/video.hpp), or written as DIR/preview/frame_NNNN.png when ffmpeg is not
// installed. The cloth is warm red on the front and tinted on the back so folds read; obstacles
// are grey-blue and follow their motion; planes are drawn as squares around the scene.
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/video.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/mesh_rasterizer.hpp"

namespace pliant::pipeline {

class ClothPreview {
public:
    static constexpr int DEFAULT_WIDTH = 640;
    static constexpr int DEFAULT_HEIGHT = 480;

    // cloth: the cloth at the start (its box and the obstacles' set the camera). Starts ffmpeg
    // (or creates DIR/preview/) right away: a preview that cannot be written fails before the
    // simulation runs.
    ClothPreview(const std::filesystem::path& out, std::span<const Vec3d> cloth,
                 std::vector<ObstacleShape> obstacles, double fps, int width = DEFAULT_WIDTH,
                 int height = DEFAULT_HEIGHT);

    // Renders one frame: the cloth at `positions` (triangles as given), obstacles at time t (s).
    void add_frame(std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles,
                   double t);
    // Finishes the video (renamed into place); returns the path written: preview.mp4 or the PNG
    // directory.
    std::filesystem::path finish();
    double render_ms() const { return m_render_ms; }

private:
    std::filesystem::path m_out;
    std::vector<ObstacleShape> m_obstacles;
    std::vector<std::vector<Vec3d>> m_obstacle_positions;  // at the current frame
    render::Camera m_camera;
    render::MeshRasterizer m_rasterizer;
    render::Image m_image;
    std::unique_ptr<io::VideoWriter> m_video;  // null: PNG frames
    int m_frame = 0;
    double m_render_ms = 0.0;
};

}  // namespace pliant::pipeline
