// Export of a radiance field as an RGBA volume for the volume pipeline (clean → tet grid → PBD →
// resampling → ray casting).
//
// The volume covers the grid's box with `resolution` voxels along its longest side (dims_a =
// max(1, round(resolution · extent_a / largest extent)), spacing_a = extent_a / dims_a, origin =
// box.lo). At each voxel centre the field is evaluated as in training (trilinear raw parameters,
// then activation): σ (per world unit) = softplus(s) · DENSITY_SCALE / scale, and
//   α_u = 1 − exp(−σ u),  u = the smallest spacing of the exported volume,
// the opacity per opacity unit u that render::raycast assumes by default (opacity per unit
// distance, volume/transfer_function.hpp), so that a ray of length L through a uniform region
// absorbs 1 − exp(−σ L) in both renderers. Colour: sigmoid of the raw colour, straight. Cells the
// occupancy grid skips export α = 0 (the trained model renders them as empty). rgba8 stores
// round(255 x); rgba32f the floats. Parallel over z; bitwise identical for any thread count.
//
// volume::clean (threshold 5/20/35, alpha normalization) is applied by the caller afterwards.
#pragma once

#include <optional>

#include "pliant/nerf/radiance_grid.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::nerf {

struct ExportOptions {
    int resolution = 256;                               // voxels along the longest side, [1, 2048]
    volume::VoxelType type = volume::VoxelType::rgba8;  // rgba8 or rgba32f
    std::size_t max_bytes = volume::Volume::MAX_BYTES;  // memory limit of the exported volume
    // The exported region (world units, the dataset's frame; e.g. nerf::auto_crop's): the volume
    // covers it as described above for the grid's box; voxels outside the grid's box are empty
    // (α = 0). none: the grid's box.
    std::optional<AABBd> box;
};

// The exported volume's dims over `box` (see above) and its voxel bytes; for checking a run's
// output before training. Precondition: a valid box and resolution.
volume::Dims export_dims(const AABBd& box, int resolution);
std::size_t export_bytes(const AABBd& box, const ExportOptions& options);

// InvalidInput for a resolution out of range, a scalar voxel type, an empty or non-finite
// options.box, or a volume larger than options.max_bytes.
volume::Volume export_volume(const RadianceGrid& grid, const ExportOptions& options = {});

}  // namespace pliant::nerf
