// A whole deformed frame at the source system's scale (issue 29), stage by stage, through both
// routes of pipeline::ResampleMode: the 256³ rgba8 phantom with its 64³-cell tet grid
// (source_scale_phantom.hpp), the soft body at stiffness 0.8 and 10 substeps under a driver
// (twist, wave, bubble, drag as bench_pbd's BM_SourceScaleStep) for 24 warm-up frames, then
// `frames` timed frames of: the step; exact: Resampler::resample, RayCaster::update, render;
// map: InverseMap::build, MappedRayCaster::set_map, render; 512² perspective at 30°, 20°,
// shaded unless --no-shading. Prints per stage the mean wall ms and the process CPU ms
// (all threads), the classified samples, and the PSNR of the last frame's map render against
// its exact render; --json prints the same as one JSON object.
//
// Then the frames pipelined as `pliant deform --render` runs them (pipeline/frame_pipeline.hpp):
// for each route, --pipe-frames more frames (default max(8, frames)) with the step and map (or
// the step alone) of frame f + 1 on one thread while frame f's set_map and render (or resample,
// update and render) run on the others. The period is the wall (and process CPU) ms between the
// end of the first frame's render and the end of the last one's, per frame: the throughput,
// with the stages overlapped. Beside it the mean wall ms of the produce (step + map / copy of
// the positions) and consume (set_map + render / resample + update + render) sides as they ran
// overlapped. Three alternatives of the map route for comparison: the map's state computed on
// the producing side too (MappedRayCaster::compute_map with the camera's empty cubes; the
// consumer installs it), the map built on the consuming side, and the producer on every thread
// (the step's two lanes) instead of one.
//
// --scalar adds a stage: set_map of the same maps for the 256³ phantom as an f32 scalar source
// through `mri-brain` (the viewer's and `pliant deform`'s input), whose occupancy tests its
// cells' value ranges through the lookup table. --volume FILE replaces the phantom with an rgba8
// volume file (a radiance field's cleaned reconstruction, `pliant demo`'s nerf/cleaned.nrrd) and
// its grid of cells of 4 voxels. Beside the map route's render, the same map rendered with the
// adaptive step's first level only (MappedRayCaster::set_thin_levels(1)): its time and samples;
// after the timed frames, the last one's map once more with every step sampled (thin_levels 0):
// its samples, and both levels' PSNR against it.
//
//   bin/bench_deform_frame [--driver twist|wave|bubble|drag|all] [--frames N] [--size N]
//                          [--threads N] [--pipe-frames N] [--no-shading] [--scalar]
//                          [--volume FILE] [--json]
//
// bench/compare_deform_vtk runs it beside VTK's fixed-point ray caster on the undeformed 256³
// phantom in the same run.
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <optional>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pipeline/frame_pipeline.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/mapped_raycast.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "source_scale_body.hpp"
#include "source_scale_phantom.hpp"

namespace {

using namespace pliant;

double cpu_ms() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return 1e3 * (static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec)) +
           1e-3 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Stage {
    const char* name;
    double wall = 0.0, cpu = 0.0;
    int count = 0;
};

// Times f() into s (wall and process CPU).
template <typename F>
void timed(Stage& s, F&& f) {
    const double c0 = cpu_ms();
    const Stopwatch watch;
    f();
    s.wall += watch.elapsed_ms();
    s.cpu += cpu_ms() - c0;
    ++s.count;
}

// A pipelined run's numbers (see the top of the file).
struct Pipelined {
    double period_wall = 0.0, period_cpu = 0.0;     // ms per frame
    double produce_wall = 0.0, consume_wall = 0.0;  // mean ms per frame
    int frames = 0;
};

