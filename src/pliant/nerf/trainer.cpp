#include "pliant/nerf/trainer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::nerf {

namespace {

constexpr int NUM_CHUNKS = 4;
constexpr float BETA1 = 0.9f;
constexpr float BETA2 = 0.99f;
constexpr float EPSILON = 1e-15f;

std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

// One chunk's gradient: a dense buffer (4 per voxel), a touched flag per voxel and the list of
// touched voxels (in first-touch order).
struct GradientChunk {
    std::vector<float> grad;
    std::vector<std::uint8_t> touched;
    std::vector<std::int32_t> list;
    std::vector<detail::SampleRecord> samples;  // scratch: one ray's records
    std::vector<float> env_grad;                // 3 per environment texel (empty: none)
    double loss = 0.0;
    std::int64_t num_samples = 0;

    void resize(std::int64_t voxels) {
        grad.assign(static_cast<std::size_t>(4 * voxels), 0.0f);
        touched.assign(static_cast<std::size_t>(voxels), 0);
        list.clear();
    }
    void add(std::int32_t v, const float d[4]) {
        if (touched[v] == 0) {
            touched[v] = 1;
            list.push_back(v);
        }
        float* g = grad.data() + 4 * static_cast<std::int64_t>(v);
        g[0] += d[0];
        g[1] += d[1];
        g[2] += d[2];
        g[3] += d[3];
    }
};

class Trainer {
public:
    Trainer(const Dataset& dataset, const TrainOptions& options)
        : m_dataset(dataset), m_options(options), m_box(scene_box(dataset)) {
        const float threshold = -std::log1p(-options.occupancy_alpha) * detail::DENSITY_SCALE;
        m_sigma_threshold = std::max(threshold, 1e-12f);
        m_grid = RadianceGrid(m_box, stage_resolution(0), options.density_init, options.color_init);
        allocate();
        if (options.environment_width > 0) {
            m_env = EnvironmentMap(options.environment_width, options.color_init);
            const std::size_t n = m_env.params().size();
            m_env_m.assign(n, 0.0f);
            m_env_v.assign(n, 0.0f);
            for (GradientChunk& c : m_chunks) {
                c.env_grad.assign(n, 0.0f);
            }
        }
        const Intrinsics& in = dataset.intrinsics;
        m_pixels_per_view = static_cast<std::uint64_t>(in.width) * in.height;
        m_num_pixels = m_pixels_per_view * dataset.views.size();
    }

    int stage_resolution(int stage) const {
        return std::max(4, m_options.resolution >> (m_options.stages - 1 - stage));
    }
    int stage_for(double p) const {
        int s = 0;
        for (int k = 1; k < m_options.stages; ++k) {
            if (p >= 0.3 * k / (m_options.stages - 1)) {
                s = k;
            }
        }
        return s;
    }

    void allocate() {
        const std::int64_t n = m_grid.num_voxels();
        m_m.assign(static_cast<std::size_t>(4 * n), 0.0f);
        m_v.assign(static_cast<std::size_t>(4 * n), 0.0f);
        m_mark.assign(static_cast<std::size_t>(n), 0);
        for (GradientChunk& c : m_chunks) {
            c.resize(n);
        }
        m_stage_iteration = 0;
    }

