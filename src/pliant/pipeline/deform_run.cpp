#include "pliant/pipeline/deform_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <variant>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/checkpoint.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/io/vtu.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "pliant/pipeline/frame_pipeline.hpp"
#include "pliant/pipeline/memory_budget.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/mapped_raycast.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::pipeline {
namespace {

// The run's sums, saved in checkpoints before the soft body's state.
struct DeformTotals {
    std::int32_t frame = 0;  // the last frame simulated
    RunningMean substep_ms, step_ms, resample_ms, render_ms, frame_ms;
    double min_ratio = std::numeric_limits<double>::infinity();
    double max_ratio = -std::numeric_limits<double>::infinity();
    std::int64_t max_inverted = 0;

    void save(ByteWriter& w) const {
        w.put(frame);
        for (const RunningMean* r : {&substep_ms, &step_ms, &resample_ms, &render_ms, &frame_ms}) {
            w.put(r->sum);
            w.put(r->count);
        }
        w.put(min_ratio);
        w.put(max_ratio);
        w.put(max_inverted);
    }
    void load(ByteReader& r) {
        frame = r.get<std::int32_t>("frame");
        for (RunningMean* running : {&substep_ms, &step_ms, &resample_ms, &render_ms, &frame_ms}) {
            running->sum = r.get<double>("timing sum");
            running->count = r.get<int>("timing count");
        }
        min_ratio = r.get<double>("min volume ratio");
        max_ratio = r.get<double>("max volume ratio");
        max_inverted = r.get<std::int64_t>("max inverted tets");
    }
};

// What the run's result depends on (io::run_fingerprint): the source volume, the body as built
// (rest shape, tets, masses), its options, the driver and fps; not the frame count, the video,
// the camera or the thread count. The state saves the constraints' rest data and inversion flags
// in the solver's constraint order (pbd/detail/lattice_sweep.hpp); the tag names that order, so a
// checkpoint saved in another order is refused instead of resumed with its data misplaced.
std::uint64_t deform_fingerprint(const volume::Volume& source, const pbd::SoftBody& body,
                                 const DeformRunOptions& options) {
    ByteWriter w;
    w.put_string("pliant deform, constraints in lattice-run order");
    w.put_bytes(source.bytes());
    w.put_vector(body.rest_positions());
    w.put_vector(body.tets());
    w.put_vector(body.inv_masses());
    w.put(options.body.stiffness);
    w.put(options.body.damping);
    w.put(options.body.substeps);
    w.put(options.fps);
    w.put(static_cast<std::uint32_t>(options.driver.index()));
    std::visit(
        [&](const auto& d) {
            using D = std::decay_t<decltype(d)>;
            if constexpr (std::is_same_v<D, pbd::WaveDriver>) {
                w.put(d.direction);
                w.put(d.displacement);
                w.put(d.amplitude);
                w.put(d.wavelength);
                w.put(d.speed);
                w.put(d.ramp_time);
            } else if constexpr (std::is_same_v<D, pbd::TwistDriver>) {
                w.put(d.axis);
                w.put(d.angle);
                w.put(d.ramp_time);
                w.put(d.grip);
            } else if constexpr (std::is_same_v<D, pbd::BubbleDriver>) {
                w.put(d.centre);
                w.put(d.radius);
                w.put(d.inflation);
                w.put(d.ramp_time);
            } else {
                w.put(d.axis);
                w.put(d.angle);
                w.put(d.ramp_time);
                w.put(d.centre.has_value());
                w.put(d.centre.value_or(Vec3d{0.0, 0.0, 0.0}));
            }
        },
        options.driver);
    return io::run_fingerprint(w.bytes());
}

}  // namespace

std::filesystem::path deform_checkpoint_path(const std::filesystem::path& out) {
    std::filesystem::path path = out;
    path += ".checkpoint.bin";
    return path;
}

