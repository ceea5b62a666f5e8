#include "cloth_run.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "output_directory.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::cli {
namespace {

// Rotation about x, then y, then z (degrees), then translation: the scene's transform.
Vec3d transform(const Vec3d& p, const cloth::ClothScene& scene) {
    const double to_radians = std::numbers::pi / 180.0;
    const double ax = scene.rotate_degrees.x * to_radians;
    const double ay = scene.rotate_degrees.y * to_radians;
    const double az = scene.rotate_degrees.z * to_radians;
    Vec3d q = p;
    q = {q.x, std::cos(ax) * q.y - std::sin(ax) * q.z, std::sin(ax) * q.y + std::cos(ax) * q.z};
    q = {std::cos(ay) * q.x + std::sin(ay) * q.z, q.y, -std::sin(ay) * q.x + std::cos(ay) * q.z};
    q = {std::cos(az) * q.x - std::sin(az) * q.y, std::sin(az) * q.x + std::cos(az) * q.y, q.z};
    return q + scene.translate;
}

geometry::TriangleMeshD load_cloth(const cloth::ClothScene& scene) {
    geometry::TriangleMeshD mesh;
    if (scene.grid) {
        mesh = geometry::convert_precision<double>(geometry::make_grid_sheet(
            scene.grid->quads[0], scene.grid->quads[1], static_cast<float>(scene.grid->size[0]),
            static_cast<float>(scene.grid->size[1])));
    } else {
        mesh = io::read_mesh(scene.mesh);
    }
    for (Vec3d& p : mesh.positions) {
        p = transform(p, scene);
    }
    return mesh;
}

std::vector<std::int32_t> pinned_vertices(const cloth::ClothScene& scene,
                                          const geometry::TriangleMeshD& mesh) {
    std::vector<std::int32_t> pinned = scene.pinned_vertices;
    for (const std::int32_t v : pinned) {
        if (static_cast<std::size_t>(v) >= mesh.positions.size()) {
            throw InvalidInput(fmt::format(
                "{}: pins.vertices: vertex {} out of range, expected an index below {}",
                scene.mesh.empty() ? "scene" : scene.mesh.string(), v, mesh.positions.size()));
        }
    }
    for (const cloth::PinRegion& region : scene.pin_regions) {
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
            const Vec3d& p = mesh.positions[v];
            if (p.x >= region.min.x && p.x <= region.max.x && p.y >= region.min.y &&
                p.y <= region.max.y && p.z >= region.min.z && p.z <= region.max.z) {
                pinned.push_back(static_cast<std::int32_t>(v));
            }
        }
    }
    return pinned;
}

}  // namespace

nlohmann::ordered_json run_cloth_scene(const cloth::ClothScene& scene,
                                       const std::string& scene_name,
                                       const std::filesystem::path& out, int frames,
                                       bool progress) {
    const geometry::TriangleMeshD mesh = load_cloth(scene);
    cloth::ClothSolver solver(mesh, scene.material, pinned_vertices(scene, mesh));
    for (const cloth::Obstacle& obstacle : scene.obstacles) {
        solver.add_obstacle(obstacle);
    }
    solver.set_gravity(scene.gravity);
    solver.enable_self_collision(scene.self_collision);

    const std::filesystem::path frames_dir = out / "frames";
    make_output_directory(frames_dir);
    geometry::TriangleMeshD state{mesh.positions, mesh.triangles};
    const auto write_frame = [&](int frame) {
        state.positions.assign(solver.positions().begin(), solver.positions().end());
        io::write_mesh(frames_dir / fmt::format("frame_{:04d}.{}", frame, scene.frame_format),
                       state);
    };
    write_frame(0);

    const double dt = 1.0 / scene.frames_per_second;
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    double total_ms = 0.0;
    for (int frame = 1; frame <= frames; ++frame) {
        Stopwatch watch;
        const cloth::ClothStepStats step = solver.step(dt, scene.substeps);
        for (const Vec3d& p : solver.positions()) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
                throw InternalError(fmt::format("cloth: frame {}: non-finite position", frame));
            }
        }
        write_frame(frame);
        const double ms = watch.elapsed_ms();
        total_ms += ms;
        // The independent check: exact triangle-triangle tests on the frame as written.
        Stopwatch check;
        const std::int64_t intersecting =
            collision::count_intersecting_pairs(solver.positions(), solver.triangles());
        nlohmann::ordered_json record = {{"frame", frame},
                                         {"ms", ms},
                                         {"step_ms", step.ms},
                                         {"obstacle_contacts", step.obstacle_contacts},
                                         {"intersecting_pairs", intersecting},
                                         {"check_ms", check.elapsed_ms()}};
        if (step.has_self_collision) {
            record["gather_ms"] = step.self.gather_ms;
            record["ccd_ms"] = step.self.enforce_ms;
            record["candidate_pairs"] = step.self.candidate_pairs;
            record["contacts"] = step.self.contacts;
            record["ccd_hits"] = step.self.ccd_hits;
            record["reverted_vertices"] = step.self.reverted_vertices;
        }
        per_frame.push_back(record);
        if (progress) {
            const int width = 40;
            const int done = width * frame / std::max(frames, 1);
            std::fprintf(stderr, "\r[%s%s] frame %d/%d  %.1f ms/frame",
                         std::string(done, '#').c_str(), std::string(width - done, ' ').c_str(),
                         frame, frames, total_ms / frame);
            std::fflush(stderr);
        }
    }
    if (progress) {
        std::fputc('\n', stderr);
    }
    const nlohmann::ordered_json stats = {
        {"scene", scene_name},
        {"vertices", mesh.positions.size()},
        {"triangles", mesh.triangles.size()},
        {"stretch_constraints", solver.num_stretch_constraints()},
        {"bending_constraints", solver.num_bending_constraints()},
        {"fps", scene.frames_per_second},
        {"substeps", scene.substeps},
        {"threads", num_threads()},
        {"frames", per_frame},
        {"mean_ms_per_frame", frames > 0 ? total_ms / frames : 0.0},
    };
    io::write_file_atomically(out / "stats.json",
                              [&](std::ostream& s) { s << stats.dump(2) << '\n'; });
    return stats;
}

}  // namespace pliant::cli