    // One iteration at progress p; returns the batch's MSE.
    TrainProgress step(double p) {
        // Stage change: coarse to fine.
        const int stage = stage_for(p);
        if (stage != m_stage) {
            m_stage = stage;
            m_grid = m_grid.resampled(stage_resolution(stage), m_sigma_threshold);
            allocate();
        }
        ++m_stage_iteration;
        const bool warm = m_iteration >= m_options.warmup_iterations;
        if (!warm) {
            m_grid.set_all_occupied();
        } else if (m_iteration % m_options.occupancy_interval == 0 ||
                   m_iteration == m_options.warmup_iterations || m_stage_iteration == 1) {
            m_grid.update_occupancy(m_sigma_threshold);
        }

        // Forward and backward over the batch in fixed chunks.
        const int batch = m_options.batch_rays;
        const std::int64_t grain = (batch + NUM_CHUNKS - 1) / NUM_CHUNKS;
        const detail::GridView g = m_grid.view(m_options.render.use_occupancy);
        const float step_length = m_options.render.step_voxels * m_grid.voxel_size();
        const render::Color bgc = m_dataset.background;
        const float bg[3] = {bgc.r, bgc.g, bgc.b};
        const bool learn_env = !m_env.empty();
        const float sparsity = m_options.sparsity;
        const float sparsity_norm = sparsity / static_cast<float>(batch);
        const double norm = 1.0 / (3.0 * batch);
        const Intrinsics& in = m_dataset.intrinsics;
        const std::uint64_t base = static_cast<std::uint64_t>(m_iteration) * batch;
        parallel_for_chunks(
            batch, grain, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                GradientChunk& chunk = m_chunks[static_cast<std::size_t>(c)];
                chunk.loss = 0.0;
                chunk.num_samples = 0;
                for (std::int64_t r = begin; r < end; ++r) {
                    const std::uint64_t h =
                        splitmix64(m_options.seed * 0x632be59bd9b4e019ULL + base + r);
                    const std::uint64_t pixel = h % m_num_pixels;
                    const View& view = m_dataset.views[pixel / m_pixels_per_view];
                    const std::uint64_t local = pixel % m_pixels_per_view;
                    const int x = static_cast<int>(local % in.width);
                    const int y = static_cast<int>(local / in.width);
                    if (!view.mask.empty() && view.mask[local] == 0) {
                        continue;  // an ignored pixel: no loss, no gradient
                    }
                    const NormalizedRay ray =
                        normalize_ray(m_grid, view_ray(intrinsics_of(m_dataset, view),
                                                       view.camera_to_world, x + 0.5, y + 0.5));
                    chunk.samples.clear();
                    EnvironmentTexels texels;
                    float ray_bg[3] = {bg[0], bg[1], bg[2]};
                    if (learn_env) {
                        texels = m_env.locate(ray.direction);
                        m_env.color(texels, ray_bg);
                    }
                    const detail::RayOutput out = detail::march(
                        g, ray.origin, ray.direction, step_length, ray_bg,
                        m_options.render.min_transmittance,
                        [&](const detail::SampleRecord& s) { chunk.samples.push_back(s); });
                    chunk.num_samples += out.samples;
                    const float* target = view.rgb.data() + 3 * local;
                    float gc[3];
                    for (int k = 0; k < 3; ++k) {
                        const double e = static_cast<double>(out.rgb[k]) - target[k];
                        chunk.loss += e * e * norm;
                        gc[k] = static_cast<float>(2.0 * e * norm);
                    }
                    detail::backward(g, chunk.samples.data(),
                                     static_cast<int>(chunk.samples.size()), out.rgb, gc,
                                     [&](std::int32_t v, const float d[4]) { chunk.add(v, d); });
                    if (sparsity > 0.0f) {
                        // Cauchy sparsity prior per sample: (λ / batch) log(1 + 2 τ²), τ = σ δ.
                        for (const detail::SampleRecord& rec : chunk.samples) {
                            const float sp = detail::softplus(rec.s);
                            const float tau = sp * detail::DENSITY_SCALE * rec.length;
                            const float d_s = sparsity_norm * 4.0f * tau /
                                              (1.0f + 2.0f * tau * tau) * rec.length *
                                              detail::DENSITY_SCALE * detail::sigmoid(rec.s);
                            float wt[8];
                            detail::corner_weights(rec.corner, wt);
                            std::int32_t o[8];
                            detail::corner_offsets(g, o);
                            for (int q = 0; q < 8; ++q) {
                                const float dq[4] = {wt[q] * d_s, 0.0f, 0.0f, 0.0f};
                                chunk.add(rec.corner.base + o[q], dq);
                            }
                        }
                    }
                    if (learn_env) {
                        // ∂L/∂raw = T_end · g ⊙ B (1 − B) · bilinear weight.
                        float d[3];
                        for (int k = 0; k < 3; ++k) {
                            d[k] = out.transmittance * gc[k] * ray_bg[k] * (1.0f - ray_bg[k]);
                        }
                        for (int q = 0; q < 4; ++q) {
                            float* e = chunk.env_grad.data() +
                                       3 * static_cast<std::int64_t>(texels.index[q]);
                            for (int k = 0; k < 3; ++k) {
                                e[k] += texels.weight[q] * d[k];
                            }
                        }
                    }
                }
            });
        double loss = 0.0;
        std::int64_t samples = 0;
        for (const GradientChunk& c : m_chunks) {
            loss += c.loss;
            samples += c.num_samples;
        }

        // The union of touched voxels, in chunk order then first-touch order.
        m_union.clear();
        for (GradientChunk& c : m_chunks) {
            for (const std::int32_t v : c.list) {
                if (m_mark[v] == 0) {
                    m_mark[v] = 1;
                    m_union.push_back(v);
                }
            }
            c.list.clear();
        }
        update(p);
        if (learn_env) {
            update_environment(p);
        }

