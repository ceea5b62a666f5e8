// Visibility of voxels: which voxels can contribute to an image. The tet grid keeps only cells
// near visible voxels and the resampler skips tets whose source region holds none.
#pragma once

#include <cstdint>
#include <vector>

#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

// One byte per voxel (index order of Volume::index), 1 when the voxel is visible:
//   RGBA volumes: alpha > 0 (tf ignored);
//   scalar volumes with tf: tf.evaluate(value) has opacity > 0;
//   scalar volumes without tf: value ≠ 0.
// NaN is never visible. Validates tf. Parallel, deterministic.
std::vector<std::uint8_t> visible_voxels(const Volume& volume,
                                         const TransferFunction* tf = nullptr);

}  // namespace pliant::volume