nlohmann::ordered_json run_deform(const volume::Volume& source, const volume::TransferFunction* tf,
                                  const DeformRunOptions& options) {
    io::check_volume_writable(options.out, source.type());  // fail before the run, not after
    if (!options.mesh_out.empty() && options.mesh_out.extension() != ".vtu") {
        throw InvalidInput(fmt::format("deform: the mesh output {} must be a .vtu file (VTK XML)",
                                       options.mesh_out.string()));
    }
    if (options.thin_levels < 0 || options.thin_levels > render::detail::MAX_THIN_LEVELS) {
        throw InvalidInput(fmt::format("deform: thin_levels must be in [0, {}], got {}",
                                       render::detail::MAX_THIN_LEVELS, options.thin_levels));
    }
    if (options.mesh.empty() && options.grid.cell_voxels >= 1) {
        // Every cell of the grid counted: an upper bound on the soft body's size.
        const volume::Dims& d = source.dims();
        const auto cells_along = [&](int axis) {
            return static_cast<std::uint64_t>(
                (d[static_cast<std::size_t>(axis)] + options.grid.cell_voxels - 1) /
                options.grid.cell_voxels);
        };
        const std::uint64_t cells =
            saturating_product(saturating_product(cells_along(0), cells_along(1)), cells_along(2));
        const bool renders = !options.video.empty() || !options.still.empty();
        require_memory(
            fmt::format("deform: a grid of {} cells of {}^3 voxels over the {} x {} x {} volume",
                        cells, options.grid.cell_voxels, d[0], d[1], d[2]),
            deform_need_bytes(source, cells, renders ? options.size[0] : 0,
                              renders ? options.size[1] : 0),
            options.max_memory_bytes > 0 ? options.max_memory_bytes : available_memory_bytes());
    }
    io::require_writable_file(options.out);

    // The soft body: a grid over the volume, or a TetGen mesh in the volume's world frame.
    DeformableVolume deformable(source, tf, options.grid, options.mesh, options.body);
    pbd::SoftBody& body = deformable.body();
    const geometry::TetMesh& rest = deformable.rest();
    const pbd::TetGrid* grid = deformable.grid();
    body.add_driver(options.driver);
    const double dt = 1.0 / options.fps;
    std::optional<io::VideoWriter> video;
    if (!options.video.empty()) {
        video.emplace(options.video, options.size[0], options.size[1], options.fps);
    }
    const render::Camera camera =
        render::orbit_camera(source.bounds(), options.camera[0], options.camera[1],
                             options.camera[2], options.size[0], options.size[1]);
    render::RayCastOptions ray_options;
    ray_options.shading = options.shading;
    ray_options.step = options.step;
    ray_options.thin_levels = options.thin_levels;

    const std::filesystem::path checkpoint_path = deform_checkpoint_path(options.out);
    const bool checkpoints = options.checkpoint_every > 0 && !video;
    DeformTotals totals;
    std::error_code ec;
    const std::uint64_t fingerprint =
        checkpoints || options.resume ? deform_fingerprint(source, body, options) : 0;
    if (options.resume) {
        if (video) {
            throw Unsupported(fmt::format(
                "--resume cannot continue the video {}: an MP4 is written in one go; run without "
                "--resume (or without --render)",
                options.video.string()));
        }
        if (std::filesystem::exists(checkpoint_path, ec)) {
            const io::Checkpoint checkpoint =
                io::read_checkpoint(checkpoint_path, io::CheckpointKind::deform, fingerprint);
            ByteReader r(checkpoint.payload, checkpoint_path.string());
            totals.load(r);
            body.load_state(r);
            r.expect_end();
            if (totals.frame < 0 || totals.frame >= options.frames) {
                throw InvalidInput(fmt::format(
                    "{}: the checkpoint is at frame {}, expected one before the last frame ({}); "
                    "ask for more frames or run without --resume",
                    checkpoint_path.string(), totals.frame, options.frames));
            }
            log_info("deform: resuming after frame {} from {}", totals.frame,
                     checkpoint_path.string());
        } else {
            log_info("deform: no checkpoint at {}: starting from frame 0",
                     checkpoint_path.string());
        }
    } else {
        std::filesystem::remove(checkpoint_path, ec);
    }
    io::remove_stray_temporaries(checkpoint_path.parent_path().empty()
                                     ? std::filesystem::path(".")
                                     : checkpoint_path.parent_path());
    RunningMean& substep_ms = totals.substep_ms;
    RunningMean& step_ms = totals.step_ms;
    RunningMean& resample_ms = totals.resample_ms;
    RunningMean& render_ms = totals.render_ms;
    RunningMean& frame_ms = totals.frame_ms;
    double& min_ratio = totals.min_ratio;
    double& max_ratio = totals.max_ratio;
    std::int64_t& max_inverted = totals.max_inverted;
    pbd::SoftBodyStats stats;
    volume::ResampleStats resampled;
    render::Image image;
    std::optional<render::RayCaster> caster;
    std::optional<render::MappedRayCaster> mapped;
    RunningMean map_ms;

    // The frames run through run_frame_pipeline (frame_pipeline.hpp): produce = the step, a copy
    // of the positions and (map route) the frame's inverse map into a slot; consume = the
    // resample (exact route, and the output volume at the last frame) from the slot's positions,
    // set_map or the caster's update, render, write. The exact route resamples on the consuming
    // side: on the producer's one thread it would take longer than all the rest. Pipelined only
    // when every frame renders and no checkpoint is saved (a checkpoint is the body at the frame
    // just consumed, which the next frame's step has already moved on).
    const bool every_frame = video.has_value() || static_cast<bool>(options.frame_sink);
    const bool pipelined = options.pipelined && every_frame && !checkpoints;
    const bool map_route = options.resample == ResampleMode::map;
    const auto renders = [&](int frame) {
        return every_frame || (frame == options.frames && !options.still.empty());
    };
    volume::Volume target = deformable.target_like();  // the last resample
    struct Slot {
        pbd::SoftBodyStats stats;
        std::vector<Vec3f> positions;  // the body's, after the frame's step
        volume::InverseMap map;
        double build_ms = 0.0;  // the inverse map
    };
    std::array<Slot, 2> slots;
    const auto produce = [&](int frame, int slot) {
        Slot& s = slots[static_cast<std::size_t>(slot)];
        body.step(dt);
        s.stats = body.stats();
        s.positions.assign(body.positions().begin(), body.positions().end());
        s.build_ms = 0.0;
        if (renders(frame) && map_route) {
            // The frame through its inverse map: no resample, the source prepared once.
            const Stopwatch clock;
            deformable.build_map(s.positions, s.map);
            s.build_ms = clock.elapsed_ms();
        }
    };
    const Stopwatch run_clock;
    double last_frame_end = 0.0;
    int frames_run = 0;
    const auto consume = [&](int frame, int slot) {
        const Slot& s = slots[static_cast<std::size_t>(slot)];
        stats = s.stats;
        substep_ms.add(stats.ms_per_substep);
        step_ms.add(stats.step_ms);
        min_ratio = std::min(min_ratio, stats.volume_ratio);
        max_ratio = std::max(max_ratio, stats.volume_ratio);
        max_inverted = std::max(max_inverted, stats.inverted_tets);
        if (renders(frame) && map_route) {
            const Stopwatch clock;
            if (!mapped) {
                mapped.emplace(source, tf, source, ray_options);
            }
            mapped->set_map(s.map);
            map_ms.add(s.build_ms + clock.elapsed_ms());
            render_ms.add(mapped->render(camera, image).ms);
        }
        if (frame == options.frames || (every_frame && !map_route)) {
            const Stopwatch clock;
            resampled = deformable.resample(s.positions, target);
            resample_ms.add(clock.elapsed_ms());
        }
        if (renders(frame) && !map_route) {
            // One caster for the run: later frames have the same size and kind, so update()
            // reuses its arrays instead of faulting in a new float copy every frame.
            if (caster) {
                caster->update(target, tf);
            } else {
                caster.emplace(target, tf, ray_options);
            }
            render_ms.add(caster->render(camera, image).ms + caster->prepare_ms());
        }
        if (renders(frame)) {
            if (video) {
                video->write(image);
            }
            if (options.frame_sink) {
                options.frame_sink(frame, image);
            }
        }
        // A frame's wall time: since the previous frame was done (pipelined: the period).
        const double now = run_clock.elapsed_ms();
        frame_ms.add(now - last_frame_end);
        last_frame_end = now;
        ++frames_run;
        if (checkpoints && frame % options.checkpoint_every == 0 && frame < options.frames) {
            totals.frame = frame;
            ByteWriter w;
            totals.save(w);
            body.save_state(w);
            io::Checkpoint checkpoint;
            checkpoint.kind = io::CheckpointKind::deform;
            checkpoint.fingerprint = fingerprint;
            checkpoint.payload.assign(w.bytes().begin(), w.bytes().end());
            io::write_checkpoint(checkpoint_path, checkpoint);
        }
        if (options.progress) {
            options.progress(frame, options.frames, frame_ms.mean());
        }
    };
    FramePipelineOptions pipeline_options;
    pipeline_options.pipelined = pipelined;
    pipeline_options.producer_threads = std::max(1, num_threads() / 2);
    run_frame_pipeline(totals.frame + 1, options.frames, produce, consume, pipeline_options);
    const double frame_period_ms = frames_run > 0 ? run_clock.elapsed_ms() / frames_run : 0.0;
    io::write_volume(options.out, target);
    if (!options.still.empty()) {
        io::write_png(options.still, image);
    }
    if (!options.mesh_out.empty()) {
        io::write_vtu(options.mesh_out, body.positions(), rest.tets, rest.positions);
    }
    if (video) {
        video->finish();
    }
    std::filesystem::remove(checkpoint_path, ec);  // the run is complete

    // How far the body moved from its rest shape (last frame), world units.
    double max_displacement = 0.0, sum_displacement = 0.0;
    const std::span<const Vec3f> now = body.positions();
    for (std::size_t v = 0; v < now.size(); ++v) {
        const double d = std::sqrt(squared_norm(vec3_cast<double>(now[v] - rest.positions[v])));
        max_displacement = std::max(max_displacement, d);
        sum_displacement += d;
    }
    const auto path_or_null = [](const std::filesystem::path& p) {
        return p.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(p.string());
    };
    return {{"output", options.out.string()},
            {"render", path_or_null(options.video)},
            {"still", path_or_null(options.still)},
            {"mesh_output", path_or_null(options.mesh_out)},
            {"driver", options.driver_name},
            {"frames", options.frames},
            {"substeps", options.body.substeps},
            {"stiffness", options.body.stiffness},
            {"vertices", rest.positions.size()},
            {"tets", rest.tets.size()},
            {"active_cells", grid ? grid->num_active_cells() : 0},
            {"ms_per_substep", substep_ms.mean()},
            {"step_ms", step_ms.mean()},
            {"resample_ms", resample_ms.mean()},
            {"resample_mode", name(options.resample)},
            {"thin_levels", options.thin_levels},
            {"map_ms", map_ms.mean()},
            {"render_ms", render_ms.mean()},
            {"ms_per_frame", frame_ms.mean()},
            {"frame_period_ms", frame_period_ms},
            {"pipelined", pipelined},
            {"volume_ratio", stats.volume_ratio},
            {"inverted_tets", stats.inverted_tets},
            {"max_displacement", max_displacement},
            {"mean_displacement",
             now.empty() ? 0.0 : sum_displacement / static_cast<double>(now.size())},
            {"min_volume_ratio", min_ratio},
            {"max_volume_ratio", max_ratio},
            {"max_inverted_tets", max_inverted},
            {"tets_skipped", resampled.num_tets_skipped},
            {"voxels_written", resampled.num_voxels_written}};
}

}  // namespace pliant::pipeline
