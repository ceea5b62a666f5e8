#include "pliant/render/detail/raycast_avx2.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/grid8_avx2.hpp"
#include "pliant/render/detail/lanes8_avx2.hpp"
#include "pliant/render/detail/ray_setup8_avx2.hpp"

namespace pliant::render::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

constexpr std::int64_t INDEX_LIMIT = std::int64_t{1} << 31;

// The rays of a tile's pixels (begin_pixel's results, by pixel index in the tile; 8 entries of
// slack for the last group of a row), and the pixels whose rays have samples to march, in order.
constexpr int MAX_PIXELS = TILE * TILE;
struct alignas(32) TileRays {
    float dir[3][MAX_PIXELS + LANES];
    float go[3][MAX_PIXELS + LANES];
    float gd[3][MAX_PIXELS + LANES];
    float inv_gd[3][MAX_PIXELS + LANES];
    float t_near[MAX_PIXELS + LANES], t_far[MAX_PIXELS + LANES], margin[MAX_PIXELS + LANES];
    float length[MAX_PIXELS + LANES];
    std::int32_t num_segments[MAX_PIXELS + LANES];
    // Index of the ray's empty-cube byte of cell 0 (octant · cells in k.empty_cube[0], or 0 in
    // k.axis_cube), and whether the ray has zero direction components (k.axis_cube unset).
    std::int32_t cube[MAX_PIXELS + LANES];
    std::int32_t has_more[MAX_PIXELS + LANES];
    std::int32_t start[MAX_PIXELS + LANES];  // first sample to march
    std::int32_t marched[MAX_PIXELS];        // pixels with num_full = num_segments − 1 ≥ 1
    int num_marched = 0;
};

// Pixel `pixel`'s ray as begin_pixel() returned it.
PixelRay pixel_ray_of(const TileRays& t, int pixel) {
    PixelRay p;
    for (int a = 0; a < 3; ++a) {
        p.dir[a] = t.dir[a][pixel];
        p.r.go[a] = t.go[a][pixel];
        p.r.gd[a] = t.gd[a][pixel];
        p.r.inv_gd[a] = t.inv_gd[a][pixel];
    }
    p.r.t_near = t.t_near[pixel];
    p.r.t_far = t.t_far[pixel];
    p.r.margin = t.margin[pixel];
    p.length = t.length[pixel];
    p.num_segments = t.num_segments[pixel];
    p.num_full = p.num_segments - 1;
    return p;
}

// The 4 rows of voxel pairs a sample with lower corner p reads (p, p + dy, p + dz, p + dz + dy).
PLIANT_AVX2_INLINE void prefetch_rows(const float* p, std::int32_t dy, std::int32_t dz) {
    _mm_prefetch(reinterpret_cast<const char*>(p), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(p + dy), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(p + dz), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(p + dz + dy), _MM_HINT_T0);
}

// The value shading differentiates (shading_value()): the scalar, or α of an RGBA volume (only
// the α channel of interpolate_rgba(): its channels do not mix), at voxel index `index`.
template <bool IS_RGBA>
PLIANT_AVX2_INLINE __m256 shading_value8(const Grid8& grid, __m256i index,
                                         const __m256 fraction[3]) {
    __m256 first[4], second[4];
    const std::int32_t row[4] = {0, grid.dy, grid.dz, grid.dz + grid.dy};
    // RGBA: α apart (k.alpha, the same floats as the values' 4th channel), in x-adjacent pairs.
    const float* v = IS_RGBA ? grid.alpha : grid.v;
    alignas(32) std::int32_t at[LANES];
    store(at, index);
    for (int r = 0; r < 4; ++r) {
        load_pairs(v + row[r], at, first[r], second[r]);
    }
    return trilinear8(first, second, fraction);
}

// shade() for 8 samples at grid positions g (lower corners and fractions of locate(g) given),
// rays along dir: 0.3 + 0.7 |n · dir| with n the normalized central-difference gradient, 1 where
// it vanishes. The same operations in the same order.
template <bool IS_RGBA>
PLIANT_AVX2_INLINE __m256 shade8(const Grid8& grid, const RayCastKernel& k, const __m256 g[3],
                                 const __m256i corner[3], const __m256 fraction[3],
                                 const __m256 dir[3]) {
    __m256 gradient[3];
    for (int a = 0; a < 3; ++a) {
        __m256 value[2];
        for (int side = 0; side < 2; ++side) {
            const __m256 ga = side == 0 ? _mm256_add_ps(g[a], _mm256_set1_ps(1.0f))
                                        : _mm256_sub_ps(g[a], _mm256_set1_ps(1.0f));
            __m256i c[3] = {corner[0], corner[1], corner[2]};
            __m256 f[3] = {fraction[0], fraction[1], fraction[2]};
            locate_axis8(grid, a, ga, c[a], f[a]);
            value[side] = shading_value8<IS_RGBA>(grid, voxel_index8(grid, c), f);
        }
        gradient[a] =
            _mm256_mul_ps(_mm256_sub_ps(value[0], value[1]), _mm256_set1_ps(k.inv_spacing[a]));
    }
    __m256 nonzero;
    const __m256 f = shade_factor8(gradient, dir, nonzero);
    return _mm256_blendv_ps(_mm256_set1_ps(1.0f), f, nonzero);
}