        TrainProgress progress;
        progress.iteration = ++m_iteration;
        progress.progress = p;
        progress.loss = loss;
        progress.psnr = loss > 0.0 ? -10.0 * std::log10(loss) : 99.0;
        progress.resolution = m_grid.resolution();
        progress.samples = samples;
        m_last_loss = loss;
        return progress;
    }

    // Pass 1: total gradient (chunks summed in chunk order) + TV, into chunk 0's buffer; reads
    // parameters only. Pass 2: Adam on the touched voxels, clears the buffers and flags.
    void update(double p) {
        const std::int64_t count = static_cast<std::int64_t>(m_union.size());
        float* params = m_grid.params().data();
        const auto& dims = m_grid.dims();
        const std::int64_t sy = dims[0], sz = static_cast<std::int64_t>(dims[0]) * dims[1];
        // TV as a mean over voxels (Plenoxels): λ / num_voxels per unit difference.
        const float inv_n = 1.0f / static_cast<float>(m_grid.num_voxels());
        const float tv[4] = {m_options.tv_density * inv_n, m_options.tv_color * inv_n,
                             m_options.tv_color * inv_n, m_options.tv_color * inv_n};
        parallel_for(
            count,
            [&](std::int64_t u) {
                const std::int32_t v = m_union[u];
                float total[4] = {0, 0, 0, 0};
                for (GradientChunk& c : m_chunks) {
                    if (c.touched[v] != 0) {
                        float* gv = c.grad.data() + 4 * static_cast<std::int64_t>(v);
                        for (int k = 0; k < 4; ++k) {
                            total[k] += gv[k];
                            gv[k] = 0.0f;
                        }
                        c.touched[v] = 0;
                    }
                }
                const std::int64_t i = v % dims[0];
                const std::int64_t j = (v / sy) % dims[1];
                const std::int64_t k = v / sz;
                const float* x = params + 4 * static_cast<std::int64_t>(v);
                const auto neighbour = [&](std::int64_t offset) {
                    const float* xn = params + 4 * (v + offset);
                    for (int q = 0; q < 4; ++q) {
                        total[q] += tv[q] * (x[q] - xn[q]);
                    }
                };
                if (i > 0) {
                    neighbour(-1);
                }
                if (i + 1 < dims[0]) {
                    neighbour(1);
                }
                if (j > 0) {
                    neighbour(-sy);
                }
                if (j + 1 < dims[1]) {
                    neighbour(sy);
                }
                if (k > 0) {
                    neighbour(-sz);
                }
                if (k + 1 < dims[2]) {
                    neighbour(sz);
                }
                float* g0 = m_chunks[0].grad.data() + 4 * static_cast<std::int64_t>(v);
                for (int q = 0; q < 4; ++q) {
                    g0[q] = total[q];
                }
            },
            1024);

        const float decay = std::pow(m_options.lr_final_factor, static_cast<float>(p));
        const float lr[4] = {m_options.lr_density * decay, m_options.lr_color * decay,
                             m_options.lr_color * decay, m_options.lr_color * decay};
        const float t = static_cast<float>(m_stage_iteration);
        const float correction1 = 1.0f - std::pow(BETA1, t);
        const float correction2 = 1.0f - std::pow(BETA2, t);
        parallel_for(
            count,
            [&](std::int64_t u) {
                const std::int64_t v = m_union[u];
                float* g0 = m_chunks[0].grad.data() + 4 * v;
                for (int q = 0; q < 4; ++q) {
                    const std::int64_t a = 4 * v + q;
                    const float gq = g0[q];
                    m_m[a] = BETA1 * m_m[a] + (1.0f - BETA1) * gq;
                    m_v[a] = BETA2 * m_v[a] + (1.0f - BETA2) * gq * gq;
                    const float mh = m_m[a] / correction1;
                    const float vh = m_v[a] / correction2;
                    params[a] -= lr[q] * mh / (std::sqrt(vh) + EPSILON);
                    g0[q] = 0.0f;
                }
                m_mark[v] = 0;
            },
            1024);
    }

    // Adam on every texel of the environment map: the chunks' gradients summed in chunk order,
    // bias correction over all iterations (the map lives through every stage).
    void update_environment(double p) {
        const float lr =
            m_options.lr_environment * std::pow(m_options.lr_final_factor, static_cast<float>(p));
        const float t = static_cast<float>(m_iteration + 1);
        const float correction1 = 1.0f - std::pow(BETA1, t);
        const float correction2 = 1.0f - std::pow(BETA2, t);
        float* params = m_env.params().data();
        const std::size_t n = m_env.params().size();
        for (std::size_t a = 0; a < n; ++a) {
            float gq = 0.0f;
            for (GradientChunk& c : m_chunks) {
                gq += c.env_grad[a];
                c.env_grad[a] = 0.0f;
            }
            m_env_m[a] = BETA1 * m_env_m[a] + (1.0f - BETA1) * gq;
            m_env_v[a] = BETA2 * m_env_v[a] + (1.0f - BETA2) * gq * gq;
            const float mh = m_env_m[a] / correction1;
            const float vh = m_env_v[a] / correction2;
            params[a] -= lr * mh / (std::sqrt(vh) + EPSILON);
        }
    }

