// Automatic crop of a trained field to the object it shows (`nerf train --crop auto`): the scene
// box of a capture holds the object and what it stands on (a table, the floor); the exported
// volume should hold the object only.
//
// Method (density statistics on the grid's voxels; +z is up, as `nerf poses` orients datasets):
//   1. A voxel is solid when its opacity over one voxel of the grid, α = 1 − exp(−σ / resolution)
//      (σ per normalized unit, detail/field_kernel.hpp), is ≥ alpha_threshold and its cell is
//      occupied.
//   2. Support plane: n_k = solid voxels in z-slice k. When the fullest slice k* holds at least
//      plane_fraction of its slice's voxels, it is a table top or floor: the slices from k* up
//      while n_k ≥ n_k* / 2 are the plane, and the crop starts one voxel above them. Otherwise
//      the crop starts at the box's bottom.
//   3. The object: the connected components (6-neighbours) of the solid voxels above the plane
//      holding at least component_fraction of the largest one's voxels (the object's parts, not
//      the floaters a few views leave in the air); on each axis the crop spans their voxels'
//      quantiles [quantile, 1 − quantile], widened by margin (a fraction of that span) on both
//      sides (not below the plane) and clipped to the grid's box.
// No solid voxel above the plane: the grid's box. Deterministic (sequential counts).
#pragma once

#include "pliant/core/aabb.hpp"
#include "pliant/nerf/radiance_grid.hpp"

namespace pliant::nerf {

struct AutoCropOptions {
    float alpha_threshold = 20.0f / 255.0f;  // the paper's middle cleaning threshold
    float plane_fraction = 0.2f;             // of a z-slice's voxels, (0, 1]
    double component_fraction = 0.05;        // [0, 1]
    double quantile = 0.002;                 // [0, 0.5)
    double margin = 0.05;                    // ≥ 0
};

// The object's box in world units (see the header comment).
AABBd auto_crop(const RadianceGrid& grid, const AutoCropOptions& options);

}  // namespace pliant::nerf
