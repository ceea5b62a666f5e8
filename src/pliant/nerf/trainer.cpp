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
#include "pliant/nerf/camera_refinement.hpp"

namespace pliant::nerf {

namespace {

constexpr int NUM_CHUNKS = 4;
constexpr int CAMERA_PARAMS = 6;    // per view: ω (3), τ (3)
constexpr int EXPOSURE_PARAMS = 6;  // per view: gain (3), bias (3)
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
    std::vector<double> camera_grad;            // CAMERA_PARAMS per view (empty: none)
    std::vector<double> exposure_grad;          // EXPOSURE_PARAMS per view (empty: none)
    double focal_grad = 0.0;
    std::vector<double> scratch_w, scratch_g;  // scratch: one ray's weights and ∂L/∂w
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
        const std::size_t views = dataset.views.size();
        if (options.refine_poses || options.refine_focal) {
            m_camera.assign(CAMERA_PARAMS * views, 0.0f);
            m_camera_m.assign(m_camera.size(), 0.0f);
            m_camera_v.assign(m_camera.size(), 0.0f);
            for (GradientChunk& c : m_chunks) {
                c.camera_grad.assign(m_camera.size(), 0.0);
            }
        }
        if (options.exposure) {
            m_exposure.assign(EXPOSURE_PARAMS * views, 0.0f);
            m_exposure_m.assign(m_exposure.size(), 0.0f);
            m_exposure_v.assign(m_exposure.size(), 0.0f);
            for (GradientChunk& c : m_chunks) {
                c.exposure_grad.assign(m_exposure.size(), 0.0);
            }
        }
        m_scale = m_grid.scale();
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

    bool refining() const { return !m_camera.empty(); }

    // The views' cameras with the current refinement (m_poses, m_intrinsics).
    void refine_cameras() {
        const std::size_t n = m_dataset.views.size();
        m_poses.resize(n);
        m_intrinsics.resize(n);
        const double f = std::exp(static_cast<double>(m_log_focal));
        for (std::size_t i = 0; i < n; ++i) {
            const View& view = m_dataset.views[i];
            const float* c = m_camera.data() + CAMERA_PARAMS * i;
            m_poses[i] = refined_pose(view.camera_to_world, Vec3d{c[0], c[1], c[2]},
                                      m_scale * Vec3d{c[3], c[4], c[5]});
            m_intrinsics[i] = intrinsics_of(m_dataset, view);
            m_intrinsics[i].fx *= f;
            m_intrinsics[i].fy *= f;
        }
    }

