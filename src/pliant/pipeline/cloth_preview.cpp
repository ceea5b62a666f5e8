#include "pliant/pipeline/cloth_preview.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "pliant/core/timer.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/pipeline/cloth_look.hpp"

namespace pliant::pipeline {

ClothPreview::ClothPreview(const std::filesystem::path& out, std::span<const Vec3d> cloth,
                           std::vector<ObstacleShape> obstacles, double fps, int width, int height)
    : m_out(out),
      m_obstacles(std::move(obstacles)),
      m_camera(render::frame_box(framing_box(cloth, m_obstacles), CLOTH_AZIMUTH_DEGREES,
                                 CLOTH_ELEVATION_DEGREES, width, height)) {
    m_obstacle_positions.resize(m_obstacles.size());
    if (io::ffmpeg_available()) {
        m_video = std::make_unique<io::VideoWriter>(out / "preview.mp4", width, height, fps);
    } else {
        io::make_output_directory(out / "preview");
    }
}

void ClothPreview::add_frame(std::span<const Vec3d> positions,
                             std::span<const geometry::Triangle> triangles, double t) {
    Stopwatch watch;
    std::vector<render::RenderMesh> meshes;
    for (std::size_t k = 0; k < m_obstacles.size(); ++k) {
        const ObstacleShape& shape = m_obstacles[k];
        std::span<const Vec3d> placed = shape.rest.positions;
        if (!shape.motion.is_static() || shape.animation) {
            const cloth::Pose pose = shape.motion.pose(t);
            m_obstacle_positions[k].resize(shape.rest.positions.size());
            if (shape.animation) {
                shape.animation->positions_at(t, m_obstacle_positions[k]);
            } else {
                std::copy(shape.rest.positions.begin(), shape.rest.positions.end(),
                          m_obstacle_positions[k].begin());
            }
            for (Vec3d& p : m_obstacle_positions[k]) {
                p = pose.apply(p);
            }
            placed = m_obstacle_positions[k];
        }
        meshes.push_back({placed, shape.rest.triangles, OBSTACLE_COLOR, shape.smooth});
    }
    meshes.push_back({positions, triangles, CLOTH_COLOR, true});
    m_rasterizer.render(m_camera, meshes, cloth_raster_options(), m_image);
    if (m_video) {
        m_video->write(m_image);
    } else {
        io::write_png(m_out / "preview" / fmt::format("frame_{:04d}.png", m_frame), m_image);
    }
    ++m_frame;
    m_render_ms += watch.elapsed_ms();
}

std::filesystem::path ClothPreview::finish() {
    if (m_video) {
        m_video->finish();
        return m_out / "preview.mp4";
    }
    return m_out / "preview";
}

}  // namespace pliant::pipeline
