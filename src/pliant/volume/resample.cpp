#include "pliant/volume/resample.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/volume/detail/resample_avx2.hpp"
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/visibility.hpp"

// Compiled with -ffp-contract=off (cmake/PliantCodegen.cmake): see detail/resample_kernel.hpp.

namespace pliant::volume {
namespace {

using detail::GridFrame;
using detail::TetRaster;

using detail::frame_of;

// Bricks of the visibility mask: 1 when any voxel of the BRICK³ block is visible. A first,
// coarse test before the exact per-voxel scan of a tet's footprint.
constexpr std::int64_t BRICK = 8;

struct VisibilityIndex {
    std::vector<std::uint8_t> voxels;  // Volume::index order
    std::vector<std::uint8_t> bricks;  // brick (bi, bj, bk), bi fastest
    std::int64_t nb[3];
};

VisibilityIndex build_visibility(const Volume& source, const TransferFunction* tf) {
    VisibilityIndex vis;
    vis.voxels = visible_voxels(source, tf);
    const Dims& n = source.dims();
    for (int a = 0; a < 3; ++a) {
        vis.nb[a] = (n[static_cast<std::size_t>(a)] + BRICK - 1) / BRICK;
    }
    vis.bricks.assign(static_cast<std::size_t>(vis.nb[0] * vis.nb[1] * vis.nb[2]), 0);
    parallel_for(
        static_cast<std::int64_t>(vis.bricks.size()),
        [&](std::int64_t b) {
            const std::int64_t bi = b % vis.nb[0];
            const std::int64_t bj = (b / vis.nb[0]) % vis.nb[1];
            const std::int64_t bk = b / (vis.nb[0] * vis.nb[1]);
            std::uint8_t any = 0;
            for (std::int64_t k = bk * BRICK; k < std::min((bk + 1) * BRICK, n[2]) && !any; ++k) {
                for (std::int64_t j = bj * BRICK; j < std::min((bj + 1) * BRICK, n[1]); ++j) {
                    const std::uint8_t* row = vis.voxels.data() + source.index(0, j, k);
                    for (std::int64_t i = bi * BRICK; i < std::min((bi + 1) * BRICK, n[0]); ++i) {
                        any |= row[i];
                    }
                }
            }
            vis.bricks[static_cast<std::size_t>(b)] = any;
        },
        64);
    return vis;
}

// Does the trilinear footprint of the rest tet (its box in source grid coordinates, grown by
// 1e-3 voxel for the rounding of the per-voxel map, then by the interpolation's +1 voxel) hold a
// visible voxel? Samples outside the source box are 0, so a box outside it holds none.
bool footprint_visible(const VisibilityIndex& vis, const Volume& source, const Vec3f r[4]) {
    constexpr double GROW = 1e-3;
    std::int64_t lo[3];
    std::int64_t hi[3];
    for (int a = 0; a < 3; ++a) {
        const double o = source.origin()[a];
        const double s = source.spacing()[a];
        const std::int64_t n = source.dims()[static_cast<std::size_t>(a)];
        double mn = std::numeric_limits<double>::infinity();
        double mx = -mn;
        for (int v = 0; v < 4; ++v) {
            const double g = (static_cast<double>(r[v][a]) - o) / s - 0.5;
            mn = std::min(mn, g);
            mx = std::max(mx, g);
        }
        mn -= GROW;
        mx += GROW;
        const double top = static_cast<double>(n) - 0.5;
        if (mx < -0.5 || mn > top) {
            return false;
        }
        lo[a] = static_cast<std::int64_t>(std::clamp(mn, 0.0, static_cast<double>(n - 1)));
        hi[a] = std::min(
            static_cast<std::int64_t>(std::clamp(mx, 0.0, static_cast<double>(n - 1))) + 1, n - 1);
    }
    bool any_brick = false;
    for (std::int64_t bk = lo[2] / BRICK; bk <= hi[2] / BRICK && !any_brick; ++bk) {
        for (std::int64_t bj = lo[1] / BRICK; bj <= hi[1] / BRICK && !any_brick; ++bj) {
            for (std::int64_t bi = lo[0] / BRICK; bi <= hi[0] / BRICK; ++bi) {
                if (vis.bricks[static_cast<std::size_t>(bi + vis.nb[0] * (bj + vis.nb[1] * bk))]) {
                    any_brick = true;
                    break;
                }
            }
        }
    }
    if (!any_brick) {
        return false;
    }
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k) {
        for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
            const std::uint8_t* row = vis.voxels.data() + source.index(0, j, k);
            for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
                if (row[i]) {
                    return true;
                }
            }
        }
    }
    return false;
}