// Puts the ray of pixel `pixel`, marched from sample `start`, into lane l.
void fill_lane(const TileRays& t, int pixel, std::int32_t start, std::int32_t num_cells, Lanes& s,
               int l) {
    for (int a = 0; a < 3; ++a) {
        s.dir[a][l] = t.dir[a][pixel];
        s.go[a][l] = t.go[a][pixel];
        s.gd[a][l] = t.gd[a][pixel];
        s.inv_gd[a][l] = t.inv_gd[a][pixel];
    }
    s.t_near[l] = t.t_near[pixel];
    s.t_far[l] = t.t_far[pixel];
    s.margin[l] = t.margin[pixel];
    s.cr[l] = s.cg[l] = s.cb[l] = s.acc[l] = 0.0f;
    s.n[l] = start;
    s.num_full[l] = t.num_segments[pixel] - 1;
    s.samples[l] = 0;
    s.cube[l] = t.cube[pixel];
    for (auto& m : s.more) {
        m[l] = s.cube[l];
    }
    if (t.has_more[pixel] != 0) {
        // A ray with zero direction components (rare outside axis views): up to 3 more octants.
        const float gd[3] = {t.gd[0][pixel], t.gd[1][pixel], t.gd[2][pixel]};
        const int octant = (gd[0] < 0.0f ? 1 : 0) | (gd[1] < 0.0f ? 2 : 0) | (gd[2] < 0.0f ? 4 : 0);
        const int zero =
            (gd[0] == 0.0f ? 1 : 0) | (gd[1] == 0.0f ? 2 : 0) | (gd[2] == 0.0f ? 4 : 0);
        set_more_octants(s, l, octant, zero, num_cells);
    }
}

// begin_pixel() for the 8 pixels (x + l, y), l = 0 … 7, lane by lane in the same operations, into
// entry first + l of t. Returns bit l set when lane l's ray hits the box with fewer than 2^30
// segments, bit 8 + l when it hits with more (for the scalar code), neither when it misses.
PLIANT_AVX2_FN int setup_rays(const RayCastKernel& k, int x, int y, int first,
                              std::int32_t num_cells, TileRays& t) {
    const Rays8 rays = begin_pixels8(k, x, y);
    const __m256 zero = _mm256_setzero_ps();
    const __m256* gd = rays.gd;
    for (int a = 0; a < 3; ++a) {
        _mm256_storeu_ps(t.dir[a] + first, rays.dir[a]);
        _mm256_storeu_ps(t.go[a] + first, rays.go[a]);
        _mm256_storeu_ps(t.gd[a] + first, rays.gd[a]);
        _mm256_storeu_ps(t.inv_gd[a] + first, rays.inv_gd[a]);
    }
    _mm256_storeu_ps(t.t_near + first, rays.t_near);
    _mm256_storeu_ps(t.t_far + first, rays.t_far);
    _mm256_storeu_ps(t.margin + first, rays.margin);
    _mm256_storeu_ps(t.length + first, rays.length);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(t.num_segments + first), rays.num_segments);
    if (k.axis_cube != nullptr) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(t.cube + first), _mm256_setzero_si256());
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(t.has_more + first), _mm256_setzero_si256());
    } else {
        // octant_of() and zero_axes_of() ≠ 0.
        const __m256i octant = _mm256_or_si256(
            _mm256_srli_epi32(as_int(_mm256_cmp_ps(gd[0], zero, _CMP_LT_OQ)), 31),
            _mm256_or_si256(
                _mm256_slli_epi32(
                    _mm256_srli_epi32(as_int(_mm256_cmp_ps(gd[1], zero, _CMP_LT_OQ)), 31), 1),
                _mm256_slli_epi32(
                    _mm256_srli_epi32(as_int(_mm256_cmp_ps(gd[2], zero, _CMP_LT_OQ)), 31), 2)));
        const __m256 has_zero = _mm256_or_ps(_mm256_cmp_ps(gd[0], zero, _CMP_EQ_OQ),
                                             _mm256_or_ps(_mm256_cmp_ps(gd[1], zero, _CMP_EQ_OQ),
                                                          _mm256_cmp_ps(gd[2], zero, _CMP_EQ_OQ)));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(t.cube + first),
                            _mm256_mullo_epi32(octant, _mm256_set1_epi32(num_cells)));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(t.has_more + first), as_int(has_zero));
    }
    return rays.hits | (rays.too_long << LANES);
}

