// NIfTI-1 and NIfTI-2 through niftilib's NIfTI-2 API (nifti2_io.h, which reads both; znzlib for
// .nii.gz).
//
// Read (.nii, .nii.gz, .hdr + .img; NIfTI-1, NIfTI-2 or Analyze): datatypes uint8, int16, uint16,
// float32 and RGBA32 (→ rgba8); others Unsupported. Up to 3 spatial dims; a 4th dim of 1 is
// accepted, longer series are Unsupported. Placement: the sform (sform_code > 0), else the qform
// (qform_code > 0), else pixdim[1..3] along x, y, z from (0, 0, 0): the transform's columns are
// the steps along i, j, k (world frame RAS+, as NIfTI defines it) and its translation the centre
// of voxel 0. The volume is re-indexed to the nearest axes (volume/reorient.hpp): flips and axis
// permutations are exact and give an axis-aligned volume; an oblique grid keeps its direction. A
// sheared sform falls back to the qform (with a warning); sheared without a qform is Unsupported.
// Spacing must be finite and > 0. scl_slope / scl_inter: when they are not the identity (slope 0
// or 1 with inter 0), the scaled values are returned as f32 (integer data is converted; the limit
// applies to the f32 size). niftilib's own stderr messages are silenced; errors are ours. The
// data is read with znzlib straight into the Volume.
//
// Write (.nii, or .nii.gz compressed): NIfTI-1 (floats; dims ≤ 32767) or, with nifti2, NIfTI-2
// (doubles, 64-bit dims). u8, i16, u16, f32, rgba8 (RGBA32); rgba32f is Unsupported. qform and
// sform (code 1, scanner): the direction × spacing (identity rotation for axis-aligned volumes;
// the qform as a quaternion, qfac −1 for reflections) with the voxel-0 centre as translation,
// pixdim = spacing, xyzt_units mm, scl_slope 0.
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::Volume read_nifti(const std::filesystem::path& path, std::size_t max_bytes);
void write_nifti(const std::filesystem::path& path, const volume::Volume& volume, bool gzip,
                 bool nifti2 = false);

}  // namespace pliant::io
