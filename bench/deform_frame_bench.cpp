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
//   bin/bench_deform_frame [--driver twist|wave|bubble|drag|all] [--frames N] [--size N]
//                          [--threads N] [--no-shading] [--json]
//
// bench/compare_deform_vtk runs it beside VTK's fixed-point ray caster on the undeformed 256³
// phantom in the same run.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/mapped_raycast.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
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
    bool shading = true;
    bool json = false;
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
        } else if (a == "--no-shading") {
            shading = false;
        } else if (a == "--json") {
            json = true;
        } else {
            std::fprintf(stderr,
                         "usage: bench_deform_frame [--driver twist|wave|bubble|drag|all] "
                         "[--frames N] [--size N] [--threads N] [--no-shading] [--json]\n");
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
    set_num_threads(threads);
    const bench::SourceScaleWorkload& w = bench::source_scale_workload();
    const volume::Volume& source = w.source;
    const render::Camera camera =
        render::orbit_camera(source.bounds(), 30.0, 20.0, 0.0, size, size);
    render::RayCastOptions options;
    options.shading = shading;
    Stage prepare_map{"map route: source preparation (once)"};
    std::optional<render::MappedRayCaster> mapped;
    timed(prepare_map, [&] { mapped.emplace(source, nullptr, source, options); });
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
            "source scale: 256^3 rgba8, %zu tets, %dx%d, %s, %d threads; map route's "
            "source preparation (once) %.1f ms\n",
            w.grid.mesh.tets.size(), size, size, shading ? "shaded" : "unshaded", num_threads(),
            prepare_map.wall);
    }
    for (std::size_t di = 0; di < drivers.size(); ++di) {
        const int d = drivers[di];
        bench::DrivenBody driven = bench::source_scale_driven_body(d, {});
        pbd::SoftBody& body = driven.body;
        int frame = 0;
        for (; frame < 24; ++frame) {
            driven.step(frame);
        }
        Stage step{"step (10 substeps)"}, resample{"exact: resample"},
            update{"exact: RayCaster prepare/update"}, render_exact{"exact: render"},
            build{"map: InverseMap::build"}, set_map{"map: set_map (occupancy)"},
            render_map{"map: render (+ empty cubes)"};
        render::Image exact_image, map_image;
        std::int64_t exact_samples = 0, map_samples = 0;
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
        }
        const double db = psnr(exact_image, map_image);
        const Stage* stages[] = {&step,  &resample, &update,    &render_exact,
                                 &build, &set_map,  &render_map};
        const double exact_wall =
            (step.wall + resample.wall + update.wall + render_exact.wall) / frames;
        const double exact_cpu = (step.cpu + resample.cpu + update.cpu + render_exact.cpu) / frames;
        const double map_wall = (step.wall + build.wall + set_map.wall + render_map.wall) / frames;
        const double map_cpu = (step.cpu + build.cpu + set_map.cpu + render_map.cpu) / frames;
        if (json) {
            std::printf(
                "%s{\"driver\": \"%s\", \"frames\": %d, \"inverted\": %lld, "
                "\"exact_samples\": %lld, \"map_samples\": %lld, \"psnr_map_vs_exact_db\": "
                "%.2f, \"visible_cells\": %lld, \"cells\": %lld, \"stages\": {",
                di == 0 ? "" : ", ", names[static_cast<std::size_t>(d)].c_str(), frames,
                static_cast<long long>(body.stats().inverted_tets),
                static_cast<long long>(exact_samples), static_cast<long long>(map_samples), db,
                static_cast<long long>(mapped->num_visible_cells()),
                static_cast<long long>(mapped->num_cells()));
            for (std::size_t s = 0; s < std::size(stages); ++s) {
                std::printf("%s\"%s\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}", s == 0 ? "" : ", ",
                            stages[s]->name, stages[s]->wall / frames, stages[s]->cpu / frames);
            }
            std::printf(
                "}, \"exact_frame\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}, "
                "\"map_frame\": {\"wall_ms\": %.2f, \"cpu_ms\": %.2f}}",
                exact_wall, exact_cpu, map_wall, map_cpu);
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
            std::printf(
                "  samples: exact %lld, map %lld; map cells visible %lld of %lld; PSNR "
                "map vs exact %.2f dB\n",
                static_cast<long long>(exact_samples), static_cast<long long>(map_samples),
                static_cast<long long>(mapped->num_visible_cells()),
                static_cast<long long>(mapped->num_cells()), db);
        }
    }
    if (json) {
        std::printf("]}\n");
    }
    return 0;
}