// Marches the rays of queue[0, queue_size) (pixels of t) in the 8 lanes, a lane taking the next
// ray as soon as its ray ends. REACH: each ray from its first sample to its first sample to
// classify (march_composite's skipping, the same jumps), whose index goes to t.start[pixel] and
// whose voxels are prefetched, the pixel to reached[num_reached++] (may be queue itself: it is
// written behind the reading position); rays with no such sample end there (their colour to
// colors). Otherwise: each ray from t.start[pixel] to its end, as march_composite, its colour to
// colors. Adds the classified samples to `samples`.
template <bool REACH, bool IS_RGBA, bool SHADING>
PLIANT_AVX2_FN void march_lanes(const RayCastKernel& k, TileRays& t, const std::int32_t* queue,
                                int queue_size, std::int32_t* reached, int& num_reached,
                                Color* colors, std::int64_t& samples) {
    const auto num_cells =
        static_cast<std::int32_t>(static_cast<std::int64_t>(k.cells[0]) * k.cells[1] * k.cells[2]);
    Lanes s;
    LaneSlots slots;
    // Ends the ray of lane l, its march done, and writes its colour.
    const auto end_lane = [&](int l) {
        std::int64_t lane_samples = s.samples[l];
        const Accumulated c{s.cr[l], s.cg[l], s.cb[l], s.acc[l]};
        if (c.a > k.threshold) {
            // Opaque: end_composite() adds the background behind, no last segment.
            colors[slots.pixel_of[l]] = over_background(k, c);
        } else {
            colors[slots.pixel_of[l]] =
                end_composite<IS_RGBA>(k, pixel_ray_of(t, slots.pixel_of[l]), c, lane_samples);
        }
        samples += lane_samples;
    };
    // Gives lane l the next queued ray, or clears it when none is left.
    const auto refill = [&](int l) {
        if (slots.next < queue_size) {
            const int pixel = queue[slots.next++];
            fill_lane(t, pixel, REACH ? 0 : t.start[pixel], num_cells, s, l);
            slots.take(l, pixel, t.has_more[pixel] != 0);
            return;
        }
        clear_lane(s, l);
    };
    // Frees lane l (its ray reached its first sample or ended) and refills it.
    const auto release = [&](int l) {
        slots.free(l);
        refill(l);
    };
    for (int l = 0; l < LANES; ++l) {
        refill(l);
    }

    const __m256 step = _mm256_set1_ps(k.step);
    const __m256 inv_step = _mm256_set1_ps(k.inv_step);
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 threshold = _mm256_set1_ps(k.threshold);
    const __m256 g_max[3] = {_mm256_set1_ps(k.g_max[0]), _mm256_set1_ps(k.g_max[1]),
                             _mm256_set1_ps(k.g_max[2])};
    const __m256i max_i0[3] = {_mm256_set1_epi32(k.max_i0[0]), _mm256_set1_epi32(k.max_i0[1]),
                               _mm256_set1_epi32(k.max_i0[2])};
    const __m256i cells_x = _mm256_set1_epi32(k.cells[0]);
    const __m256i cells_y = _mm256_set1_epi32(k.cells[1]);
    const __m256 cell_size = _mm256_set1_ps(static_cast<float>(CELL));
    const __m256i stride_y = _mm256_set1_epi32(static_cast<std::int32_t>(k.stride[1]));
    const __m256i stride_z = _mm256_set1_epi32(static_cast<std::int32_t>(k.stride[2]));
    const __m256i one_i = _mm256_set1_epi32(1);
    // Offsets of the voxel rows in the value array (floats: 4 per voxel for RGBA).
    constexpr std::int32_t CH = IS_RGBA ? 4 : 1;
    const auto dy = static_cast<std::int32_t>(k.d[1]);
    const auto dz = static_cast<std::int32_t>(k.d[2]);
    const float* v = k.values;
    Grid8 grid;
    load_grid8(k, grid);
    const float* lut = k.lut;
    const std::uint8_t* cubes = k.axis_cube != nullptr ? k.axis_cube : k.empty_cube[0];

    // NOLINTNEXTLINE(bugprone-infinite-loop): the lambdas above retire lanes (num_live).
    while (slots.num_live > 0) {
        const __m256i live = lanes_of8(slots.live_mask);
        const __m256i n = load(s.n);
        const __m256i num_full = load(s.num_full);
        // sample_position: go + (t_near + (n + 0.5)·Δs)·gd.
        const __m256 t_near = load(s.t_near);
        const __m256 tm =
            _mm256_add_ps(t_near, _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(n), half), step));
        // locate: clamp to [0, n − 1], lower corner min(⌊·⌋, n − 2), fractions.
        __m256i corner[3];
        __m256 fraction[3];
        __m256 g_pos[3];
        for (int a = 0; a < 3; ++a) {
            g_pos[a] = _mm256_add_ps(load(s.go[a]), _mm256_mul_ps(tm, load(s.gd[a])));
            locate_axis8(grid, a, g_pos[a], corner[a], fraction[a]);
        }
        __m256i n_next = _mm256_add_epi32(n, one_i);
        __m256i classified = live;
        if (k.skipping) {
            const __m256i cell_coord[3] = {_mm256_srli_epi32(corner[0], CELL_SHIFT),
                                           _mm256_srli_epi32(corner[1], CELL_SHIFT),
                                           _mm256_srli_epi32(corner[2], CELL_SHIFT)};
            const __m256i cell = _mm256_add_epi32(
                cell_coord[0],
                _mm256_mullo_epi32(
                    cells_x,
                    _mm256_add_epi32(cell_coord[1], _mm256_mullo_epi32(cells_y, cell_coord[2]))));
            const __m256i side = cube_side8(s, cubes, k.empty_cube[0], cell, slots.more_count > 0);
            const __m256i jumps =
                _mm256_and_si256(live, _mm256_cmpgt_epi32(side, _mm256_setzero_si256()));
            if (_mm256_movemask_ps(as_float(jumps)) != 0) {
                n_next = jump8(s, cell_coord, side, cell_size, jumps, n_next, num_full, t_near,
                               inv_step);
            }
            // The sub-cell's occupancy bit, for the samples that do not jump.
            const __m256i bit = _mm256_or_si256(
                _mm256_and_si256(_mm256_srli_epi32(corner[0], 1), one_i),
                _mm256_or_si256(
                    _mm256_slli_epi32(_mm256_and_si256(_mm256_srli_epi32(corner[1], 1), one_i), 1),
                    _mm256_slli_epi32(_mm256_and_si256(_mm256_srli_epi32(corner[2], 1), one_i),
                                      2)));
            alignas(32) std::int32_t at[LANES];
            store(at, cell);
            const __m256i sub = load_bytes(k.sub_occupied, at);
            const __m256i occupied = _mm256_cmpgt_epi32(
                _mm256_and_si256(_mm256_srlv_epi32(sub, bit), one_i), _mm256_setzero_si256());
            classified = _mm256_andnot_si256(jumps, _mm256_and_si256(live, occupied));
        }
        __m256i terminated = _mm256_setzero_si256();
        if (!REACH && _mm256_movemask_ps(as_float(classified)) != 0) {
            // classify_shaded() → composite(): straight colour and opacity of a step.
            const __m256i index = voxel_index8(grid, corner);
            alignas(32) std::int32_t at[LANES];
            store(at, index);
            __m256 rgba[4];
            if constexpr (IS_RGBA) {
                // classify<true>: α clamped to [0, 1], its step opacity (libm, lane by lane),
                // colour divided by the unclamped interpolated α.
                __m256 interpolated[4];
                interpolate_rgba8(grid, at, fraction, interpolated);
                const __m256 a = _mm256_min_ps(one, _mm256_max_ps(zero, interpolated[3]));
                const __m256 positive = _mm256_cmp_ps(a, zero, _CMP_GT_OQ);
                alignas(32) float a_step[LANES] = {};
                if (k.step_over_unit == 0.5f) {
                    // rgba_step_opacity_half, 1 for a ≥ 1.
                    const __m256 half_step =
                        _mm256_div_ps(a, _mm256_add_ps(one, _mm256_sqrt_ps(_mm256_sub_ps(one, a))));
                    store(a_step,
                          _mm256_blendv_ps(half_step, one, _mm256_cmp_ps(a, one, _CMP_GE_OQ)));
                } else {
                    int todo = _mm256_movemask_ps(_mm256_and_ps(positive, as_float(classified)));
                    alignas(32) float a_lane[LANES];
                    store(a_lane, a);
                    while (todo != 0) {
                        const int l = __builtin_ctz(static_cast<unsigned>(todo));
                        todo &= todo - 1;
                        a_step[l] = rgba_step_opacity(a_lane[l], k.step_over_unit);
                    }
                }
                const __m256 inv = _mm256_div_ps(one, interpolated[3]);
                for (int c = 0; c < 3; ++c) {
                    rgba[c] = _mm256_and_ps(positive, _mm256_mul_ps(interpolated[c], inv));
                }
                rgba[3] = _mm256_and_ps(positive, load(a_step));
            } else {
                // interpolate_scalar → lookup-table entry. The 4 rows of x-adjacent pairs
                // (dx = 1) at offsets 0, dy, dz, dz + dy.
                __m256 first[4], second[4];
                load_pairs(v, at, first[0], second[0]);
                load_pairs(v + dy, at, first[1], second[1]);
                load_pairs(v + dz, at, first[2], second[2]);
                load_pairs(v + dz + dy, at, first[3], second[3]);
                const __m256 value = trilinear8(first, second, fraction);
                const __m256i entry = _mm256_slli_epi32(
                    _mm256_cvttps_epi32(_mm256_add_ps(value, half)), 2);  // 4·index
                store(at, entry);
                load_entries(lut, at, rgba);
            }
            const __m256 alpha = rgba[3];
            const __m256 blend =
                _mm256_and_ps(as_float(classified), _mm256_cmp_ps(alpha, zero, _CMP_GT_OQ));
            if constexpr (SHADING) {
                if (_mm256_movemask_ps(blend) != 0) {
                    const __m256 dir[3] = {load(s.dir[0]), load(s.dir[1]), load(s.dir[2])};
                    const __m256 f = shade8<IS_RGBA>(grid, k, g_pos, corner, fraction, dir);
                    for (int c = 0; c < 3; ++c) {
                        rgba[c] = _mm256_mul_ps(rgba[c], f);
                    }
                }
            }
            terminated = composite8(s, rgba, blend, classified, threshold);
        }
        store(s.n, n_next);
        if constexpr (!REACH) {
            // Prefetches the voxel rows of each lane's sample after next (n_next + 1).
            const __m256 t_ahead = _mm256_add_ps(
                t_near,
                _mm256_mul_ps(
                    _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(n_next, one_i)), half),
                    step));
            __m256i ahead[3];
            for (int a = 0; a < 3; ++a) {
                const __m256 g =
                    _mm256_add_ps(load(s.go[a]), _mm256_mul_ps(t_ahead, load(s.gd[a])));
                ahead[a] = _mm256_min_epi32(
                    _mm256_cvttps_epi32(_mm256_min_ps(g_max[a], _mm256_max_ps(zero, g))),
                    max_i0[a]);
            }
            alignas(32) std::int32_t index[LANES];
            store(index, _mm256_add_epi32(
                             ahead[0], _mm256_add_epi32(_mm256_mullo_epi32(stride_y, ahead[1]),
                                                        _mm256_mullo_epi32(stride_z, ahead[2]))));
            for (int l : index) {
                prefetch_rows(v + CH * static_cast<std::int64_t>(l), CH * dy, CH * dz);
            }
        }
        const __m256i more_to_march = _mm256_cmpgt_epi32(num_full, n_next);
        if constexpr (REACH) {
            // A lane ends its reach at a sample to classify, or at its ray's end.
            const int to_classify = _mm256_movemask_ps(as_float(classified));
            int done_mask = to_classify |
                            _mm256_movemask_ps(as_float(_mm256_andnot_si256(more_to_march, live)));
            if (done_mask != 0) {
                alignas(32) std::int32_t index[LANES];
                alignas(32) std::int32_t first[LANES];
                store(index,
                      _mm256_add_epi32(corner[0],
                                       _mm256_add_epi32(_mm256_mullo_epi32(stride_y, corner[1]),
                                                        _mm256_mullo_epi32(stride_z, corner[2]))));
                store(first, n);
                while (done_mask != 0) {
                    const int l = __builtin_ctz(static_cast<unsigned>(done_mask));
                    done_mask &= done_mask - 1;
                    if ((to_classify >> l & 1) != 0) {
                        prefetch_rows(v + CH * static_cast<std::int64_t>(index[l]), CH * dy,
                                      CH * dz);
                        t.start[slots.pixel_of[l]] = first[l];
                        reached[num_reached++] = slots.pixel_of[l];
                    } else {
                        end_lane(l);
                    }
                    release(l);
                }
            }
        } else {
            // Done: opaque (accumulated opacity above the threshold), or no sample left.
            const __m256i done =
                _mm256_andnot_si256(_mm256_andnot_si256(terminated, more_to_march), live);
            int done_mask = _mm256_movemask_ps(as_float(done));
            while (done_mask != 0) {
                const int l = __builtin_ctz(static_cast<unsigned>(done_mask));
                done_mask &= done_mask - 1;
                end_lane(l);
                release(l);
            }
        }
    }
}