// detail::RestInfo of a kept tet in one byte: orientation + 1 in bits 0–1, is_interior in bit 2.
std::uint8_t encode_rest(const detail::RestInfo& info) {
    return static_cast<std::uint8_t>((info.orientation + 1) | (info.is_interior ? 4 : 0));
}
detail::RestInfo decode_rest(std::uint8_t code) {
    return {static_cast<std::int8_t>((code & 3) - 1), (code & 4) != 0};
}

// The kept tets of each slab of `height` z layers, in increasing tet index order (entries are
// positions in the kept list). The result of resample() does not depend on the slab height
// (each voxel is decided by the same tets in the same order); it trades load balance and cache
// footprint (more, thinner slabs) against tets straddling two slabs (set up twice).
struct Slabs {
    std::int64_t height = 1;
    std::int64_t count = 0;
    std::vector<std::int64_t> begin;  // count + 1 offsets into entries
    std::vector<std::int32_t> entries;
};

// Layers per slab: 16 at 256³ (a tet of a cell of 4 voxels straddles two slabs ~1 time in 5),
// at least 16 slabs for load balance on small grids.
std::int64_t slab_height(std::int64_t nz) {
    return std::clamp<std::int64_t>(nz / 16, 1, 16);
}

// Count → prefix sum → fill over fixed chunks of the kept tets: deterministic, tet order per
// slab. The count pass records each tet's slab range for the fill pass.
Slabs bin_tets(std::span<const std::int32_t> kept, std::span<const geometry::Tet> tets,
               std::span<const Vec3f> positions, const GridFrame& target) {
    Slabs slabs;
    const std::int64_t nz = target.n[2];
    slabs.height = slab_height(nz);
    slabs.count = (nz + slabs.height - 1) / slabs.height;
    const std::int64_t num = static_cast<std::int64_t>(kept.size());
    constexpr std::int64_t GRAIN = 16384;
    const std::int64_t chunk_count = num_chunks(num, GRAIN);
    std::vector<std::int64_t> counts(static_cast<std::size_t>(chunk_count * slabs.count), 0);
    // Per kept tet: first and last slab (last < first when its box holds no layer).
    std::vector<std::array<std::int32_t, 2>> ranges(static_cast<std::size_t>(num));
    parallel_for_chunks(num, GRAIN, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
        std::int64_t* row = counts.data() + c * slabs.count;
        for (std::int64_t t = b; t < e; ++t) {
            const geometry::Tet& tet =
                tets[static_cast<std::size_t>(kept[static_cast<std::size_t>(t)])];
            const Vec3f p[4] = {positions[static_cast<std::size_t>(tet[0])],
                                positions[static_cast<std::size_t>(tet[1])],
                                positions[static_cast<std::size_t>(tet[2])],
                                positions[static_cast<std::size_t>(tet[3])]};
            std::int64_t k0 = 0;
            std::int64_t k1 = -1;
            detail::tet_axis_range(p, target, 2, k0, k1);
            const std::int64_t s0 = k0 / slabs.height;
            const std::int64_t s1 = k0 <= k1 ? k1 / slabs.height : s0 - 1;
            ranges[static_cast<std::size_t>(t)] = {static_cast<std::int32_t>(s0),
                                                   static_cast<std::int32_t>(s1)};
            for (std::int64_t s = s0; s <= s1; ++s) {
                ++row[s];
            }
        }
    });
    // Offsets in (slab, chunk) order: slab-major, so a slab's entries are contiguous and in
    // chunk (= tet) order.
    std::vector<std::int64_t> offsets(counts.size());
    slabs.begin.assign(static_cast<std::size_t>(slabs.count + 1), 0);
    std::int64_t total = 0;
    for (std::int64_t s = 0; s < slabs.count; ++s) {
        slabs.begin[static_cast<std::size_t>(s)] = total;
        for (std::int64_t c = 0; c < chunk_count; ++c) {
            const std::size_t at = static_cast<std::size_t>(c * slabs.count + s);
            offsets[at] = total;
            total += counts[at];
        }
    }
    slabs.begin[static_cast<std::size_t>(slabs.count)] = total;
    slabs.entries.resize(static_cast<std::size_t>(total));
    parallel_for_chunks(num, GRAIN, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
        std::int64_t* next = offsets.data() + c * slabs.count;
        for (std::int64_t t = b; t < e; ++t) {
            const auto [s0, s1] = ranges[static_cast<std::size_t>(t)];
            for (std::int64_t s = s0; s <= s1; ++s) {
                slabs.entries[static_cast<std::size_t>(next[s]++)] = static_cast<std::int32_t>(t);
            }
        }
    });
    return slabs;
}