    // Everything a later iteration reads: the stage, iteration counts, last loss, the grid and
    // Adam's moments. The gradient chunks and marks are clear between iterations.
    void save_state(ByteWriter& out) const {
        out.put(m_stage);
        out.put(m_iteration);
        out.put(m_stage_iteration);
        out.put(m_last_loss);
        m_grid.save_state(out);
        out.put_vector(m_m);
        out.put_vector(m_v);
        if (!m_env.empty()) {
            m_env.save_state(out);
            out.put_vector(m_env_m);
            out.put_vector(m_env_v);
        }
    }
    void load_state(ByteReader& in) {
        const int stage = in.get<int>("trainer.stage");
        if (stage < 0 || stage >= m_options.stages) {
            throw InvalidInput(fmt::format("{}: trainer.stage: {}, expected 0 to {}", in.source(),
                                           stage, m_options.stages - 1));
        }
        const auto iteration = in.get<std::int64_t>("trainer.iteration");
        const auto stage_iteration = in.get<std::int64_t>("trainer.stage_iteration");
        if (iteration < 0 || stage_iteration < 0 || stage_iteration > iteration) {
            throw InvalidInput(fmt::format("{}: trainer: iteration {} and {} in its stage",
                                           in.source(), iteration, stage_iteration));
        }
        const double last_loss = in.get<double>("trainer.last_loss");
        m_grid.load_state(in, m_box, stage_resolution(stage));
        allocate();
        in.get_vector("trainer.adam_m", m_m, static_cast<std::int64_t>(m_m.size()));
        in.get_vector("trainer.adam_v", m_v, static_cast<std::int64_t>(m_v.size()));
        if (!m_env.empty()) {
            m_env.load_state(in, m_options.environment_width);
            in.get_vector("trainer.environment_adam_m", m_env_m,
                          static_cast<std::int64_t>(m_env_m.size()));
            in.get_vector("trainer.environment_adam_v", m_env_v,
                          static_cast<std::int64_t>(m_env_v.size()));
        }
        m_stage = stage;
        m_iteration = iteration;
        m_stage_iteration = stage_iteration;
        m_last_loss = last_loss;
    }

    RadianceGrid& grid() { return m_grid; }
    EnvironmentMap& environment() { return m_env; }
    std::int64_t iteration() const { return m_iteration; }
    double last_loss() const { return m_last_loss; }

private:
    const Dataset& m_dataset;
    TrainOptions m_options;
    AABBd m_box;
    float m_sigma_threshold = 0.0f;
    RadianceGrid m_grid;
    std::vector<float> m_m, m_v;
    EnvironmentMap m_env;
    std::vector<float> m_env_m, m_env_v;
    std::vector<std::uint8_t> m_mark;
    std::vector<std::int32_t> m_union;
    std::array<GradientChunk, NUM_CHUNKS> m_chunks;
    std::uint64_t m_pixels_per_view = 0;
    std::uint64_t m_num_pixels = 0;
    int m_stage = 0;
    std::int64_t m_iteration = 0;
    std::int64_t m_stage_iteration = 0;
    double m_last_loss = 0.0;
};

}  // namespace