// The MIP march of the rays t.marched[0, t.num_marched) in the 8 lanes, as raycast_begun()'s MIP
// branch: every sample of the ray (num_segments), skipping a sample whose cell's largest value
// does not exceed the lane's maximum by a jump to the cell's end; the lane's maximum in s.acc
// (−1: none), RGBA the interpolated sample that had it in s.cr, s.cg, s.cb. Colours to colors.
template <bool IS_RGBA>
PLIANT_AVX2_FN void march_mip(const RayCastKernel& k, const TileRays& t, Color* colors,
                              std::int64_t& samples) {
    const auto num_cells =
        static_cast<std::int32_t>(static_cast<std::int64_t>(k.cells[0]) * k.cells[1] * k.cells[2]);
    Lanes s;
    LaneSlots slots;
    const auto end_lane = [&](int l) {
        const Sample best_sample{s.cr[l], s.cg[l], s.cb[l], s.acc[l]};
        colors[slots.pixel_of[l]] = end_mip<IS_RGBA>(k, s.acc[l], best_sample);
        samples += s.samples[l];
    };
    const auto refill = [&](int l) {
        if (slots.next < t.num_marched) {
            const int pixel = t.marched[slots.next++];
            fill_lane(t, pixel, 0, num_cells, s, l);
            s.num_full[l] = t.num_segments[pixel];
            s.acc[l] = -1.0f;
            slots.take(l, pixel, false);
            return;
        }
        clear_lane(s, l);
    };
    for (int l = 0; l < LANES; ++l) {
        refill(l);
    }
    const __m256 step = _mm256_set1_ps(k.step);
    const __m256 inv_step = _mm256_set1_ps(k.inv_step);
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256i one_i = _mm256_set1_epi32(1);
    const __m256i cells_x = _mm256_set1_epi32(k.cells[0]);
    const __m256i cells_y = _mm256_set1_epi32(k.cells[1]);
    const __m256 cell_size = _mm256_set1_ps(static_cast<float>(CELL));
    Grid8 grid;
    load_grid8(k, grid);

    // NOLINTNEXTLINE(bugprone-infinite-loop): end_lane and refill retire lanes (num_live).
    while (slots.num_live > 0) {
        const __m256i live = lanes_of8(slots.live_mask);
        const __m256i n = load(s.n);
        const __m256i num_full = load(s.num_full);
        const __m256 t_near = load(s.t_near);
        const __m256 tm =
            _mm256_add_ps(t_near, _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(n), half), step));
        __m256i corner[3];
        __m256 fraction[3];
        for (int a = 0; a < 3; ++a) {
            const __m256 g = _mm256_add_ps(load(s.go[a]), _mm256_mul_ps(tm, load(s.gd[a])));
            locate_axis8(grid, a, g, corner[a], fraction[a]);
        }
        __m256i n_next = _mm256_add_epi32(n, one_i);
        __m256i classified = live;
        __m256 best = load(s.acc);
        if (k.skipping) {
            const __m256i cell_coord[3] = {_mm256_srli_epi32(corner[0], CELL_SHIFT),
                                           _mm256_srli_epi32(corner[1], CELL_SHIFT),
                                           _mm256_srli_epi32(corner[2], CELL_SHIFT)};
            const __m256i cell = _mm256_add_epi32(
                cell_coord[0],
                _mm256_mullo_epi32(
                    cells_x,
                    _mm256_add_epi32(cell_coord[1], _mm256_mullo_epi32(cells_y, cell_coord[2]))));
            const __m256 cell_max = _mm256_i32gather_ps(k.cell_max, cell, 4);
            const __m256i jumps =
                _mm256_and_si256(live, as_int(_mm256_cmp_ps(cell_max, best, _CMP_LE_OQ)));
            if (_mm256_movemask_ps(as_float(jumps)) != 0) {
                n_next = jump8(s, cell_coord, one_i, cell_size, jumps, n_next, num_full, t_near,
                               inv_step);
            }
            classified = _mm256_andnot_si256(jumps, live);
        }
        if (_mm256_movemask_ps(as_float(classified)) != 0) {
            alignas(32) std::int32_t at[LANES];
            store(at, voxel_index8(grid, corner));
            if constexpr (IS_RGBA) {
                __m256 value[4];
                interpolate_rgba8(grid, at, fraction, value);
                const __m256 update =
                    _mm256_and_ps(as_float(classified), _mm256_cmp_ps(value[3], best, _CMP_GT_OQ));
                store(s.cr, _mm256_blendv_ps(load(s.cr), value[0], update));
                store(s.cg, _mm256_blendv_ps(load(s.cg), value[1], update));
                store(s.cb, _mm256_blendv_ps(load(s.cb), value[2], update));
                best = _mm256_blendv_ps(best, value[3], update);
            } else {
                __m256 first[4], second[4];
                const std::int32_t row[4] = {0, grid.dy, grid.dz, grid.dz + grid.dy};
                for (int r = 0; r < 4; ++r) {
                    load_pairs(grid.v + row[r], at, first[r], second[r]);
                }
                const __m256 value = trilinear8(first, second, fraction);
                const __m256 update =
                    _mm256_and_ps(as_float(classified), _mm256_cmp_ps(value, best, _CMP_GT_OQ));
                best = _mm256_blendv_ps(best, value, update);
            }
            store(s.acc, best);
            store(s.samples, _mm256_sub_epi32(load(s.samples), classified));
        }
        store(s.n, n_next);
        int done_mask = _mm256_movemask_ps(
            as_float(_mm256_andnot_si256(_mm256_cmpgt_epi32(num_full, n_next), live)));
        while (done_mask != 0) {
            const int l = __builtin_ctz(static_cast<unsigned>(done_mask));
            done_mask &= done_mask - 1;
            end_lane(l);
            slots.free(l);
            refill(l);
        }
    }
}

}  // namespace