// Frames first..last through run_frame_pipeline; produce / consume as there.
template <typename Produce, typename Consume>
Pipelined run_pipelined(int first, int last, Produce&& produce, Consume&& consume,
                        int producer_threads = 1) {
    Pipelined out;
    out.frames = last - first + 1;
    double wall0 = 0.0, cpu0 = 0.0, wall1 = 0.0, cpu1 = 0.0, produce_sum = 0.0, consume_sum = 0.0;
    const Stopwatch watch;
    pipeline::run_frame_pipeline(
        first, last,
        [&](int frame, int slot) {
            const Stopwatch clock;
            produce(frame, slot);
            produce_sum += clock.elapsed_ms();
        },
        [&](int frame, int slot) {
            const Stopwatch clock;
            consume(frame, slot);
            consume_sum += clock.elapsed_ms();
            if (frame == first) {
                wall0 = watch.elapsed_ms();
                cpu0 = cpu_ms();
            } else if (frame == last) {
                wall1 = watch.elapsed_ms();
                cpu1 = cpu_ms();
            }
        },
        {.producer_threads = producer_threads});
    const int periods = std::max(1, last - first);
    out.period_wall = (wall1 - wall0) / periods;
    out.period_cpu = (cpu1 - cpu0) / periods;
    out.produce_wall = produce_sum / out.frames;
    out.consume_wall = consume_sum / out.frames;
    return out;
}

double psnr(const render::Image& a, const render::Image& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]);
        sum += d * d;
    }
    return sum == 0.0
               ? 999.0
               : 10.0 * std::log10(255.0 * 255.0 * static_cast<double>(a.pixels.size()) / sum);
}

}  // namespace