struct SlabCounts {
    std::int64_t num_degenerate = 0;
    std::int64_t num_inverted = 0;
    std::int64_t num_voxels_written = 0;
};

// Runs, per slab in parallel: zero_slab(k0, k1), then visit_batch(batch) over batches of the
// voxels the tie rule gives the slab's tets inside the slab, in tet order (detail::append_spans).
// Degenerate and inverted tets are counted in the first slab they overlap.
template <typename ZeroSlab, typename VisitBatch>
SlabCounts rasterize(std::span<const std::int32_t> kept, std::span<const std::uint8_t> rest_codes,
                     std::span<const geometry::Tet> tets, std::span<const Vec3f> rest,
                     std::span<const Vec3f> deformed, const GridFrame& target,
                     const GridFrame& source, bool skip_inverted, ZeroSlab&& zero_slab,
                     VisitBatch&& visit_batch) {
    const Slabs slabs = bin_tets(kept, tets, deformed, target);
    const bool use_avx2 = pliant::has_avx2();
    return parallel_reduce(
        slabs.count, SlabCounts{},
        [&](std::int64_t s_begin, std::int64_t s_end) {
            SlabCounts counts;
            // One batch buffer per task (not per tet).
            const auto batch = std::make_unique<detail::SpanBatch>();
            auto flush = [&](const detail::SpanBatch& b) {
                visit_batch(b);
            };
            const std::int64_t nx = target.n[0];
            const std::int64_t nxy = target.n[0] * target.n[1];
            for (std::int64_t s = s_begin; s < s_end; ++s) {
                const std::int64_t k_begin = s * slabs.height;
                const std::int64_t k_end = std::min(k_begin + slabs.height, target.n[2]);
                zero_slab(k_begin, k_end);
                // One set-up tet: counted, rasterized into the slab's batches.
                auto rasterize_tet = [&](const TetRaster& raster, bool ok) {
                    const bool is_first_slab = raster.lo[2] >= k_begin;
                    if (!ok) {
                        counts.num_degenerate += is_first_slab ? 1 : 0;
                        return;
                    }
                    if (raster.is_inverted) {
                        counts.num_inverted += is_first_slab ? 1 : 0;
                        if (skip_inverted) {
                            return;
                        }
                    }
                    if (use_avx2 && detail::avx2_layers_fit(raster)) {
                        std::int64_t k = k_begin;
                        while ((k = detail::append_layers_avx2(raster, k, k_end, nx, nxy, *batch,
                                                               counts.num_voxels_written)) <
                               k_end) {
                            flush(*batch);
                            batch->num_voxels = 0;
                            batch->is_interior = true;
                        }
                    } else {
                        counts.num_voxels_written +=
                            detail::append_spans(raster, k_begin, k_end, nx, nxy, *batch, flush);
                    }
                };
                // The slab's tets in order, 4 set up at a time with AVX2.
                const std::int64_t e_begin = slabs.begin[static_cast<std::size_t>(s)];
                const std::int64_t e_end = slabs.begin[static_cast<std::size_t>(s + 1)];
                std::int64_t e = e_begin;
                if (use_avx2) {
                    for (; e + 4 <= e_end; e += 4) {
                        std::int32_t ids[4][4];
                        detail::RestInfo infos[4];
                        for (int l = 0; l < 4; ++l) {
                            const std::int32_t at = slabs.entries[static_cast<std::size_t>(e + l)];
                            const geometry::Tet& tet =
                                tets[static_cast<std::size_t>(kept[static_cast<std::size_t>(at)])];
                            for (int v = 0; v < 4; ++v) {
                                ids[l][v] = tet[static_cast<std::size_t>(v)];
                            }
                            infos[l] = decode_rest(rest_codes[static_cast<std::size_t>(at)]);
                        }
                        TetRaster rasters[4];
                        const int ok = detail::setup_tets_avx2(deformed.data(), rest.data(), ids,
                                                               infos, target, source, rasters);
                        for (int l = 0; l < 4; ++l) {
                            rasterize_tet(rasters[l], ((ok >> l) & 1) != 0);
                        }
                    }
                }
                for (; e < e_end; ++e) {
                    const std::int32_t at = slabs.entries[static_cast<std::size_t>(e)];
                    const std::int32_t t = kept[static_cast<std::size_t>(at)];
                    const geometry::Tet& tet = tets[static_cast<std::size_t>(t)];
                    Vec3f p[4];
                    Vec3f r[4];
                    for (int v = 0; v < 4; ++v) {
                        p[v] = deformed[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
                        r[v] = rest[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
                    }
                    TetRaster raster;
                    const bool ok = detail::setup_tet(
                        p, tet.data(), r, decode_rest(rest_codes[static_cast<std::size_t>(at)]),
                        target, source, raster);
                    rasterize_tet(raster, ok);
                }
                if (batch->num_voxels > 0) {
                    flush(*batch);
                }
                batch->num_voxels = 0;
                batch->is_interior = true;
            }
            return counts;
        },
        [](SlabCounts a, const SlabCounts& b) {
            a.num_degenerate += b.num_degenerate;
            a.num_inverted += b.num_inverted;
            a.num_voxels_written += b.num_voxels_written;
            return a;
        },
        1);
}

// Samples of a row: g = map·(i, j, k), trilinear from the source, converted and stored.
template <typename S, int C, typename D>
SlabCounts resample_typed(std::span<const std::int32_t> kept,
                          std::span<const std::uint8_t> rest_codes,
                          std::span<const geometry::Tet> tets, std::span<const Vec3f> rest,
                          std::span<const Vec3f> deformed, const Volume& source, Volume& target,
                          bool skip_inverted) {
    const GridFrame tf = frame_of(target);
    const GridFrame sf = frame_of(source);
    const S* src = reinterpret_cast<const S*>(source.bytes().data());
    D* dst = reinterpret_cast<D*>(target.bytes().data());
    const float scale = std::is_floating_point_v<D> && std::is_same_v<S, std::uint8_t> && C == 4
                            ? 1.0f / 255.0f
                            : 1.0f;
    const std::int64_t layer = tf.n[0] * tf.n[1] * C;
    auto zero_slab = [&](std::int64_t k0, std::int64_t k1) {
        std::memset(dst + k0 * layer, 0, static_cast<std::size_t>((k1 - k0) * layer) * sizeof(D));
    };
    // f32 → f32 and rgba8 → rgba8 / rgba32f: 4 voxels at a time with AVX2 when the CPU has it
    // (the same bits).
    constexpr bool HAS_AVX2_KERNEL =
        (std::is_same_v<S, float> && C == 1 && std::is_same_v<D, float>) ||
        (std::is_same_v<S, std::uint8_t> && C == 4 &&
         (std::is_same_v<D, std::uint8_t> || std::is_same_v<D, float>));
    const bool use_avx2 = HAS_AVX2_KERNEL && pliant::has_avx2() &&
                          source.num_voxels() <= std::numeric_limits<std::int32_t>::max();
    // One loop over the batch.
    auto visit_batch = [&](const detail::SpanBatch& batch) {
        int first = 0;
        if constexpr (std::is_same_v<S, float> && C == 1 && std::is_same_v<D, float>) {
            if (use_avx2) {
                first = detail::sample_f32_avx2(src, sf.n, batch, scale, dst);
            }
        } else if constexpr (HAS_AVX2_KERNEL) {
            if (use_avx2) {
                first = detail::sample_rgba8_avx2(src, sf.n, batch, scale, dst);
            }
        }
        // The interior sampler gives the same bits as sample_trilinear, without its bounds
        // tests and clamps.
        if (batch.is_interior) {
            for (int e = first; e < batch.num_voxels; ++e) {
                float sample[C];
                detail::sample_interior<S, C>(src, sf.n, batch.g[0][e], batch.g[1][e],
                                              batch.g[2][e], sample);
                D* out = dst + C * batch.index[e];
                for (int c = 0; c < C; ++c) {
                    out[c] = detail::convert_sample<D>(sample[c], scale);
                }
            }
        } else {
            for (int e = first; e < batch.num_voxels; ++e) {
                float sample[C];
                detail::sample_trilinear<S, C>(src, sf.n, batch.g[0][e], batch.g[1][e],
                                               batch.g[2][e], sample);
                D* out = dst + C * batch.index[e];
                for (int c = 0; c < C; ++c) {
                    out[c] = detail::convert_sample<D>(sample[c], scale);
                }
            }
        }
    };
    return rasterize(kept, rest_codes, tets, rest, deformed, tf, sf, skip_inverted, zero_slab,
                     visit_batch);
}

void check_positions(std::span<const Vec3f> positions, const char* what) {
    const std::int64_t bad = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), std::int64_t{-1},
        [&](std::int64_t b, std::int64_t e) {
            for (std::int64_t v = b; v < e; ++v) {
                if (!is_finite(positions[static_cast<std::size_t>(v)])) {
                    return v;
                }
            }
            return std::int64_t{-1};
        },
        [](std::int64_t a, std::int64_t b) { return a >= 0 ? a : b; });
    if (bad >= 0) {
        const Vec3f& p = positions[static_cast<std::size_t>(bad)];
        throw InvalidInput(fmt::format("volume::Resampler: {}[{}] = ({}, {}, {}) is not finite",
                                       what, bad, p.x, p.y, p.z));
    }
}

}  // namespace

