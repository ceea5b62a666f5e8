// Training a voxel radiance field (radiance_grid.hpp) on a posed-image dataset: the Plenoxels /
// DVGO recipe on the CPU, without an MLP.
//
//   - Loss: mean squared error of batches of pixel-centre rays (photometric_loss's definition) +
//     total variation on the voxels the batch touched (sparse TV, as Plenoxels evaluates it on a
//     subset) as a mean over the grid's voxels: ∂TV/∂x_v = (λ / num_voxels) Σ_{n ∈ 6-neighbours
//     of v} (x_v − x_n), λ = tv_density on s and tv_color on the colour parameters.
//   - Optimizer: Adam (Kingma & Ba 2015; β1 0.9, β2 0.99, ε 1e-15) with per-parameter moments,
//     updating only the voxels the batch touched (lazy Adam: untouched voxels keep their
//     parameters and moments; bias correction uses the stage's iteration count). Learning rate
//     lr · lr_final_factor^p, p ∈ [0, 1] the training progress.
//   - Coarse to fine: `stages` grids of resolution R / 2^(stages − 1 − s); stage s starts at
//     progress 0.3 · s / (stages − 1); each new grid is the previous one resampled trilinearly
//     (raw parameters), its Adam moments start at zero.
//   - Empty-space skipping: an occupancy grid (RadianceGrid::update_occupancy) at threshold
//     σ_min = −ln(1 − occupancy_alpha) · DENSITY_SCALE (opacity occupancy_alpha over 1/256 of the
//     box's largest side), refreshed every occupancy_interval iterations and at every new stage;
//     all cells are occupied during the first warmup_iterations (densities still rise from their
//     initial value: pruning then would freeze the scene empty).
//   - Batches: batch_rays pixels drawn uniformly over all pixels of all views by a counter-based
//     hash of (seed, iteration, ray index): the same rays for any number of threads.
//   - Background: the dataset's constant colour, or a learned environment map over ray
//     directions (TrainOptions::environment_width; environment_map.hpp) composited behind the
//     box's transmittance; its gradient is gathered per chunk like the grid's.
//   - Determinism: rays are cut into 4 fixed chunks; each chunk scatters gradients into its own
//     dense buffer and records the voxels it touched; the buffers are summed per voxel in chunk
//     order. Results are bitwise identical for 1 and N threads (with a fixed iteration count;
//     a time budget makes the schedule depend on the machine's speed).
//
// Memory: per voxel 16 bytes of parameters, 32 of Adam moments, 4 · 21 of chunk gradients, flags
// and touched lists (at most), 2 of occupancy and marks: at most TRAIN_BYTES_PER_VOXEL = 134
// bytes (128³: 268 MiB, 256³: 2.1 GiB), plus the images. train() refuses, before allocating, a
// final grid that would need more than TrainOptions::max_bytes.
// Progress: on_iteration is called after every iteration; returning false stops training (the
// grid so far is returned). The kernels never print.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "pliant/core/function_ref.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/nerf/environment_map.hpp"
#include "pliant/nerf/radiance_grid.hpp"
#include "pliant/nerf/render.hpp"

