#include "cloth_run.hpp"

#include <fmt/format.h>
#include <signal.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cloth_preview.hpp"
#include "commands.hpp"
#include "output_directory.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/mesh_io.hpp"
#include "progress_bar.hpp"

namespace pliant::cli {
namespace {

// Set by SIGINT while a scene runs: the run stops after the frame in progress.
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_interrupt(int /*signal*/) {
    g_interrupted = 1;
}

// Installs on_interrupt for SIGINT for its lifetime and restores the previous handler.
class InterruptGuard {
public:
    InterruptGuard() {
        g_interrupted = 0;
        struct sigaction action {};
        action.sa_handler = on_interrupt;
        sigemptyset(&action.sa_mask);
        ::sigaction(SIGINT, &action, &m_previous);
    }
    ~InterruptGuard() { ::sigaction(SIGINT, &m_previous, nullptr); }
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

private:
    struct sigaction m_previous {};
};

// Applies a placement (rotation, then translation) to points, the rotation built once.
void place(std::span<Vec3d> points, const cloth::Placement& placement) {
    const cloth::Rotation rotation = cloth::Rotation::from_degrees(placement.rotate_degrees);
    for (Vec3d& p : points) {
        p = rotation.apply(p) + placement.translate;
    }
}

// The cloth as simulated: the grid or mesh, transformed, then copied once per instance.
geometry::TriangleMeshD load_cloth(const cloth::ClothScene& scene) {
    geometry::TriangleMeshD mesh;
    if (scene.grid) {
        mesh = geometry::convert_precision<double>(geometry::make_grid_sheet(
            scene.grid->quads[0], scene.grid->quads[1], static_cast<float>(scene.grid->size[0]),
            static_cast<float>(scene.grid->size[1])));
    } else {
        mesh = io::read_mesh(scene.mesh);
    }
    const cloth::Placement transform{scene.rotate_degrees, scene.translate};
    place(mesh.positions, transform);
    if (scene.instances.empty()) {
        return mesh;
    }
    const auto num_vertices = static_cast<std::int64_t>(mesh.positions.size());
    if (num_vertices * static_cast<std::int64_t>(scene.instances.size()) >
        std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput(fmt::format(
            "cloth: {} instances of {} vertices exceed the 2^31 - 1 vertex indices a mesh has",
            scene.instances.size(), num_vertices));
    }
    geometry::TriangleMeshD copies;
    for (std::size_t k = 0; k < scene.instances.size(); ++k) {
        const auto offset = static_cast<std::int32_t>(k * mesh.positions.size());
        const std::size_t first = copies.positions.size();
        copies.positions.insert(copies.positions.end(), mesh.positions.begin(),
                                mesh.positions.end());
        place(std::span<Vec3d>(copies.positions).subspan(first), scene.instances[k]);
        for (const geometry::Triangle& t : mesh.triangles) {
            copies.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
    }
    return copies;
}

// The vertices of a pin group: its listed indices and every vertex inside one of its regions.
std::vector<std::int32_t> pinned_vertices(const cloth::PinGroup& group,
                                          const geometry::TriangleMeshD& mesh,
                                          const std::string& scene_name) {
    std::vector<std::int32_t> pinned = group.vertices;
    for (const std::int32_t v : pinned) {
        if (static_cast<std::size_t>(v) >= mesh.positions.size()) {
            throw InvalidInput(fmt::format(
                "{}: {}.vertices: vertex {} out of range, expected an index below {} (the "
                "cloth's vertices, all copies)",
                scene_name, group.key, v, mesh.positions.size()));
        }
    }
    for (const cloth::PinRegion& region : group.regions) {
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
                                       const std::filesystem::path& out,
                                       const ClothRunOptions& options) {
    const int frames = options.frames;
    const geometry::TriangleMeshD mesh = load_cloth(scene);
    cloth::ClothSolver solver(mesh, scene.material);
    for (const cloth::PinGroup& group : scene.pins) {
        solver.add_moving_pins(pinned_vertices(group, mesh, scene_name), group.motion);
    }
    // Obstacles, and their shapes for the preview (planes as squares around the cloth).
    AABBd cloth_box;
    for (const Vec3d& p : mesh.positions) {
        cloth_box.extend(p);
    }
    const Vec3d centre = (cloth_box.lo + cloth_box.hi) * 0.5;
    const double plane_half_size = 0.75 * norm(cloth_box.hi - cloth_box.lo) + 0.5;
    std::vector<ObstacleShape> shapes;
    for (const cloth::SceneObstacle& obstacle : scene.obstacles) {
        if (obstacle.mesh.empty()) {
            solver.add_obstacle(obstacle.shape, obstacle.motion);
            shapes.push_back(preview_shape(obstacle, nullptr, centre, plane_half_size));
            continue;
        }
        geometry::TriangleMeshD shape = io::read_mesh(obstacle.mesh);
        place(shape.positions, obstacle.mesh_placement);
        shapes.push_back(preview_shape(obstacle, &shape, centre, plane_half_size));
        solver.add_mesh_obstacle(std::make_shared<const cloth::MeshObstacle>(std::move(shape)),
                                 obstacle.motion);
    }
    solver.set_gravity(scene.gravity);
    solver.set_air(scene.air);
    solver.enable_self_collision(scene.self_collision);

    // Input that already intersects itself is reported (the fail-safe keeps it from getting
    // worse but cannot untangle it).
    const std::int64_t initial_intersections =
        collision::count_intersecting_pairs(solver.positions(), solver.triangles());
    if (initial_intersections > 0) {
        log_warning(
            "{}: the cloth intersects itself at the start ({} pairs of triangles); the "
            "simulation keeps those pairs from growing but does not untangle them",
            scene_name, initial_intersections);
    }

    const std::filesystem::path frames_dir = out / "frames";
    make_output_directory(frames_dir);
    std::unique_ptr<ClothPreview> preview;
    if (options.preview) {
        preview = std::make_unique<ClothPreview>(out, solver.positions(), std::move(shapes),
                                                 scene.frames_per_second, options.preview_width,
                                                 options.preview_height);
    }
    geometry::TriangleMeshD state{mesh.positions, mesh.triangles};
    const auto write_frame = [&](int frame) {
        state.positions.assign(solver.positions().begin(), solver.positions().end());
        io::write_mesh(frames_dir / fmt::format("frame_{:04d}.{}", frame, scene.frame_format),
                       state);
        if (preview) {
            preview->add_frame(solver.positions(), solver.triangles(), solver.time());
        }
    };
    write_frame(0);

    const double dt = 1.0 / scene.frames_per_second;
    const InterruptGuard interrupt_guard;
    int frames_done = 0;
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    double total_ms = 0.0;
    std::int64_t worst_intersections = 0;
    for (int frame = 1; frame <= frames; ++frame) {
        if (g_interrupted != 0) {
            break;
        }
        Stopwatch watch;
        const cloth::ClothStepStats step = solver.step(dt, scene.substeps);
        for (const Vec3d& p : solver.positions()) {
            if (!is_finite(p)) {
                throw InternalError(
                    fmt::format("cloth: frame {}: non-finite position; frames 0-{} are in {}",
                                frame, frame - 1, frames_dir.string()));
            }
        }
        const double ms = watch.elapsed_ms();
        total_ms += ms;
        Stopwatch writing;
        write_frame(frame);
        const double write_ms = writing.elapsed_ms();
        // The independent check: exact triangle-triangle tests on the frame as written.
        Stopwatch check;
        const std::int64_t intersecting =
            collision::count_intersecting_pairs(solver.positions(), solver.triangles());
        worst_intersections = std::max(worst_intersections, intersecting);
        nlohmann::ordered_json record = {{"frame", frame},
                                         {"ms", ms},
                                         {"step_ms", step.solve_ms},
                                         {"refit_ms", step.self.refit_ms},
                                         {"traverse_ms", step.self.traverse_ms},
                                         {"narrow_ms", step.self.narrow_ms},
                                         {"response_ms", step.self.response_ms},
                                         {"obstacle_contacts", step.obstacle_contacts},
                                         {"intersecting_pairs", intersecting},
                                         {"check_ms", check.elapsed_ms()},
                                         {"write_ms", write_ms}};
        if (step.has_self_collision) {
            record["gather_ms"] = step.self.gather_ms;
            record["project_ms"] = step.self.project_ms;
            record["ccd_ms"] = step.self.enforce_ms;
            record["candidate_pairs"] = step.self.candidate_pairs;
            record["contacts"] = step.self.contacts;
            record["ccd_hits"] = step.self.ccd_hits;
            record["reverted_vertices"] = step.self.reverted_vertices;
            record["fail_safe_rounds"] = step.self.enforce_rounds;
            record["gathers"] = step.self.gathers;
            record["path_updates"] = step.self.path_updates;
            record["new_paths"] = step.self.new_paths;
        }
        per_frame.push_back(record);
        frames_done = frame;
        if (options.progress) {
            print_progress(frame, frames, total_ms / frame);
        }
    }
    if (options.progress) {
        end_progress();
    }
    nlohmann::ordered_json stats = {
        {"scene", scene_name},
        {"vertices", mesh.positions.size()},
        {"triangles", mesh.triangles.size()},
        {"stretch_constraints", solver.num_stretch_constraints()},
        {"bending_constraints", solver.num_bending_constraints()},
        {"fps", scene.frames_per_second},
        {"substeps", scene.substeps},
        {"threads", num_threads()},
        {"initial_intersecting_pairs", initial_intersections},
        {"max_intersecting_pairs", worst_intersections},
        {"frames", per_frame},
        {"mean_ms_per_frame", frames_done > 0 ? total_ms / frames_done : 0.0},
    };
    const bool interrupted = frames_done < frames;
    if (interrupted) {
        stats["interrupted"] = true;
    }
    if (preview) {
        stats["preview"] = preview->finish().string();
        stats["preview_ms_per_frame"] = preview->render_ms() / (frames_done + 1);
    }
    io::write_file_atomically(out / "stats.json",
                              [&](std::ostream& s) { s << stats.dump(2) << '\n'; });
    if (interrupted) {
        throw Interrupted(
            fmt::format("stopped after frame {} of {}; frames 0-{} in {}, {}stats in {}",
                        frames_done, frames, frames_done, frames_dir.string(),
                        stats.contains("preview")
                            ? fmt::format("preview {}, ", stats["preview"].get<std::string>())
                            : std::string(),
                        (out / "stats.json").string()));
    }
    return stats;
}

}  // namespace pliant::cli