bool can_resample_into(VoxelType source, VoxelType target) {
    if (source == target) {
        return true;
    }
    switch (source) {
        case VoxelType::u8:
        case VoxelType::i16:
        case VoxelType::u16:
            return target == VoxelType::f32;
        case VoxelType::rgba8:
            return target == VoxelType::rgba32f;
        case VoxelType::f32:
        case VoxelType::rgba32f:
            return false;
    }
    return false;
}

Resampler::Resampler(const Volume& source, std::span<const geometry::Tet> tets,
                     std::span<const Vec3f> rest_positions, const ResampleOptions& options)
    : m_source(&source), m_tets(tets), m_rest(rest_positions), m_options(options) {
    if (source.empty()) {
        throw InvalidInput("volume::Resampler: the source volume is empty");
    }
    const std::int64_t num_vertices = static_cast<std::int64_t>(rest_positions.size());
    if (num_vertices > std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput(fmt::format(
            "volume::Resampler: rest_positions.size() ({}) exceeds the 2^31 - 1 tets can index",
            num_vertices));
    }
    if (static_cast<std::int64_t>(tets.size()) > std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput(
            fmt::format("volume::Resampler: tets.size() ({}) exceeds 2^31 - 1", tets.size()));
    }
    const std::int64_t num_tets = static_cast<std::int64_t>(tets.size());
    const std::int64_t bad_tet = parallel_reduce(
        num_tets, std::int64_t{-1},
        [&](std::int64_t b, std::int64_t e) {
            for (std::int64_t t = b; t < e; ++t) {
                for (const std::int32_t v : tets[static_cast<std::size_t>(t)]) {
                    if (v < 0 || v >= num_vertices) {
                        return t;
                    }
                }
            }
            return std::int64_t{-1};
        },
        [](std::int64_t a, std::int64_t b) { return a >= 0 ? a : b; });
    if (bad_tet >= 0) {
        const geometry::Tet& t = tets[static_cast<std::size_t>(bad_tet)];
        throw InvalidInput(fmt::format(
            "volume::Resampler: tets[{}] = ({}, {}, {}, {}) has an index outside [0, {}) "
            "(rest_positions.size())",
            bad_tet, t[0], t[1], t[2], t[3], num_vertices));
    }
    check_positions(rest_positions, "rest_positions");
    if (options.tf != nullptr && channels(source.type()) == 1) {
        options.tf->validate();
    }

    // Tets whose rest footprint holds a visible voxel, in index order.
    const VisibilityIndex vis = build_visibility(source, options.tf);
    std::vector<std::uint8_t> keep(static_cast<std::size_t>(num_tets));
    parallel_for(
        num_tets,
        [&](std::int64_t t) {
            const geometry::Tet& tet = tets[static_cast<std::size_t>(t)];
            const Vec3f r[4] = {rest_positions[static_cast<std::size_t>(tet[0])],
                                rest_positions[static_cast<std::size_t>(tet[1])],
                                rest_positions[static_cast<std::size_t>(tet[2])],
                                rest_positions[static_cast<std::size_t>(tet[3])]};
            keep[static_cast<std::size_t>(t)] = footprint_visible(vis, source, r) ? 1 : 0;
        },
        1024);
    for (std::int64_t t = 0; t < num_tets; ++t) {
        if (keep[static_cast<std::size_t>(t)]) {
            m_kept.push_back(static_cast<std::int32_t>(t));
        }
    }
    // What every frame's setup needs of the rest tets (orientation, samples in the interior).
    const GridFrame sf = frame_of(source);
    m_rest_codes.resize(m_kept.size());
    parallel_for(
        static_cast<std::int64_t>(m_kept.size()),
        [&](std::int64_t at) {
            const geometry::Tet& tet =
                tets[static_cast<std::size_t>(m_kept[static_cast<std::size_t>(at)])];
            const Vec3f r[4] = {rest_positions[static_cast<std::size_t>(tet[0])],
                                rest_positions[static_cast<std::size_t>(tet[1])],
                                rest_positions[static_cast<std::size_t>(tet[2])],
                                rest_positions[static_cast<std::size_t>(tet[3])]};
            m_rest_codes[static_cast<std::size_t>(at)] = encode_rest(detail::rest_info(r, sf));
        },
        4096);
}