void TrainOptions::validate() const {
    const auto fail = [](const char* name, auto value, const char* expected) {
        throw InvalidInput(
            fmt::format("nerf::TrainOptions: {} {}, expected {}", name, value, expected));
    };
    if (resolution < 4 || resolution > 1024) {
        fail("resolution", resolution, "[4, 1024]");
    }
    if (stages < 1 || stages > 6) {
        fail("stages", stages, "[1, 6]");
    }
    if (seconds < 0.0 || !std::isfinite(seconds)) {
        fail("seconds", seconds, "a finite value >= 0");
    }
    if (seconds == 0.0 && iterations < 1) {
        fail("iterations", iterations, ">= 1 (or seconds > 0)");
    }
    if (batch_rays < 1 || batch_rays > (1 << 22)) {
        fail("batch_rays", batch_rays, "[1, 4194304]");
    }
    if (!(lr_density >= 0.0f) || !(lr_color >= 0.0f)) {
        fail("lr", lr_density, ">= 0");
    }
    if (!(lr_final_factor > 0.0f && lr_final_factor <= 1.0f)) {
        fail("lr_final_factor", lr_final_factor, "(0, 1]");
    }
    if (!(tv_density >= 0.0f) || !(tv_color >= 0.0f)) {
        fail("tv", tv_density, ">= 0");
    }
    if (!std::isfinite(density_init) || !std::isfinite(color_init)) {
        fail("density_init", density_init, "finite initial values");
    }
    if (!(occupancy_alpha >= 0.0f && occupancy_alpha < 1.0f)) {
        fail("occupancy_alpha", occupancy_alpha, "[0, 1)");
    }
    if (environment_width != 0 &&
        (environment_width < 2 || environment_width > 4096 || environment_width % 2 != 0)) {
        fail("environment_width", environment_width, "0 or an even value in [2, 4096]");
    }
    if (!(sparsity >= 0.0f) || !std::isfinite(sparsity)) {
        fail("sparsity", sparsity, "a finite value >= 0");
    }
    if (!(lr_environment >= 0.0f)) {
        fail("lr_environment", lr_environment, ">= 0");
    }
    if (occupancy_interval < 1) {
        fail("occupancy_interval", occupancy_interval, ">= 1");
    }
    if (warmup_iterations < 0) {
        fail("warmup_iterations", warmup_iterations, ">= 0");
    }
    if (!(render.step_voxels > 0.0f) || !std::isfinite(render.step_voxels)) {
        fail("render.step_voxels", render.step_voxels, "> 0");
    }
    if (!(render.min_transmittance >= 0.0f && render.min_transmittance < 1.0f)) {
        fail("render.min_transmittance", render.min_transmittance, "[0, 1)");
    }
}

std::size_t estimated_training_bytes(const AABBd& box, const TrainOptions& options) {
    const std::array<int, 3> d = RadianceGrid::dims_for(box, options.resolution);
    return TRAIN_BYTES_PER_VOXEL * static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) *
           static_cast<std::size_t>(d[2]);
}

TrainResult train(const Dataset& dataset, const TrainOptions& options,
                  FunctionRef<bool(const TrainProgress&)> on_iteration,
                  const TrainCheckpoints& checkpoints) {
    options.validate();
    validate(dataset);
    const AABBd box = scene_box(dataset);
    const std::size_t bytes = estimated_training_bytes(box, options);
    if (bytes > options.max_bytes) {
        const std::array<int, 3> d = RadianceGrid::dims_for(box, options.resolution);
        throw InvalidInput(fmt::format(
            "nerf::train: resolution {} gives a {} x {} x {} grid whose training state needs "
            "about {:.0f} MiB ({} bytes per voxel), more than the memory limit of {:.0f} MiB",
            options.resolution, d[0], d[1], d[2], bytes / 1048576.0, TRAIN_BYTES_PER_VOXEL,
            options.max_bytes / 1048576.0));
    }
    Trainer trainer(dataset, options);
    const Stopwatch watch;
    double earlier_ms = 0.0;  // training time before the checkpoint resumed from
    if (!checkpoints.resume_from.empty()) {
        ByteReader in(checkpoints.resume_from, checkpoints.resume_source);
        earlier_ms = in.get<double>("trainer.elapsed_ms");
        trainer.load_state(in);
        in.expect_end();
    }
    const auto save = [&] {
        ByteWriter out;
        out.put(earlier_ms + watch.elapsed_ms());
        trainer.save_state(out);
        checkpoints.save(out.bytes(), trainer.iteration());
    };
    TrainResult result;
    for (;;) {
        const double elapsed = earlier_ms + watch.elapsed_ms();
        const double p = options.seconds > 0.0 ? elapsed / (1000.0 * options.seconds)
                                               : static_cast<double>(trainer.iteration()) /
                                                     static_cast<double>(options.iterations);
        if (p >= 1.0) {
            break;
        }
        TrainProgress progress = trainer.step(p);
        progress.elapsed_ms = earlier_ms + watch.elapsed_ms();
        progress.occupied_cells = trainer.grid().num_occupied();
        if (checkpoints.every > 0 && checkpoints.save &&
            trainer.iteration() % checkpoints.every == 0) {
            save();
        }
        if (!on_iteration(progress)) {
            result.stopped = true;
            if (checkpoints.save && checkpoints.every > 0) {
                save();
            }
            break;
        }
    }
    result.iterations = trainer.iteration();
    result.elapsed_ms = earlier_ms + watch.elapsed_ms();
    result.final_loss = trainer.last_loss();
    result.grid = std::move(trainer.grid());
    result.environment = std::move(trainer.environment());
    return result;
}

}  // namespace pliant::nerf