bool composite_avx2_fits(const RayCastKernel& k) {
    if (!has_avx2() || (!k.is_rgba && k.lut == nullptr) ||
        (k.is_rgba && k.shading && k.alpha == nullptr)) {
        return false;
    }
    const std::int64_t num_voxels = static_cast<std::int64_t>(k.n[0]) * k.n[1] * k.n[2];
    const std::int64_t num_cells = static_cast<std::int64_t>(k.cells[0]) * k.cells[1] * k.cells[2];
    for (int o = 0; o < 8; ++o) {
        if (k.empty_cube[o] != k.empty_cube[0] + o * num_cells) {
            return false;
        }
    }
    // Voxel pairs along x are loaded together: dx = 1 (an x extent of at least 2 voxels).
    const std::int64_t floats_per_voxel = k.is_rgba ? 4 : 1;
    return k.d[0] == 1 && floats_per_voxel * num_voxels < INDEX_LIMIT / 2 &&
           8 * num_cells < INDEX_LIMIT;
}

namespace {

template <bool IS_RGBA, bool SHADING>
PLIANT_AVX2_FN std::int64_t composite_tile(const RayCastKernel& k, int x0, int y0, int x1, int y1,
                                           Color* colors) {
    const int tile_width = x1 - x0;
    const auto num_cells =
        static_cast<std::int32_t>(static_cast<std::int64_t>(k.cells[0]) * k.cells[1] * k.cells[2]);
    std::int64_t samples = 0;

    // The tile's rays, 8 at a time; those with samples to march are queued for the lanes.
    TileRays t;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; x += LANES) {
            const int first = (y - y0) * tile_width + (x - x0);
            const int bits = setup_rays(k, x, y, first, num_cells, t);
            const int count = std::min(LANES, x1 - x);
            for (int l = 0; l < count; ++l) {
                const int pixel = first + l;
                if ((bits >> l & 1) != 0) {
                    if (t.num_segments[pixel] > 1) {
                        t.marched[t.num_marched++] = pixel;
                    } else {
                        colors[pixel] = end_composite<IS_RGBA>(k, pixel_ray_of(t, pixel),
                                                               Accumulated{}, samples);
                    }
                } else if ((bits >> (LANES + l) & 1) != 0) {
                    PixelRay p;  // too many samples for a lane's counters: the scalar kernel
                    begin_pixel(k, x + l, y, p);
                    const Accumulated c = march_composite<IS_RGBA>(k, p, samples);
                    colors[pixel] = end_composite<IS_RGBA>(k, p, c, samples);
                } else {
                    colors[pixel] = k.background;
                }
            }
        }
    }

    // Two passes over the queue (the march split at each ray's first classified sample, so the
    // same operations): the first moves every ray through empty space to that sample and
    // prefetches its voxels, the second classifies. A ray's first voxels are thus requested
    // about a tile's worth of rays before they are needed; a miss costs ~150 ns (DRAM of this
    // 2-vCPU guest), more than the ~400 instructions that the reorder buffer can run past it.
    int num_reached = 0;
    if (k.skipping) {
        march_lanes<true, IS_RGBA, SHADING>(k, t, t.marched, t.num_marched, t.marched, num_reached,
                                            colors, samples);
    } else {
        num_reached = t.num_marched;
        for (int q = 0; q < num_reached; ++q) {
            t.start[t.marched[q]] = 0;
        }
    }
    int unused = 0;
    march_lanes<false, IS_RGBA, SHADING>(k, t, t.marched, num_reached, nullptr, unused, colors,
                                         samples);
    return samples;
}

}  // namespace