ResampleStats Resampler::resample(std::span<const Vec3f> deformed_positions, Volume& target) const {
    if (deformed_positions.size() != m_rest.size()) {
        throw InvalidInput(
            fmt::format("volume::Resampler::resample: deformed_positions.size() ({}) != "
                        "rest_positions.size() ({})",
                        deformed_positions.size(), m_rest.size()));
    }
    if (target.empty()) {
        throw InvalidInput(
            "volume::Resampler::resample: the target volume is empty (allocate it "
            "with the output grid's dims, spacing and origin)");
    }
    const VoxelType st = m_source->type();
    const VoxelType tt = target.type();
    if (!can_resample_into(st, tt)) {
        throw InvalidInput(fmt::format(
            "volume::Resampler::resample: cannot resample a {} source into a {} target (valid: "
            "the source type, f32 from u8/i16/u16, rgba32f from rgba8)",
            name(st), name(tt)));
    }
    if (&target == m_source) {
        throw InvalidInput("volume::Resampler::resample: target is the source volume");
    }
    check_positions(deformed_positions, "deformed_positions");

    const bool skip = m_options.skip_inverted;
    SlabCounts counts;
    auto run = [&]<typename S, int C, typename D>() {
        counts = resample_typed<S, C, D>(m_kept, m_rest_codes, m_tets, m_rest, deformed_positions,
                                         *m_source, target, skip);
    };
    switch (st) {
        case VoxelType::u8:
            tt == st ? run.operator()<std::uint8_t, 1, std::uint8_t>()
                     : run.operator()<std::uint8_t, 1, float>();
            break;
        case VoxelType::i16:
            tt == st ? run.operator()<std::int16_t, 1, std::int16_t>()
                     : run.operator()<std::int16_t, 1, float>();
            break;
        case VoxelType::u16:
            tt == st ? run.operator()<std::uint16_t, 1, std::uint16_t>()
                     : run.operator()<std::uint16_t, 1, float>();
            break;
        case VoxelType::f32:
            run.operator()<float, 1, float>();
            break;
        case VoxelType::rgba8:
            tt == st ? run.operator()<std::uint8_t, 4, std::uint8_t>()
                     : run.operator()<std::uint8_t, 4, float>();
            break;
        case VoxelType::rgba32f:
            run.operator()<float, 4, float>();
            break;
    }
    ResampleStats stats;
    stats.num_tets = num_tets();
    stats.num_tets_skipped = num_tets() - static_cast<std::int64_t>(m_kept.size());
    stats.num_degenerate = counts.num_degenerate;
    stats.num_inverted = counts.num_inverted;
    stats.num_voxels_written = counts.num_voxels_written;
    return stats;
}