namespace pliant::nerf {

struct TrainOptions {
    int resolution = 128;  // voxels along the box's longest side at the last stage, [4, 1024]
    int stages = 3;        // coarse-to-fine stages, [1, 6]; each halves the resolution
    std::int64_t iterations = 2000;  // iterations when seconds == 0
    double seconds = 0.0;            // > 0: a wall-clock budget instead of an iteration count
    int batch_rays = 4096;           // rays per iteration, [1, 1 << 22]
    float lr_density = 0.1f;         // Adam learning rate of the raw density s
    float lr_color = 0.1f;           // … of the raw colour
    float lr_final_factor = 0.1f;    // the learning rate decays to this fraction, (0, 1]
    float tv_density = 0.0f;         // TV weight on s (≥ 0)
    float tv_color = 0.0f;           // TV weight on the colour parameters (≥ 0)
    float density_init = -10.0f;     // raw density of every voxel at start (nearly transparent)
    float color_init = 0.0f;         // raw colour at start (sigmoid 0 = grey 0.5)
    float occupancy_alpha = 1e-4f;   // see the header comment, [0, 1)
    int occupancy_interval = 16;     // iterations between occupancy refreshes (≥ 1)
    int warmup_iterations = 128;     // iterations (over all stages) before the first refresh
    FieldRenderOptions render;       // step and early termination while training
    // Background of rays leaving the box: 0 the dataset's constant colour; > 0 a learned
    // EnvironmentMap (environment_map.hpp) this many texels around (even, [2, 4096]), raw values
    // starting at color_init, Adam at lr_environment (decaying as the others; dense over the
    // texels, bias correction over all iterations).
    int environment_width = 0;
    float lr_environment = 0.1f;
    // Weight λ of a sparsity prior on density (Plenoxels' Cauchy loss on real scenes): the loss
    // gains (λ / batch_rays) Σ_samples log(1 + 2 τ²), τ = σ δ the sample's optical thickness,
    // pushing the air between the cameras and the object empty (≥ 0; 0: off).
    float sparsity = 0.0f;
    // Weight λ of Mip-NeRF 360's distortion loss (Barron et al. 2022, eq. 15) per ray, against
    // floaters: (λ / batch_rays) Σ_rays [Σ_i Σ_j w_i w_j |m_i − m_j| + ⅓ Σ_i w_i² δ_i], w_i the
    // samples' compositing weights, m_i their midpoints and δ_i their lengths (normalized
    // units); it pulls each ray's weight into one compact interval (≥ 0; 0: off).
    float distortion = 0.0f;
    // Per-view exposure compensation (photos whose exposure or white balance differ): the
    // rendered colour C of training view i is compared as (1 + g_i) ⊙ C + b_i (per channel; 6
    // parameters per view, zero at start, Adam at lr_exposure decaying as the others), and the
    // loss gains exposure_prior · Σ_i (|g_i|² + |b_i|²), which pulls toward the identity; after
    // each step the mean over the views is subtracted from each parameter (a gain shared by all
    // views is the field's colour, not an exposure). Held-out views are scored with the
    // identity, which is the views' mean exposure.
    bool exposure = false;
    float lr_exposure = 1e-2f;
    float exposure_prior = 1e-4f;
    // Camera refinement while training (nerfstudio's camera optimizer): per training view a
    // rotation ω (so(3), radians, about the view's eye, applied on the left: R' = exp(ω) R) and a
    // translation τ of the eye (normalized units of the scene box, world axes), zero at start;
    // with refine_focal one log-scale of the focal lengths shared by all views (fx' = fx e^φ).
    // Gradients through the ray's origin and direction (∂L/∂u of the trilinear field at each
    // sample, u = o + t d; the clipped chord and the background's dependence on the direction are
    // held fixed). Adam at lr_pose / lr_focal, decaying as the others, from progress
    // refine_start on (the field takes shape first).
    bool refine_poses = false;
    bool refine_focal = false;
    float lr_pose = 1e-3f;
    float lr_focal = 2e-4f;
    double refine_start = 0.1;
    std::uint64_t seed = 1;
    std::size_t max_bytes = std::size_t{16} << 30;  // memory limit of the final grid (bytes)

    // InvalidInput naming the option and its value when one is out of range.
    void validate() const;
};

struct TrainProgress {
    std::int64_t iteration = 0;  // iterations done
    double progress = 0.0;       // p ∈ [0, 1]
    double loss = 0.0;           // this batch's mean squared error (no TV)
    double psnr = 0.0;           // −10 log10(loss), dB
    int resolution = 0;          // the current stage's grid
    std::int64_t occupied_cells = 0;
    std::int64_t samples = 0;  // samples evaluated in this batch
    double elapsed_ms = 0.0;
};

// A training view's learned exposure: compared colour = (1 + gain) ⊙ C + bias.
struct ViewExposure {
    std::array<float, 3> gain{0, 0, 0};
    std::array<float, 3> bias{0, 0, 0};
};

struct TrainResult {
    RadianceGrid grid;
    EnvironmentMap environment;          // empty unless TrainOptions::environment_width > 0
    std::vector<ViewExposure> exposure;  // per training view; empty unless TrainOptions::exposure
    // The training views' refined camera-to-world poses (refine_poses; empty otherwise) and the
    // focal lengths' refined scale e^φ (1 without refine_focal).
    std::vector<Pose> poses;
    double focal_scale = 1.0;
    std::int64_t iterations = 0;
    double elapsed_ms = 0.0;
    double final_loss = 0.0;  // the last batch's MSE
    bool stopped = false;     // on_iteration returned false
};

inline constexpr std::size_t TRAIN_BYTES_PER_VOXEL = 134;

// The training state's bytes at the final resolution over `box` (TRAIN_BYTES_PER_VOXEL per
// voxel of RadianceGrid::dims_for(box, options.resolution)).
std::size_t estimated_training_bytes(const AABBd& box, const TrainOptions& options);

// Checkpoints of a training run: every `every` iterations (and when on_iteration stops it),
// save(state, iteration) gets the trainer's whole state (the stage, iteration counts, grid, the
// environment map, Adam's moments and the training time so far; core/bytes.hpp layout). With
// resume_from non-empty (such a state; resume_source names it in errors), training continues from
// it: the rays of iteration i depend only on the seed and i, so with an iteration count (not
// `seconds`) and the same thread count the final grid is bitwise identical to an uninterrupted
// run's.
struct TrainCheckpoints {
    std::int64_t every = 0;  // 0: no checkpoints
    std::function<void(std::span<const std::byte> state, std::int64_t iteration)> save;
    std::span<const std::byte> resume_from;
    std::string resume_source;
};

// Trains a field on `dataset` (validated first; its scene box from nerf::scene_box). InvalidInput
// when the final grid would need more than options.max_bytes, or for a resume_from state that
// is truncated or of another grid.
TrainResult train(const Dataset& dataset, const TrainOptions& options,
                  FunctionRef<bool(const TrainProgress&)> on_iteration,
                  const TrainCheckpoints& checkpoints = {});

}  // namespace pliant::nerf