PLIANT_AVX2_FN std::int64_t composite_tile_avx2(const RayCastKernel& k, int x0, int y0, int x1,
                                                int y1, Color* colors) {
    if (k.is_rgba) {
        return k.shading ? composite_tile<true, true>(k, x0, y0, x1, y1, colors)
                         : composite_tile<true, false>(k, x0, y0, x1, y1, colors);
    }
    return k.shading ? composite_tile<false, true>(k, x0, y0, x1, y1, colors)
                     : composite_tile<false, false>(k, x0, y0, x1, y1, colors);
}

namespace {

// MIP: every ray that hits the box is marched (all its segments).
template <bool IS_RGBA>
PLIANT_AVX2_FN std::int64_t mip_tile(const RayCastKernel& k, int x0, int y0, int x1, int y1,
                                     Color* colors) {
    const int tile_width = x1 - x0;
    const auto num_cells =
        static_cast<std::int32_t>(static_cast<std::int64_t>(k.cells[0]) * k.cells[1] * k.cells[2]);
    std::int64_t samples = 0;
    TileRays t;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; x += LANES) {
            const int first = (y - y0) * tile_width + (x - x0);
            const int bits = setup_rays(k, x, y, first, num_cells, t);
            const int count = std::min(LANES, x1 - x);
            for (int l = 0; l < count; ++l) {
                const int pixel = first + l;
                if ((bits >> l & 1) != 0) {
                    t.marched[t.num_marched++] = pixel;
                } else if ((bits >> (LANES + l) & 1) != 0) {
                    // Too many samples for a lane's counters: the scalar kernel.
                    const PixelResult p = raycast_pixel<IS_RGBA>(k, x + l, y);
                    colors[pixel] = p.color;
                    samples += p.samples;
                } else {
                    colors[pixel] = k.background;
                }
            }
        }
    }
    march_mip<IS_RGBA>(k, t, colors, samples);
    return samples;
}

}  // namespace