void Resampler::count_coverage(std::span<const Vec3f> deformed_positions, const Volume& grid,
                               std::span<std::uint8_t> counts) const {
    if (deformed_positions.size() != m_rest.size()) {
        throw InvalidInput(
            fmt::format("volume::Resampler::count_coverage: deformed_positions.size() ({}) != "
                        "rest_positions.size() ({})",
                        deformed_positions.size(), m_rest.size()));
    }
    if (grid.num_voxels() <= 0 || static_cast<std::int64_t>(counts.size()) != grid.num_voxels()) {
        throw InvalidInput(fmt::format(
            "volume::Resampler::count_coverage: counts.size() ({}) != grid.num_voxels() ({})",
            counts.size(), grid.num_voxels()));
    }
    check_positions(deformed_positions, "deformed_positions");
    const GridFrame tf = frame_of(grid);
    const std::int64_t layer = tf.n[0] * tf.n[1];
    rasterize(
        m_kept, m_rest_codes, m_tets, m_rest, deformed_positions, tf, frame_of(*m_source),
        m_options.skip_inverted,
        [&](std::int64_t k0, std::int64_t k1) {
            std::memset(counts.data() + k0 * layer, 0, static_cast<std::size_t>((k1 - k0) * layer));
        },
        [&](const detail::SpanBatch& batch) {
            for (int e = 0; e < batch.num_voxels; ++e) {
                std::uint8_t& c = counts[static_cast<std::size_t>(batch.index[e])];
                c = c == 255 ? c : static_cast<std::uint8_t>(c + 1);
            }
        });
}

ResampleStats resample(const Volume& source, std::span<const geometry::Tet> tets,
                       std::span<const Vec3f> rest_positions,
                       std::span<const Vec3f> deformed_positions, Volume& target,
                       const ResampleOptions& options) {
    return Resampler(source, tets, rest_positions, options).resample(deformed_positions, target);
}

}  // namespace pliant::volume
