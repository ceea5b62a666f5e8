#include "pliant/pipeline/cloth_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

#include "pliant/cloth/ccd_fail_safe.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/checkpoint.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/ply_polygons.hpp"
#include "pliant/io/video.hpp"
#include "pliant/pipeline/cloth_preview.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"
#include "pliant/pipeline/garment_output.hpp"

namespace pliant::pipeline {
namespace {

// Substeps longer than this (ms) get a warning (docs/formats.md, "Choosing substeps").
constexpr double MAX_QUIET_SUBSTEP_MS = 5.0;
// The number N of a frame file name frame_NNNN.obj / .ply (at least 4 digits, nothing else), or
// -1 for any other name (a number too large for int is not ours).
int frame_number(const std::filesystem::path& file) {
    const std::string stem = file.stem().string();
    const std::string extension = file.extension().string();
    if (stem.rfind("frame_", 0) != 0 || (extension != ".obj" && extension != ".ply")) {
        return -1;
    }
    const char* digits = stem.data() + 6;
    const char* end = stem.data() + stem.size();
    int number = 0;
    const auto [stop, error] = std::from_chars(digits, end, number);
    return end - digits >= 4 && error == std::errc() && stop == end && number >= 0 ? number : -1;
}

// The name this run gives frame n's file.
std::string frame_file_name(int n, const std::string& format) {
    return fmt::format("frame_{:04d}.{}", n, format);
}

// Removes the frame files of an earlier run into the same directory that this run did not
// replace: frame_NNNN.obj / .ply numbered above last_frame, or in the other format. Called once
// this run's frames are written, so frames/ holds exactly the frames stats.json describes.
void remove_stale_frames(const std::filesystem::path& frames_dir, int last_frame,
                         const std::string& format) {
    for (const std::filesystem::directory_entry& entry :
         std::filesystem::directory_iterator(frames_dir)) {
        const int number = frame_number(entry.path());
        if (entry.is_regular_file() && number >= 0 &&
            (entry.path().extension().string() != "." + format || number > last_frame)) {
            std::filesystem::remove(entry.path());
        }
    }
}

// Throws IoError, before anything is written, when a directory stands where the run would write
// a file: stats.json, preview.mp4 (when it writes a video) or frames/frame_NNNN.<format> for a
// frame it writes. (The preview's PNG frames, written without ffmpeg, go to preview/, which
// make_output_directory checks.)
void require_output_files_writable(const std::filesystem::path& out, int frames,
                                   const std::string& format, bool writes_video) {
    io::require_no_directory_at(out / "stats.json");
    if (writes_video) {
        io::require_no_directory_at(out / "preview.mp4");
    }
    std::error_code ec;
    if (!std::filesystem::is_directory(out / "frames", ec)) {
        return;
    }
    for (const std::filesystem::directory_entry& entry :
         std::filesystem::directory_iterator(out / "frames")) {
        const int number = frame_number(entry.path());
        if (number >= 0 && number <= frames &&
            entry.path().filename() == frame_file_name(number, format)) {
            io::require_no_directory_at(entry.path());
        }
    }
}

// Throws the exception in `failure` again, of the same type, with `context` before its message.
[[noreturn]] void rethrow_with_context(const std::exception_ptr& failure,
                                       const std::string& context) {
    try {
        std::rethrow_exception(failure);
    } catch (const InvalidInput& e) {
        throw InvalidInput(context + e.what());
    } catch (const IoError& e) {
        throw IoError(context + e.what());
    } catch (const Unsupported& e) {
        throw Unsupported(context + e.what());
    } catch (const InternalError& e) {
        throw InternalError(context + e.what());
    }
    std::rethrow_exception(failure);  // another type: unchanged (not reached: caught above)
}

// What a cloth run's result depends on, hashed (io::run_fingerprint): the cloth as set up (rest
// shape, start, masses), the material, the obstacles and their motions, gravity, air, fps,
// substeps, self-collision and the frame format. Not the frame count (a resumed run may go
// further), the preview or the thread count (results do not depend on it).
std::uint64_t cloth_fingerprint(const cloth::ClothScene& scene, const ClothSimulation& sim) {
    ByteWriter w;
    const cloth::ClothSolver& solver = sim.solver();
    const auto put_motion = [&](const cloth::Motion& motion) {
        w.put(motion.pivot);
        w.put(static_cast<std::uint64_t>(motion.keyframes.size()));
        for (const cloth::Keyframe& k : motion.keyframes) {
            w.put(k.time);
            w.put(k.translate);
            w.put(k.rotate_degrees);
        }
    };
    w.put_string("pliant cloth");
    w.put_vector(sim.setup().mesh.positions);
    w.put_vector(solver.triangles());
    w.put_vector(solver.positions());
    w.put_vector(solver.velocities());
    w.put_vector(solver.inverse_masses());
    const cloth::ClothMaterial& m = solver.material();
    for (const double value :
         {m.areal_density, m.stretch_compliance, m.bend_compliance, m.strain_limit, m.damping,
          m.thickness, m.static_friction, m.kinetic_friction, m.self_static_friction,
          m.self_kinetic_friction}) {
        w.put(value);
    }
    w.put(static_cast<std::int32_t>(m.bending));
    w.put(static_cast<std::int32_t>(m.stretch_solver));
    w.put(scene.vbd.has_value());
    if (scene.vbd) {
        w.put(static_cast<std::int32_t>(scene.vbd->iterations));
        w.put(scene.vbd->chebyshev_rho);
        w.put(scene.vbd->ogc.has_value());
        if (scene.vbd->ogc) {
            const cloth::OgcOptions& o = *scene.vbd->ogc;
            for (const double value :
                 {o.radius, o.query_factor, o.bound_share, o.redetect_share, o.stiffness}) {
                w.put(value);
            }
            w.put(o.audit);
        }
    }
    if (scene.xpbd_ogc) {
        const cloth::OgcOptions& o = *scene.xpbd_ogc;
        w.put_string("xpbd ogc");
        for (const double value :
             {o.radius, o.query_factor, o.bound_share, o.redetect_share, o.stiffness}) {
            w.put(value);
        }
        w.put(o.audit);
    }
    for (const cloth::PinGroup& group : scene.pins) {
        w.put_vector(group.vertices);
        put_motion(group.motion);
        if (group.attach) {
            w.put(group.attach->obstacle_index);
            w.put(group.attach->max_distance);
        }
    }
    for (const cloth::SceneObstacle& obstacle : scene.obstacles) {
        w.put(static_cast<std::uint8_t>(obstacle.shape.index()));
        std::visit([&](const auto& shape) { w.put_vector(std::span(&shape, 1)); }, obstacle.shape);
        w.put_string(obstacle.mesh.string());
        w.put(obstacle.mesh_placement.rotate_degrees);
        w.put(obstacle.mesh_placement.translate);
        put_motion(obstacle.motion);
    }
    for (const cloth::MovingMeshObstacle& obstacle : solver.model().mesh_obstacles()) {
        w.put_vector(obstacle.mesh->face_normals());
        if (obstacle.animation) {
            w.put(obstacle.animation->fps());
            w.put(obstacle.animation->loops());
            for (std::size_t f = 0; f < obstacle.animation->num_frames(); ++f) {
                w.put_vector(obstacle.animation->frame(f));
            }
        }
    }
    for (const cloth::SceneSeam& seam : scene.seams) {
        w.put_vector(seam.a);
        w.put_vector(seam.b);
        w.put(seam.seconds);
    }
    if (sim.setup().garment) {  // the frames' faces
        w.put_vector(sim.setup().garment->corner_vertices);
    }
    w.put(scene.gravity);
    w.put(scene.air.density);
    w.put(scene.air.drag_coefficient);
    w.put(scene.air.wind);
    w.put(scene.air.gust_amplitude);
    w.put(scene.air.gust_period);
    w.put(scene.air.gust_wavelength);
    w.put(scene.frames_per_second);
    w.put(scene.substeps);
    w.put(scene.self_collision);
    w.put_string(scene.frame_format);
    return io::run_fingerprint(w.bytes());
}

// The most obstacle intersections in a frame of the records (records of a checkpoint written
// before they were counted have none).
std::int64_t max_obstacle_intersections(const nlohmann::ordered_json& per_frame) {
    std::int64_t most = 0;
    for (const nlohmann::ordered_json& record : per_frame) {
        most = std::max(most, record.value("obstacle_intersections", std::int64_t{0}));
    }
    return most;
}

// The run's own part of a checkpoint, before the simulation's state.
struct ClothRunTotals {
    std::int32_t frame = 0;  // the last frame written
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    double total_ms = 0.0;
    std::int64_t worst_intersections = 0;
    double worst_strain = 0.0;
    double worst_strain_p99 = 0.0;
};

void write_cloth_checkpoint(const std::filesystem::path& path, std::uint64_t fingerprint,
                            const ClothRunTotals& totals, const ClothSimulation& sim) {
    ByteWriter w;
    w.put(totals.frame);
    w.put_string(totals.per_frame.dump());
    w.put(totals.total_ms);
    w.put(totals.worst_intersections);
    w.put(totals.worst_strain);
    w.put(totals.worst_strain_p99);
    sim.save_state(w);
    io::Checkpoint checkpoint;
    checkpoint.kind = io::CheckpointKind::cloth;
    checkpoint.fingerprint = fingerprint;
    checkpoint.payload.assign(w.bytes().begin(), w.bytes().end());
    io::write_checkpoint(path, checkpoint);
}

// Loads `checkpoint` into sim; returns the run's totals.
ClothRunTotals load_cloth_checkpoint(const std::filesystem::path& path,
                                     const io::Checkpoint& checkpoint, ClothSimulation& sim) {
    ByteReader r(checkpoint.payload, path.string());
    ClothRunTotals totals;
    totals.frame = r.get<std::int32_t>("frame");
    const std::string per_frame = r.get_string("per-frame stats");
    totals.per_frame = nlohmann::ordered_json::parse(per_frame, nullptr, false);
    if (totals.per_frame.is_discarded() || !totals.per_frame.is_array() ||
        totals.per_frame.size() != static_cast<std::size_t>(std::max(totals.frame, 0))) {
        throw InvalidInput(fmt::format("{}: per-frame stats: expected a JSON array of {} records",
                                       path.string(), totals.frame));
    }
    totals.total_ms = r.get<double>("total ms");
    totals.worst_intersections = r.get<std::int64_t>("max intersecting pairs");
    totals.worst_strain = r.get<double>("max strain");
    totals.worst_strain_p99 = r.get<double>("max strain p99");
    sim.load_state(r);
    r.expect_end();
    if (sim.frame() != totals.frame) {
        throw InvalidInput(fmt::format("{}: frame {} but the simulation's state is at frame {}",
                                       path.string(), totals.frame, sim.frame()));
    }
    return totals;
}

}  // namespace

nlohmann::ordered_json run_cloth_scene(const cloth::ClothScene& scene,
                                       const std::string& scene_name,
                                       const std::filesystem::path& out,
                                       const ClothRunOptions& options) {
    const int frames = options.frames;
    require_output_files_writable(out, frames, scene.frame_format,
                                  options.preview && io::ffmpeg_available());
    ClothSimulation sim = ClothSimulation::from_scene(
        scene, scene_name, ClothSimulationOptions{.max_memory_bytes = options.max_memory_bytes});
    const cloth::ClothSolver& solver = sim.solver();
    const geometry::TriangleMeshD& mesh = sim.setup().mesh;
    const StartState& start = sim.start();
    const std::int64_t initial_intersections = start.initial_intersections;
    const std::optional<cloth::UntangleResult>& untangled = start.untangled;
    const std::filesystem::path checkpoint_path = out / "checkpoint.bin";
    const std::uint64_t fingerprint = cloth_fingerprint(scene, sim);
    // The preview's camera frames the start, also for a resumed run.
    const std::vector<Vec3d> start_positions(solver.positions().begin(), solver.positions().end());

    ClothRunTotals totals;
    // Frame 0 as written: the input, or what untangling left of its intersections.
    totals.worst_intersections = untangled ? untangled->final_pairs : initial_intersections;
    std::error_code ec;
    if (options.resume && std::filesystem::exists(checkpoint_path, ec)) {
        const io::Checkpoint checkpoint =
            io::read_checkpoint(checkpoint_path, io::CheckpointKind::cloth, fingerprint);
        totals = load_cloth_checkpoint(checkpoint_path, checkpoint, sim);
        if (totals.frame > frames) {
            throw InvalidInput(fmt::format(
                "{}: the checkpoint is at frame {}, after the last frame asked for ({}); ask for "
                "at least {} frames",
                checkpoint_path.string(), totals.frame, frames, totals.frame));
        }
        for (int frame = 0; frame <= totals.frame; ++frame) {
            const std::filesystem::path file =
                out / "frames" / frame_file_name(frame, scene.frame_format);
            if (!std::filesystem::is_regular_file(file, ec)) {
                throw InvalidInput(fmt::format(
                    "{}: the checkpoint is at frame {}, but {} is missing; run without --resume "
                    "to start over",
                    checkpoint_path.string(), totals.frame, file.string()));
            }
        }
        log_info("{}: resuming after frame {} from {}", scene_name, totals.frame,
                 checkpoint_path.string());
    } else if (options.resume) {
        log_info("{}: no checkpoint at {}: starting from frame 0", scene_name,
                 checkpoint_path.string());
    }
    const int first_frame = totals.frame + 1;

    const std::filesystem::path frames_dir = out / "frames";
    io::make_output_directory(frames_dir);
    // A run killed while writing leaves its temporary files; an earlier run's checkpoint belongs
    // to frames this run replaces.
    io::remove_stray_temporaries(out);
    io::remove_stray_temporaries(frames_dir);
    if (!options.resume) {
        std::filesystem::remove(checkpoint_path, ec);
    }
    std::unique_ptr<ClothPreview> preview;
    if (options.preview) {
        preview = std::make_unique<ClothPreview>(out, start_positions, sim.setup().shapes,
                                                 scene.frames_per_second, options.preview_width,
                                                 options.preview_height);
    }
    geometry::TriangleMeshD state{mesh.positions, mesh.triangles};
    // A garment read as polygons (OBJ or PLY) is written with its own faces, UVs, groups and
    // materials (OBJ frames, its material libraries beside them) or faces, UVs and properties
    // (PLY frames).
    const std::optional<io::PolygonMesh>& garment = sim.setup().garment;
    if (garment && scene.frame_format == "obj") {
        copy_material_libraries(*garment, scene.mesh.parent_path(), frames_dir, scene_name);
    }
    for (const char* kind : {"pc2", "mdd"}) {  // rebuilt when this run completes
        std::filesystem::remove(out / point_cache_file_name(kind), ec);
    }
    const auto write_frame = [&](int frame) {
        const std::filesystem::path file = frames_dir / frame_file_name(frame, scene.frame_format);
        if (garment && scene.frame_format == "obj") {
            io::write_obj_polygons(file, *garment, solver.positions());
        } else if (garment) {
            io::write_ply_polygons(file, *garment, solver.positions());
        } else {
            state.positions.assign(solver.positions().begin(), solver.positions().end());
            io::write_mesh(file, state);
        }
        if (preview) {
            preview->add_frame(solver.positions(), solver.triangles(), solver.time());
        }
    };
    // A failure to write (a full disk): the frames before it stay, stats.json describes them.
    std::exception_ptr failure;
    nlohmann::ordered_json failure_json;
    bool write_failed = false;
    if (first_frame == 1) {
        write_frame(0);
    } else if (preview) {
        // The preview of the frames before the checkpoint, from the frames on disk (positions as
        // written; obstacles at the frames' times).
        for (int frame = 0; frame < first_frame; ++frame) {
            const geometry::TriangleMeshD written =
                io::read_mesh(frames_dir / frame_file_name(frame, scene.frame_format));
            preview->add_frame(written.positions, solver.triangles(),
                               frame / scene.frames_per_second);
        }
    }

    // One constraint iteration per substep: long substeps make cloth stretch and can make it
    // diverge (a 2 m sheet of 2 cm edges at 25 ms), whatever the scene.
    const double substep_ms = 1e3 / (scene.frames_per_second * scene.substeps);
    if (substep_ms > MAX_QUIET_SUBSTEP_MS) {
        log_warning(
            "{}: substeps of {:.4g} ms (fps {} x {} substeps): above about {} ms cloth stretches "
            "far and can diverge; raise substeps (the built-in scenes use about 1 ms)",
            scene_name, substep_ms, scene.frames_per_second, scene.substeps, MAX_QUIET_SUBSTEP_MS);
    }
    int frames_done = first_frame - 1;
    nlohmann::ordered_json& per_frame = totals.per_frame;
    RunningMean checkpoint_ms;  // this process's checkpoints
    const auto save_checkpoint = [&] {
        const Stopwatch watch;
        totals.frame = frames_done;
        write_cloth_checkpoint(checkpoint_path, fingerprint, totals, sim);
        checkpoint_ms.add(watch.elapsed_ms());
    };
    // A frame that fails (the simulation diverged, or a guard such as self-collision's pair limit
    // tripped) ends the run like an interrupt: the frames before it and stats.json (with
    // "error") are written, then the error is reported.
    bool warned_budget = false;        // the fail-safe's budget warning is given once
    bool warned_lag = false;           // so is the lagging pins' warning
    bool warned_obstacle_lag = false;  // and the lagging obstacle contacts' one
    for (int frame = first_frame; frame <= frames; ++frame) {
        if (options.keep_going && !options.keep_going()) {
            break;
        }
        Stopwatch watch;
        cloth::ClothStepStats step;
        try {
            step = sim.step();
        } catch (const Error& e) {
            failure = std::current_exception();
            failure_json = {{"frame", frame}, {"message", e.what()}};
            break;
        }
        const double ms = watch.elapsed_ms();
        Stopwatch writing;
        try {
            write_frame(frame);
        } catch (const IoError& e) {
            // A frame that cannot be written (a full disk) ends the run the same way; its file,
            // if the preview failed after it, goes with the stale frames below.
            failure = std::current_exception();
            failure_json = {{"frame", frame}, {"message", e.what()}};
            write_failed = true;
            break;
        }
        totals.total_ms += ms;
        const double write_ms = writing.elapsed_ms();
        // The independent checks on the frame as written.
        const ClothFrameCheck check = sim.check();
        const std::int64_t intersecting = check.intersecting_pairs;
        totals.worst_intersections = std::max(totals.worst_intersections, intersecting);
        const cloth::StrainStats& strain = check.strain;
        totals.worst_strain = std::max(totals.worst_strain, strain.max);
        totals.worst_strain_p99 = std::max(totals.worst_strain_p99, strain.p99);
        nlohmann::ordered_json record = {{"frame", frame},
                                         {"ms", ms},
                                         {"step_ms", step.solve_ms},
                                         {"refit_ms", step.self.refit_ms},
                                         {"traverse_ms", step.self.traverse_ms},
                                         {"narrow_ms", step.self.narrow_ms},
                                         {"response_ms", step.self.response_ms},
                                         {"obstacle_contacts", step.obstacle_contacts},
                                         {"solver_sweeps", step.solver_sweeps},
                                         {"intersecting_pairs", intersecting},
                                         {"obstacle_intersections", check.obstacle_intersections},
                                         {"strain_p90", strain.p90},
                                         {"strain_p99", strain.p99},
                                         {"strain_max", strain.max},
                                         {"edges_over_10_percent", strain.over_10_percent},
                                         {"check_ms", check.ms},
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
            record["ccd_pairs"] = step.self.ccd_pairs;
            record["fail_safe_budget_exceeded"] = step.self.budget_exceeded;
            record["fail_safe_frozen_vertices"] = step.self.frozen_vertices;
            if (step.self.budget_exceeded > 0 && !warned_budget) {
                warned_budget = true;
                log_warning(
                    "{}: frame {}: the self-collision fail-safe had more pairs to test than its "
                    "budget ({} per window) in {} of the frame's windows: it held {} vertices at "
                    "their window-start positions without testing them (the cloth stays "
                    "intersection-free, but moves stiffly there); the motion is too violent for "
                    "the substeps (stats.json: fail_safe_budget_exceeded, per frame)",
                    scene_name, frame, cloth::CCDFailSafe::pair_budget(mesh.positions.size()),
                    step.self.budget_exceeded, step.self.frozen_vertices);
            }
            const cloth::ClothModel::PinLag lag = sim.solver().model().pin_lag();
            record["pins_lagging"] = lag.vertices;
            record["pins_max_lag"] = lag.max;
            if (lag.vertices > 0 && !warned_lag) {
                warned_lag = true;
                log_warning(
                    "{}: frame {}: {} pinned vertices lag behind their keyframed target, up to "
                    "{:.3g} m: pins chase their target at most half the thickness per substep "
                    "(their keyframes move them faster); stats.json: pins_lagging, pins_max_lag, "
                    "per frame",
                    scene_name, frame, lag.vertices, lag.max);
            }
            record["gathers"] = step.self.gathers;
            record["path_updates"] = step.self.path_updates;
            record["new_paths"] = step.self.new_paths;
            if (step.has_ogc) {
                record["ogc_detections"] = step.ogc_detections;
                record["ogc_wide_detections"] = step.ogc_wide_detections;
                record["ogc_truncated_vertices"] = step.ogc_truncated;
                record["ogc_pairs"] = step.ogc_pairs;
                record["ogc_close_pairs"] = step.ogc_close_pairs;
                record["ogc_detect_ms"] = step.ogc_detect_ms;
                record["ogc_pair_audits"] = step.ogc_pair_audits;
                record["ogc_full_audits"] = step.ogc_full_audits;
            }
        }
        if (sim.solver().model().has_obstacles()) {
            record["obstacle_max_step"] = step.obstacle_max_step;
            record["obstacle_swept_contacts"] = step.obstacle_swept_contacts;
            record["obstacle_edge_contacts"] = step.obstacle_edge_contacts;
            record["obstacle_face_contacts"] = step.obstacle_face_contacts;
            record["obstacle_carried"] = step.obstacle_carried;
            record["obstacle_pushes_undone"] = step.obstacle_pushes_undone;
            record["obstacles_lagging"] = step.obstacles_lagging;
            record["obstacle_max_lag"] = step.obstacle_max_lag;
            if (step.obstacle_max_lag > 0.0 && !warned_obstacle_lag) {
                warned_obstacle_lag = true;
                log_warning(
                    "{}: frame {}: an obstacle moved up to {:.3g} m in one substep and pushed "
                    "cloth out at a bounded speed (half the thickness per substep beyond the "
                    "cloth's own motion): up to {:.3g} m of a push held back; stats.json: "
                    "obstacle_max_step, obstacles_lagging, obstacle_max_lag, per frame",
                    scene_name, frame, step.obstacle_max_step, step.obstacle_max_lag);
            }
        }
        per_frame.push_back(record);
        frames_done = frame;
        if (options.checkpoint_every > 0 &&
            (frame % options.checkpoint_every == 0 || frame == frames)) {
            try {
                save_checkpoint();
            } catch (const IoError& e) {
                failure = std::current_exception();
                failure_json = {{"frame", frame}, {"message", e.what()}};
                write_failed = true;
                break;
            }
        }
        if (options.progress) {
            options.progress(frame, frames, totals.total_ms / frame);
        }
    }
    const bool interrupted = frames_done < frames && !failure;
    if (interrupted && options.checkpoint_every > 0 && frames_done >= first_frame) {
        try {
            save_checkpoint();  // resume continues from where the interrupt stopped
        } catch (const IoError& e) {
            log_warning("{}: {}; --resume continues from the previous checkpoint", scene_name,
                        e.what());
        }
    }
    const int frames_run = frames_done - first_frame + 1;
    nlohmann::ordered_json stats = {
        {"scene", scene_name},
        {"vertices", mesh.positions.size()},
        {"triangles", mesh.triangles.size()},
        {"stretch_constraints", solver.num_stretch_constraints()},
        {"stretch_chains", solver.num_stretch_chains()},
        {"bending_constraints", solver.num_bending_constraints()},
        {"isometric_bending_constraints", solver.num_isometric_bending_constraints()},
        {"strain_limits", solver.num_strain_limits()},
        {"fps", scene.frames_per_second},
        {"substeps", scene.substeps},
        {"solver", scene.vbd ? "vbd" : "xpbd"},
        {"contact", (scene.vbd && scene.vbd->ogc) || scene.xpbd_ogc ? "ogc" : "proximity"},
        {"threads", num_threads()},
        {"initial_intersecting_pairs", initial_intersections},
        {"untangle", untangle_report(start)},
        {"max_intersecting_pairs", totals.worst_intersections},
        {"max_obstacle_intersections", max_obstacle_intersections(per_frame)},
        {"max_strain_p99", totals.worst_strain_p99},
        {"max_strain", totals.worst_strain},
        {"frames", per_frame},
        {"mean_ms_per_frame", frames_done > 0 ? totals.total_ms / frames_done : 0.0},
    };
    if (first_frame > 1) {
        stats["resumed_after_frame"] = first_frame - 1;
    }
    if (checkpoint_ms.count > 0) {
        stats["checkpoint_ms"] = checkpoint_ms.mean();
        stats["checkpoint_bytes"] = std::filesystem::file_size(checkpoint_path, ec);
    }
    remove_stale_frames(frames_dir, frames_done, scene.frame_format);
    if (!scene.point_cache.empty() && !failure && !interrupted && frames_done == frames) {
        const std::filesystem::path point_cache_path =
            out / point_cache_file_name(scene.point_cache);
        try {
            write_point_cache_from_frames(
                point_cache_path, scene.point_cache, frames_done, scene.frames_per_second,
                [&](int frame) { return frames_dir / frame_file_name(frame, scene.frame_format); });
            stats["point_cache"] = point_cache_path.string();
        } catch (const Error& e) {  // the frames are complete: report, keep stats.json
            log_warning("{}: the point cache was not written: {}", scene_name, e.what());
            stats["point_cache"] = nullptr;
        }
    }
    stats["interrupted"] = interrupted;
    stats["error"] = failure_json;  // null after a complete run
    if (preview) {
        try {
            stats["preview"] = preview->finish().string();
            stats["preview_ms_per_frame"] = preview->render_ms() / (frames_run + first_frame);
        } catch (const IoError&) {
            if (!failure) {
                throw;
            }
            // The run already failed to write: the frames and stats.json matter more.
        }
    }
    bool stats_written = true;
    try {
        io::write_file_atomically(out / "stats.json",
                                  [&](std::ostream& s) { s << stats.dump(2) << '\n'; });
    } catch (const IoError& e) {
        // No stats.json rather than one that describes other frames.
        std::filesystem::remove(out / "stats.json", ec);
        stats_written = false;
        if (!failure) {
            throw;
        }
        log_warning("{}: {}; stats.json removed", scene_name, e.what());
    }
    if (failure) {
        log_info("frames 0-{} (before the failure) are in {}, stats in {}", frames_done,
                 frames_dir.string(), (out / "stats.json").string());
        if (write_failed) {
            rethrow_with_context(
                failure,
                fmt::format("{}: after frame {}: writing the output failed; frames 0-{}{} "
                            "are kept in {}; free space and rerun with --resume: ",
                            scene_name, frames_done, frames_done,
                            stats_written ? " and stats.json describing them" : "", out.string()));
        }
        rethrow_with_context(failure, fmt::format("{}: frame {}: ", scene_name, frames_done + 1));
    }
    if (interrupted) {
        throw Interrupted(
            fmt::format("stopped after frame {} of {}; frames 0-{} in {}, {}stats in {}{}",
                        frames_done, frames, frames_done, frames_dir.string(),
                        stats.contains("preview")
                            ? fmt::format("preview {}, ", stats["preview"].get<std::string>())
                            : std::string(),
                        (out / "stats.json").string(),
                        options.checkpoint_every > 0 ? "; continue with --resume" : ""));
    }
    return stats;
}

}  // namespace pliant::pipeline