PLIANT_AVX2_FN std::int64_t mip_tile_avx2(const RayCastKernel& k, int x0, int y0, int x1, int y1,
                                          Color* colors) {
    return k.is_rgba ? mip_tile<true>(k, x0, y0, x1, y1, colors)
                     : mip_tile<false>(k, x0, y0, x1, y1, colors);
}

namespace {

// 4 values as doubles.
PLIANT_AVX2_INLINE __m256d four(const std::uint8_t* in) {
    std::int32_t word;
    std::memcpy(&word, in, 4);
    return _mm256_cvtepi32_pd(_mm_cvtepu8_epi32(_mm_cvtsi32_si128(word)));
}
PLIANT_AVX2_INLINE __m256d four(const std::int16_t* in) {
    return _mm256_cvtepi32_pd(
        _mm_cvtepi16_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(in))));
}
PLIANT_AVX2_INLINE __m256d four(const std::uint16_t* in) {
    return _mm256_cvtepi32_pd(
        _mm_cvtepu16_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(in))));
}
PLIANT_AVX2_INLINE __m256d four(const float* in) {
    return _mm256_cvtps_pd(_mm_loadu_ps(in));
}

template <typename T>
PLIANT_AVX2_FN std::int64_t lookup_coordinates(const T* in, std::int64_t count, double lo,
                                               double scale, float* out) {
    const __m256d lo_v = _mm256_set1_pd(lo);
    const __m256d scale_v = _mm256_set1_pd(scale);
    const __m256d zero = _mm256_setzero_pd();
    const __m256d top = _mm256_set1_pd(double{LUT_SIZE - 1});
    const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFF));
    const std::int64_t end = count - count % 4;
    for (std::int64_t i = 0; i < end; i += 4) {
        const __m256d s = _mm256_mul_pd(_mm256_sub_pd(four(in + i), lo_v), scale_v);
        // std::clamp(s, 0, top) = top < max(0, s) ? top : …, for finite s; 0 otherwise.
        const __m256d clamped = _mm256_min_pd(top, _mm256_max_pd(zero, s));
        const __m256d finite = _mm256_cmp_pd(_mm256_and_pd(s, abs_mask), inf, _CMP_LT_OQ);
        _mm_storeu_ps(out + i, _mm256_cvtpd_ps(_mm256_and_pd(clamped, finite)));
    }
    return end;
}

}  // namespace

