// The ray caster's composite march in AVX2, eight rays at a time (render/raycast.hpp documents the
// algorithm, render/detail/raycast_kernel.hpp has the scalar kernel). Compiled for AVX2 with a
// function attribute and chosen at run time (pliant::has_avx2(), core/simd_dispatch.hpp).
//
// Each of the 8 lanes marches its own ray and does, lane by lane, the IEEE operations of
// march_composite() in the same order, without FMA: sample position, clamp and lower corner,
// cell, empty cube (and its jump), sub-cell bit, trilinear value (scalar volumes) or
// opacity-weighted colour (RGBA volumes), classification (lookup-table entry; or RGBA's clamp,
// step opacity through the same libm calls lane by lane, and division by α), the gradient
// shading of classify_shaded() when on, and front-to-back compositing. Rays are set up
// (begin_pixel) and ended (end_composite) by the scalar code, so every pixel and sample count is
// bitwise what raycast_pixel<IS_RGBA> computes. A lane whose ray ends takes the tile's next ray at
// once, so lanes stay busy whatever their rays' lengths. The arithmetic runs 8 wide; the loads
// stay per lane (AVX2 gathers are slow on AMD Zen), voxels in x-adjacent pairs (an RGBA pair is
// 8 consecutive floats, one load, transposed); RGBA gradients read a copy of α alone
// (RayCastKernel::alpha). Clipping planes are applied in the rays' set-up. MIP marches 8 rays the
// same way (mip_tile_avx2), a sample's cell maximum gathered.
#pragma once

#include <cstdint>

#include "pliant/render/detail/raycast_kernel.hpp"

namespace pliant::render::detail {

// Whether composite_tile_avx2() (mip_tile_avx2() for MIP) can render with k: any mode (shaded or
// not, scalar or RGBA, clipped or not), float indices into the values below 2^31 and the 8 octants'
// cube indices too, an x extent of at least 2 voxels, and a CPU that runs AVX2 (has_avx2()).
bool composite_avx2_fits(const RayCastKernel& k);

// raycast_pixel<k.is_rgba>(k, x, y) for every pixel (x, y) of the tile [x0, x1) × [y0, y1): its
// colour into colors[(y − y0)·(x1 − x0) + (x − x0)], bit for bit; returns the sum of the pixels'
// samples. Precondition: composite_avx2_fits(k).
std::int64_t composite_tile_avx2(const RayCastKernel& k, int x0, int y0, int x1, int y1,
                                 Color* colors);
// The same for MIP (k.is_mip): every ray's largest value, its cell-maximum skipping as the scalar
// kernel's, bit for bit. Precondition: composite_avx2_fits(k).
std::int64_t mip_tile_avx2(const RayCastKernel& k, int x0, int y0, int x1, int y1, Color* colors);

// lookup_coordinate(in[i], lo, scale) for i in [0, count − count mod 4), bit for bit (the same
// double operations, 4 lanes); returns that count (the caller converts the rest). Precondition:
// has_avx2().
std::int64_t lookup_coordinates_avx2(const std::uint8_t* in, std::int64_t count, double lo,
                                     double scale, float* out);
std::int64_t lookup_coordinates_avx2(const std::int16_t* in, std::int64_t count, double lo,
                                     double scale, float* out);
std::int64_t lookup_coordinates_avx2(const std::uint16_t* in, std::int64_t count, double lo,
                                     double scale, float* out);
std::int64_t lookup_coordinates_avx2(const float* in, std::int64_t count, double lo, double scale,
                                     float* out);

// The ray caster's RGBA voxels: for voxel v in [0, count − count mod 2) with channels c (c / 255
// for rgba8, clamped to [0, 1] as std::clamp does, 0 when not finite) out[4v … 4v + 3] =
// (c0·c3, c1·c3, c2·c3, c3) and, when alpha is not null, alpha[v] = c3; bit for bit the scalar
// formula (raycast.cpp's RowConverter). Returns that count. Precondition: has_avx2().
std::int64_t rgba_values_avx2(const std::uint8_t* in, std::int64_t count, float* out, float* alpha);
std::int64_t rgba_values_avx2(const float* in, std::int64_t count, float* out, float* alpha);

}  // namespace pliant::render::detail
