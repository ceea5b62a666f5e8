// AVX2 kernels of the resampler (volume/resample.hpp), compiled for AVX2 with a function
// attribute and chosen at run time (pliant::has_avx2(), core/simd_dispatch.hpp). Each lane does the
// IEEE operations of the scalar kernels of detail/resample_kernel.hpp in the same order, without
// FMA contraction: the results are bitwise those of the scalar kernels, so the choice never changes
// an output.
#pragma once

#include <cstdint>

#include "pliant/volume/detail/resample_kernel.hpp"

namespace pliant::volume::detail {

// setup_tet() of 4 tets at once: tet l has vertex indices ids[l] into the deformed and rest
// positions, and rest information rest[l]. out[l] gets what setup_tet(p, ids[l], r, rest[l],
// target, source, out[l]) writes for p[v] = deformed[ids[l][v]], r[v] = rest_positions[ids[l][v]],
// bit for bit (out[l].lo/hi always; the rest when bit l of the result is set, i.e. when setup_tet
// returns true).
int setup_tets_avx2(const Vec3f* deformed, const Vec3f* rest_positions,
                    const std::int32_t ids[4][4], const RestInfo rest[4], const GridFrame& target,
                    const GridFrame& source, TetRaster out[4]);

// Whether append_layers_avx2() takes the tet: is_fast, at most 8 voxels wide and 16 rows high
// (so that the rows of 4 layers fit into an empty batch).
inline bool avx2_layers_fit(const TetRaster& t) {
    return t.is_fast && t.hi[0] - t.lo[0] < 8 && t.hi[1] - t.lo[1] < 16;
}

// append_spans() for a tet with avx2_layers_fit(), 4 rows at a time (rows of up to 4 layers
// share a vector), the same voxels in the same order with the same coordinates, without a
// flush: appends layers [k, k_end) (clipped to the tet's box) while the batch has room for 4
// whole layers and returns the first layer it did not append (k_end when done: else the caller
// flushes the batch and calls again from there). Adds the number of voxels appended to num_voxels.
std::int64_t append_layers_avx2(const TetRaster& t, std::int64_t k, std::int64_t k_end,
                                std::int64_t nx, std::int64_t nxy, SpanBatch& batch,
                                std::int64_t& num_voxels);

// Samples the first batch.num_voxels − batch.num_voxels mod 4 voxels of the batch from an f32
// source (dims n, n[0]·n[1]·n[2] < 2^31) into the f32 target dst: dst[index] =
// sample_trilinear<float, 1>(g) · scale, bit for bit. Returns the number sampled (the caller
// samples the rest).
int sample_f32_avx2(const float* src, const std::int64_t n[3], const SpanBatch& batch, float scale,
                    float* dst);

// The same for an rgba8 source (4 channels per voxel) into an rgba8 target
// (convert_sample<uint8_t>: rounded, clamped) or an rgba32f one (channels · scale): dst[4·index +
// c] = convert_sample(sample_trilinear<uint8_t, 4>(g)[c], scale) (opacity-weighted colour), bit for
// bit, two voxels per vector.
int sample_rgba8_avx2(const std::uint8_t* src, const std::int64_t n[3], const SpanBatch& batch,
                      float scale, std::uint8_t* dst);
int sample_rgba8_avx2(const std::uint8_t* src, const std::int64_t n[3], const SpanBatch& batch,
                      float scale, float* dst);

}  // namespace pliant::volume::detail