std::int64_t lookup_coordinates_avx2(const std::uint8_t* in, std::int64_t count, double lo,
                                     double scale, float* out) {
    return lookup_coordinates(in, count, lo, scale, out);
}
std::int64_t lookup_coordinates_avx2(const std::int16_t* in, std::int64_t count, double lo,
                                     double scale, float* out) {
    return lookup_coordinates(in, count, lo, scale, out);
}
std::int64_t lookup_coordinates_avx2(const std::uint16_t* in, std::int64_t count, double lo,
                                     double scale, float* out) {
    return lookup_coordinates(in, count, lo, scale, out);
}
std::int64_t lookup_coordinates_avx2(const float* in, std::int64_t count, double lo, double scale,
                                     float* out) {
    return lookup_coordinates(in, count, lo, scale, out);
}

namespace {

// The 8 channels of 2 voxels as floats in [0, 1]: c / 255 (rgba8) or the float itself.
PLIANT_AVX2_INLINE __m256 eight(const std::uint8_t* in) {
    return _mm256_div_ps(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(
                             _mm_loadl_epi64(reinterpret_cast<const __m128i*>(in)))),
                         _mm256_set1_ps(255.0f));
}
PLIANT_AVX2_INLINE __m256 eight(const float* in) {
    return _mm256_loadu_ps(in);
}

template <typename T>
PLIANT_AVX2_FN std::int64_t rgba_values(const T* in, std::int64_t count, float* out, float* alpha) {
    const __m256 zero = _mm256_setzero_ps();
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF));
    const std::int64_t end = count - count % 2;
    for (std::int64_t v = 0; v < end; v += 2) {
        const __m256 x = eight(in + 4 * v);
        // std::clamp(x, 0, 1) (x < 0 ? 0 : 1 < x ? 1 : x, so −0 stays −0) when finite, else 0.
        __m256 c = _mm256_blendv_ps(x, zero, _mm256_cmp_ps(x, zero, _CMP_LT_OQ));
        c = _mm256_blendv_ps(c, one, _mm256_cmp_ps(one, c, _CMP_LT_OQ));
        c = _mm256_and_ps(c, _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_LT_OQ));
        const __m256 a = _mm256_permute_ps(c, 0xFF);  // α of each voxel in its 4 channels
        _mm256_storeu_ps(out + 4 * v, _mm256_blend_ps(_mm256_mul_ps(c, a), c, 0x88));
        if (alpha != nullptr) {
            alpha[v] = _mm256_cvtss_f32(a);
            alpha[v + 1] = _mm256_cvtss_f32(_mm256_permute2f128_ps(a, a, 0x11));
        }
    }
    return end;
}

}  // namespace

std::int64_t rgba_values_avx2(const std::uint8_t* in, std::int64_t count, float* out,
                              float* alpha) {
    return rgba_values(in, count, out, alpha);
}
std::int64_t rgba_values_avx2(const float* in, std::int64_t count, float* out, float* alpha) {
    return rgba_values(in, count, out, alpha);
}

#else

std::int64_t lookup_coordinates_avx2(const std::uint8_t*, std::int64_t, double, double, float*) {
    return 0;
}
std::int64_t lookup_coordinates_avx2(const std::int16_t*, std::int64_t, double, double, float*) {
    return 0;
}
std::int64_t lookup_coordinates_avx2(const std::uint16_t*, std::int64_t, double, double, float*) {
    return 0;
}
std::int64_t lookup_coordinates_avx2(const float*, std::int64_t, double, double, float*) {
    return 0;
}

std::int64_t rgba_values_avx2(const std::uint8_t*, std::int64_t, float*, float*) {
    return 0;
}
std::int64_t rgba_values_avx2(const float*, std::int64_t, float*, float*) {
    return 0;
}

bool composite_avx2_fits(const RayCastKernel&) {
    return false;
}

std::int64_t composite_tile_avx2(const RayCastKernel&, int, int, int, int, Color*) {
    return 0;
}

std::int64_t mip_tile_avx2(const RayCastKernel&, int, int, int, int, Color*) {
    return 0;
}

#endif

}  // namespace pliant::render::detail