int main(int argc, char** argv) {
    std::string driver = "twist";
    int frames = 4;
    int size = 512;
    int threads = 0;
    int pipe_frames = 0;
    bool shading = true;
    bool scalar = false;
    bool json = false;
    std::string volume_path;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        if (a == "--driver" && has_value) {
            driver = argv[++i];
        } else if (a == "--frames" && has_value) {
            frames = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--size" && has_value) {
            size = std::max(8, std::atoi(argv[++i]));
        } else if (a == "--threads" && has_value) {
            threads = std::max(0, std::atoi(argv[++i]));
        } else if (a == "--pipe-frames" && has_value) {
            pipe_frames = std::max(2, std::atoi(argv[++i]));
        } else if (a == "--no-shading") {
            shading = false;
        } else if (a == "--scalar") {
            scalar = true;
        } else if (a == "--json") {
            json = true;
        } else if (a == "--volume" && has_value) {
            volume_path = argv[++i];
        } else {
            std::fprintf(stderr,
                         "usage: bench_deform_frame [--driver twist|wave|bubble|drag|all] "
                         "[--frames N] [--size N] [--threads N] [--pipe-frames N] [--no-shading] "
                         "[--scalar] [--volume FILE] [--json]\n");
            return 2;
        }
    }
    const std::vector<std::string> names = {"twist", "wave", "bubble", "drag"};
    std::vector<int> drivers;
    for (int d = 0; d < 4; ++d) {
        if (driver == "all" || driver == names[static_cast<std::size_t>(d)]) {
            drivers.push_back(d);
        }
    }
    if (drivers.empty()) {
        std::fprintf(stderr, "bench_deform_frame: unknown driver '%s'\n", driver.c_str());
        return 2;
    }
    if (pipe_frames == 0) {
        pipe_frames = std::max(8, frames);
    }
    if (scalar && !volume_path.empty()) {
        std::fprintf(stderr, "bench_deform_frame: --scalar is the phantom's, not --volume's\n");
        return 2;
    }
    set_num_threads(threads);
    std::unique_ptr<bench::SourceScaleWorkload> from_file;
    if (!volume_path.empty()) {
        try {
            volume::Volume v = io::read_volume(volume_path);
            if (v.type() != volume::VoxelType::rgba8) {
                throw InvalidInput(volume_path + ": expected an rgba8 volume");
            }
            from_file = bench::source_scale_workload_of(std::move(v));
        } catch (const Error& e) {
            std::fprintf(stderr, "bench_deform_frame: error: %s\n", e.what());
            return 1;
        }
    }
    const bench::SourceScaleWorkload& w = from_file ? *from_file : bench::source_scale_workload();
    const volume::Volume& source = w.source;
    const render::Camera camera =
        render::orbit_camera(source.bounds(), 30.0, 20.0, 0.0, size, size);
    render::RayCastOptions options;
    options.shading = shading;
    Stage prepare_map{"map route: source preparation (once)"};
    std::optional<render::MappedRayCaster> mapped;
    timed(prepare_map, [&] { mapped.emplace(source, nullptr, source, options); });
    // --scalar: the phantom as f32 values through mri-brain.
    volume::Volume scalar_source;
    volume::TransferFunction scalar_tf;
    std::optional<render::MappedRayCaster> scalar_mapped;
    if (scalar) {
        scalar_source = volume::shepp_logan_3d(source.dims());
        scalar_tf = volume::preset("mri-brain", scalar_source);
        scalar_mapped.emplace(scalar_source, &scalar_tf, scalar_source, options);
        if (!json) {
            std::printf("f32 source's preparation (--scalar, once): %.1f ms\n",
                        scalar_mapped->prepare_ms());
        }
    }
    const volume::Resampler resampler(source, w.grid.mesh.tets, w.grid.mesh.positions);
    volume::Volume target =
        volume::Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
    std::optional<render::RayCaster> caster;

    if (json) {
        std::printf(
            "{\"tets\": %zu, \"size\": %d, \"shading\": %s, \"threads\": %d, "
            "\"map_prepare_ms\": %.2f, \"drivers\": [",
            w.grid.mesh.tets.size(), size, shading ? "true" : "false", num_threads(),
            prepare_map.wall);
    } else {
        std::printf(
            "source scale: %s (%lldx%lldx%lld rgba8), %zu tets, %dx%d, %s, %d threads; map "
            "route's source preparation (once) %.1f ms\n",
            volume_path.empty() ? "phantom" : volume_path.c_str(),
            static_cast<long long>(source.dims()[0]), static_cast<long long>(source.dims()[1]),
            static_cast<long long>(source.dims()[2]), w.grid.mesh.tets.size(), size, size,
            shading ? "shaded" : "unshaded", num_threads(), prepare_map.wall);
    }
    for (std::size_t di = 0; di < drivers.size(); ++di) {
        const int d = drivers[di];
        bench::DrivenBody driven = bench::source_scale_driven_body(d, {}, w);
        pbd::SoftBody& body = driven.body;
        int frame = 0;
        for (; frame < 24; ++frame) {
            driven.step(frame);
        }
        Stage step{"step (10 substeps)"}, resample{"exact: resample"},
            update{"exact: RayCaster prepare/update"}, render_exact{"exact: render"},
            build{"map: InverseMap::build"}, set_map{"map: set_map (occupancy)"},
            render_map{"map: render (+ empty cubes)"},
            render_one_level{"map: render, first thin level only"},
            set_map_scalar{"map: set_map, f32 source (--scalar)"};
        render::Image exact_image, map_image, one_level_image;
        std::int64_t exact_samples = 0, map_samples = 0, one_level_samples = 0;
        volume::InverseMap map;
        for (int f = 0; f < frames; ++f, ++frame) {
            timed(step, [&] { driven.step(frame); });
            timed(resample, [&] { resampler.resample(body.positions(), target); });
            timed(update, [&] {
                if (caster) {
                    caster->update(target, nullptr);
                } else {
                    caster.emplace(target, nullptr, options);
                }
            });
            timed(render_exact,
                  [&] { exact_samples = caster->render(camera, exact_image).samples; });
            timed(build, [&] {
                map.build(source, source, w.grid.mesh.tets, w.grid.mesh.positions, body.positions(),
                          {.node_voxels = w.grid.cell_voxels});
            });
            timed(set_map, [&] { mapped->set_map(map); });
            timed(render_map, [&] { map_samples = mapped->render(camera, map_image).samples; });
            mapped->set_thin_levels(1);
            timed(render_one_level,
                  [&] { one_level_samples = mapped->render(camera, one_level_image).samples; });
            mapped->set_thin_levels(options.thin_levels);
            if (scalar_mapped) {
                timed(set_map_scalar, [&] { scalar_mapped->set_map(map); });
            }
        }
        const double db = psnr(exact_image, map_image);
        const double one_level_db = psnr(exact_image, one_level_image);
        render::Image fixed_image;
        mapped->set_thin_levels(0);
        const std::int64_t fixed_samples = mapped->render(camera, fixed_image).samples;
        mapped->set_thin_levels(options.thin_levels);
        const double map_fixed_db = psnr(fixed_image, map_image);
        const double one_level_fixed_db = psnr(fixed_image, one_level_image);
        // The same stages pipelined, on the frames after these. Map route: step + build in the
        // background, set_map + render on the caller. Exact route: step + a copy of the
        // positions in the background, resample + update + render on the caller (a resample
        // on one thread would take longer than the rest of the frame).
        std::array<volume::InverseMap, 2> maps;
        std::array<render::MapOccupancy, 2> states;
        const int octants = mapped->octants_of(camera);
        const auto step_and_map = [&](int f, int slot) {
            driven.step(f);
            maps[static_cast<std::size_t>(slot)].build(source, source, w.grid.mesh.tets,
                                                       w.grid.mesh.positions, body.positions(),
                                                       {.node_voxels = w.grid.cell_voxels});
        };
        const auto step_map_and_state = [&](int f, int slot) {
            step_and_map(f, slot);
            mapped->compute_map(maps[static_cast<std::size_t>(slot)],
                                states[static_cast<std::size_t>(slot)], octants);
        };
        const auto show_state = [&](int, int slot) {
            mapped->install_map(states[static_cast<std::size_t>(slot)]);
            mapped->render(camera, map_image);
        };
        const auto show_map = [&](int, int slot) {
            mapped->set_map(maps[static_cast<std::size_t>(slot)]);
            mapped->render(camera, map_image);
        };
        const Pipelined map_pipe =
            run_pipelined(frame, frame + pipe_frames - 1, step_and_map, show_map);
        frame += pipe_frames;
        const Pipelined map_producer_state =
            run_pipelined(frame, frame + pipe_frames - 1, step_map_and_state, show_state);
        frame += pipe_frames;
        // The same with the producer on every thread (BackgroundTask's default, the viewer's
        // former scheme): the step's two lanes in the background.
        const Pipelined map_all =
            run_pipelined(frame, frame + pipe_frames - 1, step_and_map, show_map, 0);
        frame += pipe_frames;
        std::array<std::vector<Vec3f>, 2> positions;
        const auto step_and_copy = [&](int f, int slot) {
            driven.step(f);
            positions[static_cast<std::size_t>(slot)].assign(body.positions().begin(),
                                                             body.positions().end());
        };
        const Pipelined exact_pipe =
            run_pipelined(frame, frame + pipe_frames - 1, step_and_copy, [&](int, int slot) {
                resampler.resample(positions[static_cast<std::size_t>(slot)], target);
                caster->update(target, nullptr);
                caster->render(camera, exact_image);
            });
        frame += pipe_frames;
        const Pipelined map_late =
            run_pipelined(frame, frame + pipe_frames - 1, step_and_copy, [&](int, int slot) {
                map.build(source, source, w.grid.mesh.tets, w.grid.mesh.positions,
                          positions[static_cast<std::size_t>(slot)],
                          {.node_voxels = w.grid.cell_voxels});
                mapped->set_map(map);
                mapped->render(camera, map_image);
            });
        frame += pipe_frames;
        std::vector<const Stage*> stages = {&step,  &resample, &update,     &render_exact,
                                            &build, &set_map,  &render_map, &render_one_level};
        if (scalar_mapped) {
            stages.push_back(&set_map_scalar);
        }
        const double exact_wall =
            (step.wall + resample.wall + update.wall + render_exact.wall) / frames;
        const double exact_cpu = (step.cpu + resample.cpu + update.cpu + render_exact.cpu) / frames;
        const double map_wall = (step.wall + build.wall + set_map.wall + render_map.wall) / frames;
        const double map_cpu = (step.cpu + build.cpu + set_map.cpu + render_map.cpu) / frames;
        if (json) {
            std::printf(
                "%s{\"driver\": \"%s\", \"frames\": %d, \"inverted\": %lld, "
                "\"exact_samples\": %lld, \"map_samples\": %lld, \"psnr_map_vs_exact_db\": "
                "%.2f, \"one_level_samples\": %lld, \"psnr_one_level_vs_exact_db\": %.2f, "
                "\"fixed_step_samples\": %lld, \"psnr_map_vs_fixed_step_db\": %.2f, "
                "\"psnr_one_level_vs_fixed_step_db\": %.2f, "
                "\"visible_cells\": %lld, \"cells\": %lld, \"stages\": {",
                di == 0 ? "" : ", ", names[static_cast<std::size_t>(d)].c_str(), frames,
                static_cast<long long>(body.stats().inverted_tets),
                static_cast<long long>(exact_samples), static_cast<long long>(map_samples), db,
                static_cast<long long>(one_level_samples), one_level_db,
                static_cast<long long>(fixed_samples), map_fixed_db, one_level_fixed_db,
                static_cast<long long>(mapped->num_visible_cells()),
                static_cast<long long>(mapped->num_cells()));
            for (std::size_t s = 0; s < stages.size(); ++s) {
                std::printf("%s\"%s\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}", s == 0 ? "" : ", ",
                            stages[s]->name, stages[s]->wall / frames, stages[s]->cpu / frames);
            }
            std::printf(
                "}, \"exact_frame\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}, "
                "\"map_frame\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}",
                exact_wall, exact_cpu, map_wall, map_cpu);
            for (const auto& [key, p] :
                 {std::pair{"map_pipelined", &map_pipe}, std::pair{"exact_pipelined", &exact_pipe},
                  std::pair{"map_state_on_producer_pipelined", &map_producer_state},
                  std::pair{"map_late_pipelined", &map_late},
                  std::pair{"map_all_threads_pipelined", &map_all}}) {
                std::printf(
                    ", \"%s\": {\"frames\": %d, \"period_wall_ms\": %.2f, \"period_cpu_ms\": %.2f, "
                    "\"fps\": %.2f, \"produce_wall_ms\": %.2f, \"consume_wall_ms\": %.2f}",
                    key, p->frames, p->period_wall, p->period_cpu, 1e3 / p->period_wall,
                    p->produce_wall, p->consume_wall);
            }
            std::printf("}");
        } else {
            std::printf("\n%s: %d timed frames after 24, %lld inverted tets\n",
                        names[static_cast<std::size_t>(d)].c_str(), frames,
                        static_cast<long long>(body.stats().inverted_tets));
            std::printf("  %-36s %10s %10s\n", "stage", "wall ms", "CPU ms");
            for (const Stage* s : stages) {
                std::printf("  %-36s %10.1f %10.1f\n", s->name, s->wall / frames, s->cpu / frames);
            }
            std::printf("  %-36s %10.1f %10.1f  (%.1f fps)\n", "whole frame, exact", exact_wall,
                        exact_cpu, 1e3 / exact_wall);
            std::printf("  %-36s %10.1f %10.1f  (%.1f fps)\n", "whole frame, map", map_wall,
                        map_cpu, 1e3 / map_wall);
            struct Row {
                const char* label;
                const Pipelined* p;
                const char* produce;
                const char* consume;
            };
            for (const Row& row :
                 {Row{"pipelined period, exact", &exact_pipe, "step", "resample + update + render"},
                  Row{"pipelined period, map", &map_pipe, "step + build", "set_map + render"},
                  Row{"pipelined, map state on producer", &map_producer_state,
                      "step + build + state", "install + render"},
                  Row{"pipelined, map built late", &map_late, "step", "build + set_map + render"},
                  Row{"pipelined, map, producer all threads", &map_all, "step + build",
                      "set_map + render"}}) {
                std::printf(
                    "  %-36s %10.1f %10.1f  (%.1f fps; %d frames; overlapped: %s %.1f, "
                    "%s %.1f)\n",
                    row.label, row.p->period_wall, row.p->period_cpu, 1e3 / row.p->period_wall,
                    row.p->frames, row.produce, row.p->produce_wall, row.consume,
                    row.p->consume_wall);
            }
            std::printf(
                "  samples: exact %lld, map %lld (first thin level only %lld); map cells visible "
                "%lld of %lld; PSNR map vs exact %.2f dB (first thin level only %.2f dB)\n",
                static_cast<long long>(exact_samples), static_cast<long long>(map_samples),
                static_cast<long long>(one_level_samples),
                static_cast<long long>(mapped->num_visible_cells()),
                static_cast<long long>(mapped->num_cells()), db, one_level_db);
            std::printf(
                "  every step sampled (last frame): %lld samples; PSNR against it: map %.2f dB, "
                "first thin level only %.2f dB\n",
                static_cast<long long>(fixed_samples), map_fixed_db, one_level_fixed_db);
        }
    }
    if (json) {
        std::printf("]}\n");
    }
    return 0;
}
