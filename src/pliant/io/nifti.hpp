// NIfTI-1 through niftilib (nifti1_io.h, znzlib for .nii.gz).
//
// Read (.nii, .nii.gz, .hdr + .img): datatypes uint8, int16, uint16, float32 and RGBA32 (→ rgba8);
// others Unsupported. Up to 3 spatial dims; a 4th dim of 1 is accepted, longer series are
// Unsupported. Spacing: |diagonal| of the sform (sform_code > 0) or else the qform
// (qform_code > 0) matrix, else pixdim[1..3]; must be finite and > 0. Placement: the transform's
// translation is the centre of voxel 0; off-diagonal terms (rotation, shear, permutation) are
// Unsupported; negative diagonal terms flip that axis. Without sform and qform, voxel centres are
// at i · pixdim (origin = −pixdim / 2). scl_slope / scl_inter: when they are not the identity
// (slope 0 or 1 with inter 0), the scaled values are returned as f32 (integer data is converted;
// the limit applies to the f32 size). niftilib's own stderr messages are silenced; errors are
// ours. The data is read with znzlib straight into the Volume (one copy in memory).
//
// Write (.nii, or .nii.gz compressed): u8, i16, u16, f32, rgba8 (RGBA32); rgba32f is Unsupported.
// qform and sform (code 1, scanner) identity rotation with the voxel-0 centre as translation,
// pixdim = spacing, xyzt_units mm, scl_slope 0. Spacing and origin are stored as float.
#pragma once

#include <cstddef>
#include <filesystem>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::Volume read_nifti(const std::filesystem::path& path, std::size_t max_bytes);
void write_nifti(const std::filesystem::path& path, const volume::Volume& volume, bool gzip);

}  // namespace pliant::io
