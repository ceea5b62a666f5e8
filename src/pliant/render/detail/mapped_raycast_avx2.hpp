// The composite march of render::MappedRayCaster in AVX2, eight rays at a time: each lane marches
// its own ray through the map (mapped_march() of mapped_raycast_kernel.hpp) and does, lane by
// lane, the scalar kernel's IEEE operations in the same order without FMA
// (core/simd_dispatch.hpp): sample position, map cell and fraction, empty cube (and its jump) or
// the cell's validity, the map's trilinear source coordinate (and, shaded, its derivatives), the
// source box test, the RGBA source's trilinear value, classification (α clamp, step opacity,
// division by α), the gradient through the map's Jacobian, and front-to-back compositing. A lane
// whose ray ends (opaque, or no sample left) takes the tile's next ray at once, so no sample past
// the early termination is classified and lanes stay busy whatever their rays' lengths. Rays are
// set up (begin_pixel) and ended (mapped_end) by the scalar code, so every pixel and sample count
// is bitwise what mapped_pixel<true> computes. The map's nodes and the voxels are loaded per lane
// (no gathers, as raycast_avx2.hpp); an RGBA voxel pair is 8 consecutive floats, one load,
// transposed (an rgba8 source's pair is 8 bytes, one load, widened, transposed, each channel
// c / 255 without a division, then premultiplied: bitwise interpolate_rgba8()); the stored
// gradient's voxel pair is 16 bytes, one load, sign-extended, transposed (source_gradient()).
// Step opacities other than the default step's (Δs/u = 1/2) go through the scalar libm calls
// lane by lane. The adaptive step's state (the level wanted, the run's level, discarded samples,
// jumps onto the coarsest runs) is the scalar march's, lane by lane.
#pragma once

#include <cstdint>

#include "pliant/render/detail/mapped_raycast_kernel.hpp"

namespace pliant::render::detail {

// Whether mapped_tile_avx2() can render for m: an RGBA source with at least 2 voxels along x,
// float voxel indices below 2^31, the stored gradient when shading, the 8 octants' empty cubes in
// one array with byte indices below 2^31, and a CPU that runs AVX2.
bool mapped_avx2_fits(const MappedKernel& m);

// mapped_pixel<true>(m, x, y) for every pixel (x, y) of the tile [x0, x1) × [y0, y1): its colour
// into colors[(y − y0)·(x1 − x0) + (x − x0)], bit for bit; returns the sum of the pixels'
// samples. Precondition: mapped_avx2_fits(m), x1 − x0 and y1 − y0 at most TILE.
std::int64_t mapped_tile_avx2(const MappedKernel& m, int x0, int y0, int x1, int y1, Color* colors);

}  // namespace pliant::render::detail
