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
#include <vector>

#include "pliant/cloth/ccd_fail_safe.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/video.hpp"
#include "pliant/pipeline/cloth_preview.hpp"
#include "pliant/pipeline/cloth_setup.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"

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

    const std::filesystem::path frames_dir = out / "frames";
    io::make_output_directory(frames_dir);
    std::unique_ptr<ClothPreview> preview;
    if (options.preview) {
        preview = std::make_unique<ClothPreview>(out, solver.positions(), sim.setup().shapes,
                                                 scene.frames_per_second, options.preview_width,
                                                 options.preview_height);
    }
    geometry::TriangleMeshD state{mesh.positions, mesh.triangles};
    const auto write_frame = [&](int frame) {
        state.positions.assign(solver.positions().begin(), solver.positions().end());
        io::write_mesh(frames_dir / frame_file_name(frame, scene.frame_format), state);
        if (preview) {
            preview->add_frame(solver.positions(), solver.triangles(), solver.time());
        }
    };
    write_frame(0);

    // One constraint iteration per substep: long substeps make cloth stretch and can make it
    // diverge (a 2 m sheet of 2 cm edges at 25 ms), whatever the scene.
    const double substep_ms = 1e3 / (scene.frames_per_second * scene.substeps);
    if (substep_ms > MAX_QUIET_SUBSTEP_MS) {
        log_warning(
            "{}: substeps of {:.4g} ms (fps {} x {} substeps): above about {} ms cloth stretches "
            "far and can diverge; raise substeps (the built-in scenes use about 1 ms)",
            scene_name, substep_ms, scene.frames_per_second, scene.substeps, MAX_QUIET_SUBSTEP_MS);
    }
    int frames_done = 0;
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    double total_ms = 0.0;
    // Frame 0 as written: the input, or what untangling left of its intersections.
    std::int64_t worst_intersections = untangled ? untangled->final_pairs : initial_intersections;
    double worst_strain = 0.0;
    double worst_strain_p99 = 0.0;
    // A frame that fails (the simulation diverged, or a guard such as self-collision's pair limit
    // tripped) ends the run like an interrupt: the frames before it and stats.json (with
    // "error") are written, then the error is reported.
    std::exception_ptr failure;
    nlohmann::ordered_json failure_json;
    bool warned_budget = false;  // the fail-safe's budget warning is given once
    bool warned_lag = false;     // so is the lagging pins' warning
    for (int frame = 1; frame <= frames; ++frame) {
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
        total_ms += ms;
        Stopwatch writing;
        write_frame(frame);
        const double write_ms = writing.elapsed_ms();
        // The independent checks on the frame as written.
        const ClothFrameCheck check = sim.check();
        const std::int64_t intersecting = check.intersecting_pairs;
        worst_intersections = std::max(worst_intersections, intersecting);
        const cloth::StrainStats& strain = check.strain;
        worst_strain = std::max(worst_strain, strain.max);
        worst_strain_p99 = std::max(worst_strain_p99, strain.p99);
        nlohmann::ordered_json record = {{"frame", frame},
                                         {"ms", ms},
                                         {"step_ms", step.solve_ms},
                                         {"refit_ms", step.self.refit_ms},
                                         {"traverse_ms", step.self.traverse_ms},
                                         {"narrow_ms", step.self.narrow_ms},
                                         {"response_ms", step.self.response_ms},
                                         {"obstacle_contacts", step.obstacle_contacts},
                                         {"intersecting_pairs", intersecting},
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
        }
        per_frame.push_back(record);
        frames_done = frame;
        if (options.progress) {
            options.progress(frame, frames, total_ms / frame);
        }
    }
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
        {"threads", num_threads()},
        {"initial_intersecting_pairs", initial_intersections},
        {"untangle", untangle_report(start)},
        {"max_intersecting_pairs", worst_intersections},
        {"max_strain_p99", worst_strain_p99},
        {"max_strain", worst_strain},
        {"frames", per_frame},
        {"mean_ms_per_frame", frames_done > 0 ? total_ms / frames_done : 0.0},
    };
    remove_stale_frames(frames_dir, frames_done, scene.frame_format);
    const bool interrupted = frames_done < frames && !failure;
    stats["interrupted"] = interrupted;
    stats["error"] = failure_json;  // null after a complete run
    if (preview) {
        stats["preview"] = preview->finish().string();
        stats["preview_ms_per_frame"] = preview->render_ms() / (frames_done + 1);
    }
    io::write_file_atomically(out / "stats.json",
                              [&](std::ostream& s) { s << stats.dump(2) << '\n'; });
    if (failure) {
        log_info("frames 0-{} (before the failure) are in {}, stats in {}", frames_done,
                 frames_dir.string(), (out / "stats.json").string());
        rethrow_with_context(failure, fmt::format("{}: frame {}: ", scene_name, frames_done + 1));
    }
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

}  // namespace pliant::pipeline
