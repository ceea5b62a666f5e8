#include "cloth_preview.hpp"

#include <fmt/format.h>

#include <variant>

#include "output_directory.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/png.hpp"

namespace pliant::cli {
namespace {

constexpr render::Color CLOTH_COLOR{0.82f, 0.30f, 0.22f};
constexpr render::Color OBSTACLE_COLOR{0.62f, 0.68f, 0.76f};
constexpr double AZIMUTH_DEGREES = -60.0;
constexpr double ELEVATION_DEGREES = 25.0;
constexpr int SPHERE_SEGMENTS = 48;

// The cloth's start and the bounded obstacles (plane squares are as large as the scene, so they
// are left out).
AABBd framing_box(std::span<const Vec3d> cloth, const std::vector<ObstacleShape>& obstacles) {
    AABBd box;
    for (const Vec3d& p : cloth) {
        box.extend(p);
    }
    for (const ObstacleShape& shape : obstacles) {
        if (shape.bounded) {
            for (const Vec3d& p : shape.rest.positions) {
                box.extend(p);
            }
        }
    }
    return box;
}

}  // namespace

ObstacleShape preview_shape(const cloth::SceneObstacle& obstacle,
                            const geometry::TriangleMeshD* mesh, const Vec3d& centre,
                            double plane_half_size) {
    ObstacleShape shape;
    shape.motion = obstacle.motion;
    if (mesh != nullptr) {
        shape.rest = *mesh;
        shape.smooth = false;
    } else if (const auto* sphere = std::get_if<cloth::SphereObstacle>(&obstacle.shape)) {
        shape.rest = geometry::make_uv_sphere(sphere->center, sphere->radius, SPHERE_SEGMENTS);
    } else if (const auto* box = std::get_if<cloth::BoxObstacle>(&obstacle.shape)) {
        shape.rest = geometry::make_box(box->min, box->max);
        shape.smooth = false;
    } else {
        const auto& plane = std::get<cloth::PlaneObstacle>(obstacle.shape);
        const Vec3d n = plane.normal * (1.0 / norm(plane.normal));
        const Vec3d foot = centre - n * dot(centre - plane.point, n);
        shape.rest = geometry::make_plane_square(foot, n, plane_half_size);
        shape.smooth = false;
        shape.bounded = false;
    }
    return shape;
}

ClothPreview::ClothPreview(const std::filesystem::path& out, std::span<const Vec3d> cloth,
                           std::vector<ObstacleShape> obstacles, double fps, int width, int height)
    : m_out(out),
      m_obstacles(std::move(obstacles)),
      m_camera(render::frame_box(framing_box(cloth, m_obstacles), AZIMUTH_DEGREES,
                                 ELEVATION_DEGREES, width, height)) {
    m_obstacle_positions.resize(m_obstacles.size());
    if (io::ffmpeg_available()) {
        m_video = std::make_unique<io::VideoWriter>(out / "preview.mp4", width, height, fps);
    } else {
        make_output_directory(out / "preview");
    }
}

void ClothPreview::add_frame(std::span<const Vec3d> positions,
                             std::span<const geometry::Triangle> triangles, double t) {
    Stopwatch watch;
    std::vector<render::RenderMesh> meshes;
    for (std::size_t k = 0; k < m_obstacles.size(); ++k) {
        const ObstacleShape& shape = m_obstacles[k];
        std::span<const Vec3d> placed = shape.rest.positions;
        if (!shape.motion.is_static()) {
            const cloth::Pose pose = shape.motion.pose(t);
            m_obstacle_positions[k].resize(shape.rest.positions.size());
            for (std::size_t v = 0; v < shape.rest.positions.size(); ++v) {
                m_obstacle_positions[k][v] = pose.apply(shape.rest.positions[v]);
            }
            placed = m_obstacle_positions[k];
        }
        meshes.push_back({placed, shape.rest.triangles, OBSTACLE_COLOR, shape.smooth});
    }
    meshes.push_back({positions, triangles, CLOTH_COLOR, true});
    render::RasterOptions options;
    options.background = {0.93f, 0.94f, 0.96f};
    options.back_tint = {0.95f, 0.80f, 0.35f};
    m_rasterizer.render(m_camera, meshes, options, m_image);
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

}  // namespace pliant::cli
