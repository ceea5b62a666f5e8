// Oriented volumes: placing a file's grid in the world, and resampling an oriented volume onto an
// axis-aligned grid.
//
// A file states where its grid lies as the world position of voxel (0, 0, 0)'s centre and the
// world step from one voxel to the next along i, j and k (NIfTI qform/sform columns, NRRD
// `space directions`, DICOM ImageOrientationPatient × PixelSpacing and the slice step, MetaImage
// TransformMatrix × ElementSpacing). place_nearest_axes re-indexes the voxels (flips and axis
// swaps: exact, no interpolation) so that grid axis a is the one nearest to world axis a; the
// volume is then axis-aligned (direction exactly the identity) unless the grid is truly oblique
// (an axis more than ~1e-6 rad from every world axis), and then its direction is kept.
//
// resample_to_axis_aligned turns an oriented volume into an axis-aligned one covering it:
// trilinear interpolation, for the kernels that work in the grid's frame (tet grids, deformed-mesh
// resampling; the ray caster renders oriented volumes as they lie, or these on request).
#pragma once

#include <array>
#include <cstddef>

#include "pliant/core/vec3.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

struct GridPlacement {
    Vec3d centre0{0.0, 0.0, 0.0};  // world position of voxel (0, 0, 0)'s centre
    // World step between neighbouring voxels along i, j, k: direction × spacing (world units).
    std::array<Vec3d, 3> steps{Vec3d{1.0, 0.0, 0.0}, Vec3d{0.0, 1.0, 0.0}, Vec3d{0.0, 0.0, 1.0}};
    // The steps' exact lengths when the file states them apart from the steps (NIfTI pixdim
    // beside a float sform, DICOM PixelSpacing, MetaImage ElementSpacing); 0: |steps[a]|. Used
    // for oblique grids, whose |steps[a]| carries the rounding of the direction.
    std::array<double, 3> lengths{0.0, 0.0, 0.0};
};

// Largest |cosine| between two grid axes that place_nearest_axes treats as orthogonal (and then
// makes exactly orthonormal): the rest is rounding in files, e.g. DICOM's cosines written with
// six decimals. Larger is a sheared grid.
inline constexpr double MAX_AXIS_COSINE = 1e-3;

// The largest |cosine| between two of the steps (0 for an orthogonal grid); NaN when a step is
// zero or not finite.
double max_axis_cosine(const GridPlacement& placement);

// Re-indexes `volume` (its voxels in the file's order; its spacing, origin and direction are
// ignored) so that each grid axis is the one nearest to +x, +y, +z, and sets spacing, origin and
// direction from `placement`. When every axis is within 1e-6 of a world axis, the direction is
// exactly the identity and spacing[a] = |steps[a][a]| after re-indexing (so axis-aligned files
// read bit for bit as they always did); else spacing[a] = lengths[a] (when > 0) or |steps[a]|,
// and the direction is the nearest orthonormal matrix to the normalized steps. World positions of
// the voxels are kept. InvalidInput when a step is zero or not finite, or the grid is sheared
// (max_axis_cosine > MAX_AXIS_COSINE). Flips are done in place; swapping axes needs memory for a
// second copy of the voxels.
Volume place_nearest_axes(Volume volume, const GridPlacement& placement);

struct AxisAlignedOptions {
    // Spacing of the new grid, world units; 0 on every axis: the smallest spacing of the source,
    // on every axis (isotropic).
    Vec3d spacing{0.0, 0.0, 0.0};
    // Value of the voxels outside the source's box (every channel of RGBA voxels).
    double outside = 0.0;
    // Refuse (InvalidInput) a result larger than this many bytes, before allocating.
    std::size_t max_bytes = Volume::MAX_BYTES;
};

// An axis-aligned volume of the same voxel type covering the oriented source: its box is the
// smallest world box holding the source's turned box (Volume::world_bounds), grown symmetrically
// to a whole number of voxels. Each voxel centre takes the trilinear interpolation of the source
// at that world point (voxel centres of the source are its samples; within half a voxel of the
// source box's faces the nearest samples are extended; outside the box: options.outside).
// Integer types are rounded to nearest and clamped to their range. Sample positions within 1e-6
// voxel of a source voxel centre take that voxel exactly, so a rotation by a multiple of 90°
// resamples to the exact permutation. An axis-aligned source is returned unchanged (a copy) when
// options.spacing is 0. Runs over slices in parallel (core/parallel.hpp); bitwise identical for
// any thread count.
Volume resample_to_axis_aligned(const Volume& source, const AxisAlignedOptions& options = {});

}  // namespace pliant::volume
