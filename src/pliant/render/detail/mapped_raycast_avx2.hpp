// The batch classification of render::MappedRayCaster in AVX2: mapped_classify<true>() of up to 8
// samples of one ray at once, lane by lane the scalar kernel's IEEE operations in the same order
// without FMA (core/simd_dispatch.hpp), so images and sample counts are bitwise the scalar
// kernel's. The map's nodes and the voxels are loaded per lane (no gathers, as
// raycast_avx2.hpp); an RGBA voxel pair is 8 consecutive floats, one load, transposed; the
// gradients read the α copy. Step opacities other than the default step's (Δs/u = 1/2) go
// through the scalar libm calls lane by lane.
#pragma once

#include "pliant/render/detail/mapped_raycast_kernel.hpp"

namespace pliant::render::detail {

// Whether Avx2Batch can classify for m: an RGBA source with at least 2 voxels along x, float
// voxel indices below 2^31, the α copy when shading, and a CPU that runs AVX2.
bool mapped_avx2_fits(const MappedKernel& m);

// mapped_classify<true>(m, cells[i], dir) for i < count ≤ MAP_BATCH, bit for bit.
// Precondition: mapped_avx2_fits(m).
void mapped_classify_avx2(const MappedKernel& m, const MapCell* cells, int count, Vec3f dir,
                          Sample* out);

struct Avx2Batch {
    void operator()(const MappedKernel& m, const MapCell* cells, int count, Vec3f dir,
                    Sample* out) const {
        mapped_classify_avx2(m, cells, count, dir, out);
    }
};

}  // namespace pliant::render::detail
