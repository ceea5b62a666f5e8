// Rendering the voxel radiance field (detail/field_kernel.hpp) from dataset cameras, and the
// photometric loss with its analytic gradient (used by the tests; the trainer runs the same
// kernels on batches with per-chunk gradient buffers).
#pragma once

#include <span>
#include <vector>

#include "pliant/nerf/dataset.hpp"
#include "pliant/nerf/environment_map.hpp"
#include "pliant/nerf/radiance_grid.hpp"

namespace pliant::nerf {

struct FieldRenderOptions {
    // Sampling step δ in voxels of the grid's longest side (> 0): 0.5 = two samples per voxel.
    float step_voxels = 0.5f;
    // A ray stops after the sample at which its transmittance falls below this ([0, 1)).
    float min_transmittance = 1e-4f;
    bool use_occupancy = true;  // skip unoccupied cells
};

// A ray in the grid's normalized coordinates (origin, unit direction).
struct NormalizedRay {
    float origin[3];
    float direction[3];
};
NormalizedRay normalize_ray(const RadianceGrid& grid, const render::Ray& world_ray);

// The view's image from the field, 3 · width · height floats (row-major from the top-left),
// pixel-centre rays (nerf::view_ray). Parallel over rows; bitwise identical for any thread count.
std::vector<float> render_view(const RadianceGrid& grid, const Intrinsics& intrinsics,
                               const Pose& pose, render::Color background,
                               const FieldRenderOptions& options = {});
// The same over a learned background: each ray ends on environment's colour in its direction
// (environment_map.hpp); an empty map means `background`.
std::vector<float> render_view(const RadianceGrid& grid, const EnvironmentMap& environment,
                               const Intrinsics& intrinsics, const Pose& pose,
                               render::Color background, const FieldRenderOptions& options = {});

// L = (1 / (3 n)) Σ_rays Σ_channels (C − target)² over n rays (targets: 3 per ray), computed
// sequentially; ∂L/∂params is ADDED to grad (4 · num_voxels floats). Returns L. InvalidInput
// when the sizes disagree.
double photometric_loss(const RadianceGrid& grid, std::span<const NormalizedRay> rays,
                        std::span<const float> targets, render::Color background,
                        const FieldRenderOptions& options, std::span<float> grad);

}  // namespace pliant::nerf