    // The refined poses and focal scale (refining() only).
    std::vector<Pose> refined_poses() {
        refine_cameras();
        return m_poses;
    }
    double focal_scale() const { return std::exp(static_cast<double>(m_log_focal)); }
    std::vector<ViewExposure> exposures() const {
        std::vector<ViewExposure> out(m_exposure.size() / EXPOSURE_PARAMS);
        for (std::size_t i = 0; i < out.size(); ++i) {
            for (int k = 0; k < 3; ++k) {
                out[i].gain[k] = m_exposure[EXPOSURE_PARAMS * i + k];
                out[i].bias[k] = m_exposure[EXPOSURE_PARAMS * i + 3 + k];
            }
        }
        return out;
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
        const float distortion = m_options.distortion;
        const float distortion_norm = distortion / static_cast<float>(batch);
        const double norm = 1.0 / (3.0 * batch);
        const Intrinsics& in = m_dataset.intrinsics;
        const std::uint64_t base = static_cast<std::uint64_t>(m_iteration) * batch;
        const bool refine = refining() && p >= m_options.refine_start;
        if (refining()) {
            refine_cameras();
        }
        const bool exposure = m_options.exposure;
        parallel_for_chunks(
            batch, grain, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                GradientChunk& chunk = m_chunks[static_cast<std::size_t>(c)];
                chunk.loss = 0.0;
                chunk.num_samples = 0;
                for (std::int64_t r = begin; r < end; ++r) {
                    const std::uint64_t h =
                        splitmix64(m_options.seed * 0x632be59bd9b4e019ULL + base + r);
                    const std::uint64_t pixel = h % m_num_pixels;
                    const std::size_t vi = pixel / m_pixels_per_view;
                    const View& view = m_dataset.views[vi];
                    const std::uint64_t local = pixel % m_pixels_per_view;
                    const int x = static_cast<int>(local % in.width);
                    const int y = static_cast<int>(local / in.width);
                    if (!view.mask.empty() && view.mask[local] == 0) {
                        continue;  // an ignored pixel: no loss, no gradient
                    }
                    const NormalizedRay ray =
                        refining() ? normalize_ray(m_grid, view_ray(m_intrinsics[vi], m_poses[vi],
                                                                    x + 0.5, y + 0.5))
                                   : normalize_ray(
                                         m_grid, view_ray(intrinsics_of(m_dataset, view),
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
                    if (exposure) {
                        // Compared colour (1 + gain) ⊙ C + bias.
                        const float* xp = m_exposure.data() + EXPOSURE_PARAMS * vi;
                        double* xg = chunk.exposure_grad.data() + EXPOSURE_PARAMS * vi;
                        for (int k = 0; k < 3; ++k) {
                            const double gain = 1.0 + static_cast<double>(xp[k]);
                            const double e =
                                gain * out.rgb[k] + xp[3 + k] - static_cast<double>(target[k]);
                            chunk.loss += e * e * norm;
                            const double de = 2.0 * e * norm;
                            xg[k] += de * out.rgb[k];
                            xg[3 + k] += de;
                            gc[k] = static_cast<float>(de * gain);
                        }
                    } else {
                        for (int k = 0; k < 3; ++k) {
                            const double e = static_cast<double>(out.rgb[k]) - target[k];
                            chunk.loss += e * e * norm;
                            gc[k] = static_cast<float>(2.0 * e * norm);
                        }
                    }
                    float go[3] = {0, 0, 0}, gd[3] = {0, 0, 0};
                    detail::backward(
                        g, chunk.samples.data(), static_cast<int>(chunk.samples.size()), out.rgb,
                        gc, [&](std::int32_t v, const float d[4]) { chunk.add(v, d); },
                        [&](const detail::SampleRecord& rec, const float d[4]) {
                            if (refine) {
                                float pg[3];
                                detail::position_gradient(g, rec.corner, d, pg);
                                for (int k = 0; k < 3; ++k) {
                                    go[k] += pg[k];
                                    gd[k] += rec.t * pg[k];
                                }
                            }
                        });
                    if (refine) {
                        accumulate_camera(chunk, vi, ray, go, gd);
                    }
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
                    if (distortion > 0.0f) {
                        add_distortion_gradient(g, chunk, distortion_norm);
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
        if (refine) {
            update_camera(p);
        }
        if (exposure) {
            update_exposure(p);
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

    // The distortion loss's gradient for the ray whose samples are in chunk.samples (in order):
    // with W_<i, M_<i the prefix sums of w_j and w_j m_j (and W_>i, M_>i the suffix sums),
    //   g_i = ∂L/∂w_i = 2 (m_i W_<i − M_<i + M_>i − m_i W_>i) + ⅔ w_i δ_i,
    // then through w_i = T_i α_i as the colour is (field_kernel.hpp's backward with the scalar
    // "colour" g_i, no background): ∂L/∂σ_k = δ_k (T_{k+1} g_k − Σ_{j>k} w_j g_j).
    void add_distortion_gradient(const detail::GridView& g, GradientChunk& chunk,
                                 float weight) const {
        const std::vector<detail::SampleRecord>& rec = chunk.samples;
        const std::size_t n = rec.size();
        if (n < 2) {
            return;
        }
        std::vector<double>& w = chunk.scratch_w;
        std::vector<double>& gw = chunk.scratch_g;
        w.resize(n);
        gw.resize(n);
        double T = 1.0, total_w = 0.0, total_wm = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            w[i] = T * rec[i].alpha;
            T *= 1.0 - rec[i].alpha;
            total_w += w[i];
            total_wm += w[i] * rec[i].t;
        }
        double below_w = 0.0, below_wm = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const double m = rec[i].t;
            const double above_w = total_w - below_w - w[i];
            const double above_wm = total_wm - below_wm - w[i] * m;
            gw[i] = 2.0 * (m * below_w - below_wm + above_wm - m * above_w) +
                    (2.0 / 3.0) * w[i] * rec[i].length;
            below_w += w[i];
            below_wm += w[i] * m;
        }
        double suffix = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            suffix += w[i] * gw[i];
        }
        std::int32_t o[8];
        detail::corner_offsets(g, o);
        T = 1.0;
        for (std::size_t k = 0; k < n; ++k) {
            const detail::SampleRecord& r = rec[k];
            suffix -= w[k] * gw[k];
            const double t_next = T * (1.0 - r.alpha);
            const double d_sigma = r.length * (t_next * gw[k] - suffix);
            const auto d_s =
                static_cast<float>(weight * d_sigma * detail::DENSITY_SCALE * detail::sigmoid(r.s));
            float wt[8];
            detail::corner_weights(r.corner, wt);
            for (int q = 0; q < 8; ++q) {
                const float dq[4] = {wt[q] * d_s, 0.0f, 0.0f, 0.0f};
                chunk.add(r.corner.base + o[q], dq);
            }
            T = t_next;
        }
    }

    // ∂L/∂(ω, τ) of view vi and ∂L/∂φ from ∂L/∂o and ∂L/∂d of one ray (unit direction d):
    //   τ: ∂L/∂o (normalized units);  ω: d × ∂L/∂d (the direction turns as δd = δω × d);
    //   φ: the camera-frame direction D = d / (−d · z) (z the camera's unit back axis, so D's
    //      component along −z is 1) changes with the focal scale as ∂D/∂φ = −(D + z), and
    //      ∂L/∂D = (g_d − (g_d · d) d) / |D|.
    void accumulate_camera(GradientChunk& chunk, std::size_t vi, const NormalizedRay& ray,
                           const float go[3], const float gd[3]) const {
        const Vec3d d{ray.direction[0], ray.direction[1], ray.direction[2]};
        const Vec3d g_d{gd[0], gd[1], gd[2]};
        double* cg = chunk.camera_grad.data() + CAMERA_PARAMS * vi;
        if (m_options.refine_poses) {
            const Vec3d w = cross(d, g_d);
            cg[0] += w.x;
            cg[1] += w.y;
            cg[2] += w.z;
            cg[3] += go[0];
            cg[4] += go[1];
            cg[5] += go[2];
        }
        if (m_options.refine_focal) {
            const Vec3d axis_z = m_poses[vi].axis(2);
            const Vec3d z = axis_z / norm(axis_z);
            const double along = -dot(d, z);
            if (along > 1e-6) {
                const Vec3d big_d = d / along;
                const Vec3d g_perp = g_d - dot(g_d, d) * d;
                chunk.focal_grad -= dot(g_perp, big_d + z) / norm(big_d);
            }
        }
    }

    // Adam on the camera deltas (chunks summed in chunk order; bias correction over the
    // refinement's iterations).
    void update_camera(double p) {
        ++m_camera_iteration;
        const float decay = std::pow(m_options.lr_final_factor, static_cast<float>(p));
        const float t = static_cast<float>(m_camera_iteration);
        const float correction1 = 1.0f - std::pow(BETA1, t);
        const float correction2 = 1.0f - std::pow(BETA2, t);
        const auto adam = [&](float& x, float& m, float& v, float gq, float lr) {
            m = BETA1 * m + (1.0f - BETA1) * gq;
            v = BETA2 * v + (1.0f - BETA2) * gq * gq;
            x -= lr * (m / correction1) / (std::sqrt(v / correction2) + 1e-12f);
        };
        if (m_options.refine_poses) {
            const float lr = m_options.lr_pose * decay;
            for (std::size_t a = 0; a < m_camera.size(); ++a) {
                double gq = 0.0;
                for (GradientChunk& c : m_chunks) {
                    gq += c.camera_grad[a];
                    c.camera_grad[a] = 0.0;
                }
                adam(m_camera[a], m_camera_m[a], m_camera_v[a], static_cast<float>(gq), lr);
            }
        }
        if (m_options.refine_focal) {
            double gq = 0.0;
            for (GradientChunk& c : m_chunks) {
                gq += c.focal_grad;
                c.focal_grad = 0.0;
            }
            adam(m_log_focal, m_focal_m, m_focal_v, static_cast<float>(gq),
                 m_options.lr_focal * decay);
        }
    }

    // Adam on the exposures, with the prior's gradient 2 λ x (bias correction over all
    // iterations), then the mean over the views subtracted.
    void update_exposure(double p) {
        const float lr =
            m_options.lr_exposure * std::pow(m_options.lr_final_factor, static_cast<float>(p));
        const float t = static_cast<float>(m_iteration + 1);
        const float correction1 = 1.0f - std::pow(BETA1, t);
        const float correction2 = 1.0f - std::pow(BETA2, t);
        const float prior = 2.0f * m_options.exposure_prior;
        for (std::size_t a = 0; a < m_exposure.size(); ++a) {
            double gq = 0.0;
            for (GradientChunk& c : m_chunks) {
                gq += c.exposure_grad[a];
                c.exposure_grad[a] = 0.0;
            }
            const float g = static_cast<float>(gq) + prior * m_exposure[a];
            m_exposure_m[a] = BETA1 * m_exposure_m[a] + (1.0f - BETA1) * g;
            m_exposure_v[a] = BETA2 * m_exposure_v[a] + (1.0f - BETA2) * g * g;
            m_exposure[a] -= lr * (m_exposure_m[a] / correction1) /
                             (std::sqrt(m_exposure_v[a] / correction2) + 1e-12f);
        }
        // The gauge: a gain shared by all views trades against the field's colours, so the
        // parameters are kept at zero mean over the views (the held-out views' identity is
        // then the training views' mean exposure).
        const std::size_t views = m_exposure.size() / EXPOSURE_PARAMS;
        for (int k = 0; k < EXPOSURE_PARAMS; ++k) {
            double mean = 0.0;
            for (std::size_t i = 0; i < views; ++i) {
                mean += m_exposure[EXPOSURE_PARAMS * i + k];
            }
            mean /= static_cast<double>(views);
            for (std::size_t i = 0; i < views; ++i) {
                m_exposure[EXPOSURE_PARAMS * i + k] -= static_cast<float>(mean);
            }
        }
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
        if (refining()) {
            out.put(m_camera_iteration);
            out.put_vector(m_camera);
            out.put_vector(m_camera_m);
            out.put_vector(m_camera_v);
            out.put(m_log_focal);
            out.put(m_focal_m);
            out.put(m_focal_v);
        }
        if (m_options.exposure) {
            out.put_vector(m_exposure);
            out.put_vector(m_exposure_m);
            out.put_vector(m_exposure_v);
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
        if (refining()) {
            m_camera_iteration = in.get<std::int64_t>("trainer.camera_iteration");
            const auto n = static_cast<std::int64_t>(m_camera.size());
            in.get_vector("trainer.camera", m_camera, n);
            in.get_vector("trainer.camera_adam_m", m_camera_m, n);
            in.get_vector("trainer.camera_adam_v", m_camera_v, n);
            m_log_focal = in.get<float>("trainer.log_focal");
            m_focal_m = in.get<float>("trainer.focal_adam_m");
            m_focal_v = in.get<float>("trainer.focal_adam_v");
        }
        if (m_options.exposure) {
            const auto n = static_cast<std::int64_t>(m_exposure.size());
            in.get_vector("trainer.exposure", m_exposure, n);
            in.get_vector("trainer.exposure_adam_m", m_exposure_m, n);
            in.get_vector("trainer.exposure_adam_v", m_exposure_v, n);
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
    double m_scale = 1.0;  // the box's largest side: world units per normalized unit
    std::vector<float> m_camera, m_camera_m, m_camera_v;  // CAMERA_PARAMS per view
    float m_log_focal = 0.0f, m_focal_m = 0.0f, m_focal_v = 0.0f;
    std::int64_t m_camera_iteration = 0;
    std::vector<Pose> m_poses;             // the refined cameras of this iteration
    std::vector<Intrinsics> m_intrinsics;  // …
    std::vector<float> m_exposure, m_exposure_m, m_exposure_v;  // EXPOSURE_PARAMS per view
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
    if (!(distortion >= 0.0f) || !std::isfinite(distortion)) {
        fail("distortion", distortion, "a finite value >= 0");
    }
    if (!(lr_exposure >= 0.0f) || !(exposure_prior >= 0.0f) || !std::isfinite(exposure_prior)) {
        fail("lr_exposure / exposure_prior", lr_exposure, "finite values >= 0");
    }
    if (!(lr_pose >= 0.0f) || !(lr_focal >= 0.0f)) {
        fail("lr_pose / lr_focal", lr_pose, ">= 0");
    }
    if (!(refine_start >= 0.0 && refine_start <= 1.0)) {
        fail("refine_start", refine_start, "[0, 1]");
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
    result.exposure = trainer.exposures();
    if (options.refine_poses || options.refine_focal) {
        result.poses = trainer.refined_poses();
        result.focal_scale = trainer.focal_scale();
    }
    return result;
}

}  // namespace pliant::nerf
