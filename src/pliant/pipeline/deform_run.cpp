#include "pliant/pipeline/deform_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::pipeline {
namespace {

struct Running {
    double sum = 0.0;
    int count = 0;
    void add(double x) {
        sum += x;
        ++count;
    }
    double mean() const { return count > 0 ? sum / count : 0.0; }
};

}  // namespace

nlohmann::ordered_json run_deform(const volume::Volume& source, const volume::TransferFunction* tf,
                                  const DeformRunOptions& options) {
    io::check_volume_writable(options.out, source.type());  // fail before the run, not after
    io::require_writable_file(options.out);

    // The soft body: a grid over the volume, or a TetGen mesh in the volume's world frame.
    DeformableVolume deformable(source, tf, options.grid, options.mesh, options.body);
    pbd::SoftBody& body = deformable.body();
    const geometry::TetMesh& rest = deformable.rest();
    const pbd::TetGrid* grid = deformable.grid();
    body.add_driver(options.driver);
    const double dt = 1.0 / options.fps;
    volume::Volume target = deformable.target_like();
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

    Running substep_ms, step_ms, resample_ms, render_ms, frame_ms;
    double min_ratio = std::numeric_limits<double>::infinity();
    double max_ratio = -std::numeric_limits<double>::infinity();
    std::int64_t max_inverted = 0;
    pbd::SoftBodyStats stats;
    volume::ResampleStats resampled;
    render::Image image;
    for (int frame = 1; frame <= options.frames; ++frame) {
        const Stopwatch frame_clock;
        body.step(dt);
        stats = body.stats();
        substep_ms.add(stats.ms_per_substep);
        step_ms.add(stats.step_ms);
        min_ratio = std::min(min_ratio, stats.volume_ratio);
        max_ratio = std::max(max_ratio, stats.volume_ratio);
        max_inverted = std::max(max_inverted, stats.inverted_tets);
        const bool last = frame == options.frames;
        if (video || last) {
            const Stopwatch clock;
            resampled = deformable.resample(target);
            resample_ms.add(clock.elapsed_ms());
        }
        if (video || (last && !options.still.empty())) {
            const render::RayCaster caster(target, tf, ray_options);
            render_ms.add(caster.render(camera, image).ms + caster.prepare_ms());
            if (video) {
                video->write(image);
            }
        }
        frame_ms.add(frame_clock.elapsed_ms());
        if (options.progress) {
            options.progress(frame, options.frames, frame_ms.mean());
        }
    }
    io::write_volume(options.out, target);
    if (!options.still.empty()) {
        io::write_png(options.still, image);
    }
    if (video) {
        video->finish();
    }

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
            {"render_ms", render_ms.mean()},
            {"ms_per_frame", frame_ms.mean()},
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
