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

#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/scene.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/video.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/mesh_rasterizer.hpp"

namespace pliant::cli {

// An obstacle as drawn: its triangles at the rest placement and its motion.
struct ObstacleShape {
    geometry::TriangleMeshD rest;
    cloth::Motion motion;
    bool smooth = true;   // false for boxes and planes (flat shading)
    bool bounded = true;  // false for planes: left out of the camera's framing
};

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

// The shapes of a scene's obstacles for the preview: spheres, boxes, plane squares (half size
// `plane_half_size`, centred at the point of the plane closest to `centre`), and mesh obstacles as
// given (already placed by their mesh placement).
ObstacleShape preview_shape(const cloth::SceneObstacle& obstacle,
                            const geometry::TriangleMeshD* mesh, const Vec3d& centre,
                            double plane_half_size);

}  // namespace pliant::cli
