// Tiny synthetic radiance-field scenes for the nerf tests: fields over the unit box, a
// ground-truth ball field, views rendered from it around the box, and the mean PSNR of a field
// over those views.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/render.hpp"
#include "pliant/nerf/trainer.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::nerf::test {

// A field over the unit box at `resolution`, empty but where set(c, q) writes the 4 raw
// parameters q[0 … 3] of the cell centred at c ∈ [0, 1]³.
template <typename Set>
RadianceGrid unit_box_field(int resolution, const Set& set) {
    RadianceGrid g(AABBd{{0, 0, 0}, {1, 1, 1}}, resolution, -12.0f, 0.0f);
    const auto& d = g.dims();
    auto p = g.params();
    for (int k = 0; k < d[2]; ++k) {
        for (int j = 0; j < d[1]; ++j) {
            for (int i = 0; i < d[0]; ++i) {
                const Vec3d c{(i + 0.5) / d[0], (j + 0.5) / d[1], (k + 0.5) / d[2]};
                set(c, &p[4 * (i + d[0] * (j + static_cast<std::size_t>(d[1]) * k))]);
            }
        }
    }
    return g;
}

// A coloured ball in the unit box: a red core (r < 0.2, σ 8) and a blue shell (r < 0.35, σ 3);
// `banded` adds a green band (|z| < 0.08 or |x − 0.1| < 0.06), texture that pins poses down.
inline RadianceGrid ball_field(int resolution, bool banded = false) {
    return unit_box_field(resolution, [banded](const Vec3d& centre, float* q) {
        const Vec3d c = centre - Vec3d{0.5, 0.5, 0.5};
        const double r = norm(c);
        if (r < 0.35) {
            const bool band = banded && (std::fabs(c.z) < 0.08 || std::fabs(c.x - 0.1) < 0.06);
            q[0] = density_raw_for_sigma(r < 0.2 ? 8.0f : 3.0f);
            q[1] = r < 0.2 ? 2.0f : -2.0f;
            q[2] = band ? 2.5f : -1.0f;
            q[3] = r < 0.2 ? -2.0f : 2.0f;
        }
    });
}

// `views` square views of `size` pixels rendered from `truth`, on a Fibonacci sphere around its
// box (azimuths start at `offset` degrees).
inline Dataset make_dataset(const RadianceGrid& truth, int views, int size, double offset) {
    Dataset ds;
    ds.box = truth.box();
    for (int i = 0; i < views; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / views;
        const double az = (i * 137.508 + offset);
        const render::Camera cam =
            render::frame_box(truth.box(), az, std::asin(z) * 180.0 / std::numbers::pi, size, size);
        ds.intrinsics = intrinsics_from_camera(cam);
        View v;
        v.name = "view" + std::to_string(i);
        v.camera_to_world = pose_from_camera(cam);
        v.rgb = render_view(truth, ds.intrinsics, v.camera_to_world, ds.background);
        ds.views.push_back(std::move(v));
    }
    return ds;
}

// The mean PSNR (dB) of `grid` rendered at the views of `ds` against their images.
inline double mean_psnr(const RadianceGrid& grid, const Dataset& ds) {
    double sum = 0.0;
    for (const View& v : ds.views) {
        sum += psnr(render_view(grid, ds.intrinsics, v.camera_to_world, ds.background), v.rgb);
    }
    return sum / static_cast<double>(ds.views.size());
}

// A training run small enough for a unit test: 24³, two stages, 300 iterations of 512 rays.
inline TrainOptions tiny_options() {
    TrainOptions o;
    o.resolution = 24;
    o.stages = 2;
    o.iterations = 300;
    o.batch_rays = 512;
    return o;
}

// One training run three ways: on 1 thread (saving its state at iteration 25), on 2 threads, and
// resumed from that state: a test checks the three give the same bits.
struct ThreadsAndResume {
    TrainResult one_thread;
    TrainResult two_threads;
    TrainResult resumed;
};

inline ThreadsAndResume train_threads_and_resume(const Dataset& ds, const TrainOptions& o) {
    const auto none = [](const TrainProgress&) {
        return true;
    };
    std::vector<std::byte> state;
    TrainCheckpoints save;
    save.every = 25;
    save.save = [&](std::span<const std::byte> s, std::int64_t iteration) {
        if (iteration == 25) {
            state.assign(s.begin(), s.end());
        }
    };
    set_num_threads(1);
    TrainResult one = train(ds, o, none, save);
    set_num_threads(2);
    TrainResult two = train(ds, o, none);
    if (state.empty()) {
        set_num_threads(0);
        throw InternalError("train_threads_and_resume: no state saved at iteration 25");
    }
    TrainCheckpoints resume;
    resume.resume_from = state;
    resume.resume_source = "state";
    TrainResult resumed = train(ds, o, none, resume);
    set_num_threads(0);
    return {std::move(one), std::move(two), std::move(resumed)};
}

// The state a run of `o` saves last (every 25 iterations), and a run of `o` resumed from `state`.
inline std::vector<std::byte> last_state(const Dataset& ds, const TrainOptions& o) {
    std::vector<std::byte> state;
    TrainCheckpoints save;
    save.every = 25;
    save.save = [&](std::span<const std::byte> s, std::int64_t) {
        state.assign(s.begin(), s.end());
    };
    (void)train(
        ds, o, [](const TrainProgress&) { return true; }, save);
    return state;
}

inline TrainResult train_resumed(const Dataset& ds, const TrainOptions& o,
                                 std::span<const std::byte> state) {
    TrainCheckpoints resume;
    resume.resume_from = state;
    resume.resume_source = "state";
    return train(
        ds, o, [](const TrainProgress&) { return true; }, resume);
}

}  // namespace pliant::nerf::test
