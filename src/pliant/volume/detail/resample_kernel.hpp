// Per-tet kernels of volume/resample.hpp, GPU-style: functions of trivially copyable data, no
// allocation, no exceptions. Shared by the resampler and the brute-force baseline in
// bench/resample_bench.cpp, so that both decide "voxel centre inside tet" with the same float
// operations in the same order. pliant is compiled with -ffp-contract=off
// (cmake/PliantCodegen.cmake): a contracted a·i + β would round differently in different call
// sites and break the tie rule's consistency between neighbouring tets.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume::detail {

// A grid's placement: voxel (i, j, k) centred at origin + ((i, j, k) + 0.5)·spacing.
struct GridFrame {
    std::int64_t n[3];
    double origin[3];
    double spacing[3];
    double inv_spacing[3];  // 1 / spacing
};

inline GridFrame frame_of(const Volume& v) {
    GridFrame g{};
    for (int a = 0; a < 3; ++a) {
        g.n[a] = v.dims()[static_cast<std::size_t>(a)];
        g.origin[a] = v.origin()[a];
        g.spacing[a] = v.spacing()[a];
        g.inv_spacing[a] = 1.0 / g.spacing[a];
    }
    return g;
}

// One deformed tet prepared for rasterization into a target grid (index space (i, j, k)).
struct TetRaster {
    // Inward face planes: h_f(i, j, k) = plane[f][0]·i + (plane[f][1]·j + (plane[f][2]·k +
    // plane[f][3])), evaluated in exactly this order everywhere (inside()). Face f is opposite
    // the tet's f-th vertex in vertex-index order (no consumer depends on the order of faces).
    double plane[4][4];
    // Tie rule: a centre with h_f = 0 is inside face f when the inward normal is
    // lexicographically positive.
    bool tie_inside[4];
    // Inclusive voxel index box containing every centre the planes can accept, clipped to the
    // grid (empty when lo > hi on an axis).
    std::int64_t lo[3];
    std::int64_t hi[3];
    // Row spans (row_span_fast()): per face, −1/plane[f][0], and the bounds that route its root
    // to the lower (a > 0: cap = +∞, floor = +∞) or the upper end (a < 0: cap = −∞,
    // floor = −∞) of the span without a branch. A face parallel to the rows (a = 0, "flat")
    // accepts a whole row or none of it: it restricts the rows of a layer (flat_rows()), or,
    // parallel to the layers too (a = b = 0), the layers [k_lo, k_hi]; in the span it is
    // neutral (−1/a stored as 0, cap = −∞, floor = +∞). is_fast: every other face's −1/a is
    // finite and non-zero (else row_span() handles the tet).
    double neg_inv_a[4];
    double root_cap[4];
    double root_floor[4];
    bool is_fast;
    std::uint8_t flat_faces;  // bit f: plane[f][0] == 0 and plane[f][1] != 0
    // The layers holding centres: [lo[2], hi[2]] narrowed by the faces with a = b = 0.
    std::int64_t k_lo;
    std::int64_t k_hi;
    // Cross-sections (slice_rows()): per edge, its z range in index space (empty for an edge
    // parallel to the layers), an end (y0, z0) and dy/dz. Entries 6 and 7 pad the arrays for
    // SIMD (empty ranges, never crossed).
    double edge_z_lo[8];
    double edge_z_hi[8];
    double edge_y0[8];
    double edge_z0[8];
    double edge_slope[8];
    // Affine map from target voxel indices to source grid coordinates (voxel centres at integers):
    // g_a = ((map[a][3] + map[a][2]·k) + map[a][1]·j) + map[a][0]·i, in this order (map_coord()).
    double map[3][4];
    bool is_inverted;
    // Every sample of the tet falls at least 1e-3 voxel inside [0, n − 1) on every source axis:
    // no bounds test or clamping needed (sample_interior).
    bool is_interior;
};
static_assert(std::is_trivially_copyable_v<TetRaster>);

// floor and ceil of a finite x with |x| < 2^62, inline (with baseline SSE2, the standard
// floor and ceil are calls into libm).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE std::int64_t floor_to_int(double x) {
    const auto t = static_cast<std::int64_t>(x);
    return t - (static_cast<double>(t) > x ? 1 : 0);
}
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE std::int64_t ceil_to_int(double x) {
    const auto t = static_cast<std::int64_t>(x);
    return t + (static_cast<double>(t) < x ? 1 : 0);
}

// Index-space coordinate of world coordinate x on axis a (voxel centres at integers).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE double index_coord(double x, const GridFrame& g, int a) {
    return (x - g.origin[a]) * g.inv_spacing[a] - 0.5;
}

// Inclusive range [lo, hi] of voxel indices of axis a within the index-space interval [mn, mx],
// grown by 1e-6 voxel (far more than the face planes' rounding), clipped to [0, n − 1]; lo > hi
// when empty. The bounding box of setup_tet and the slab binning both use this.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void axis_range(double mn, double mx, const GridFrame& g,
                                                       int a, std::int64_t& lo, std::int64_t& hi) {
    constexpr double GROW = 1e-6;
    const double top = static_cast<double>(g.n[a]);
    lo = std::max<std::int64_t>(ceil_to_int(std::clamp(mn - GROW, -1.0, top)), 0);
    hi = std::min<std::int64_t>(floor_to_int(std::clamp(mx + GROW, -1.0, top)), g.n[a] - 1);
}

// The voxel index range of the tet with vertices p along axis a.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void tet_axis_range(const Vec3f p[4], const GridFrame& g,
                                                           int a, std::int64_t& lo,
                                                           std::int64_t& hi) {
    const double mn =
        std::min(std::min<double>(p[0][a], p[1][a]), std::min<double>(p[2][a], p[3][a]));
    const double mx =
        std::max(std::max<double>(p[0][a], p[1][a]), std::max<double>(p[2][a], p[3][a]));
    axis_range(index_coord(mn, g, a), index_coord(mx, g, a), g, a, lo, hi);
}

// The tie-rule inside test of one face at voxel (i, j, k), given β = h_f(0, j, k).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE bool face_accepts(double a, double beta, bool tie,
                                                         std::int64_t i) {
    const double h = a * static_cast<double>(i) + beta;
    return h > 0.0 || (h == 0.0 && tie);
}

// Narrows [lo, end) to the integers x with accepts(x), where accepts is monotone: true on a
// suffix (is_increasing) or a prefix. guess approximates the boundary (any value, NaN too); the
// exact test corrects it, stepping from the guess.
template <typename Accepts>
PLIANT_HOST_DEVICE inline void narrow_monotone(std::int64_t& lo, std::int64_t& end,
                                               bool is_increasing, double guess,
                                               Accepts&& accepts) {
    if (lo >= end) {
        return;
    }
    const double r = guess == guess ? std::clamp(guess, static_cast<double>(lo) - 1.0,
                                                 static_cast<double>(end) + 1.0)
                                    : static_cast<double>(lo);
    if (is_increasing) {
        std::int64_t c = std::clamp(ceil_to_int(r), lo, end);
        while (c > lo && accepts(c - 1)) {
            --c;
        }
        while (c < end && !accepts(c)) {
            ++c;
        }
        lo = c;
    } else {
        std::int64_t c = std::clamp(floor_to_int(r) + 1, lo, end);
        while (c < end && accepts(c)) {
            ++c;
        }
        while (c > lo && !accepts(c - 1)) {
            --c;
        }
        end = c;
    }
}

// Narrows [t.k_lo, t.k_hi] to the layers face q accepts, for a face with a = b = 0: on it
// h = ±0 + (±0 + γ(k)), γ = c·k + d as face_beta computes it, monotone in k.
PLIANT_HOST_DEVICE inline void narrow_flat_layers(TetRaster& t, int q) {
    const double* plane = t.plane[q];
    const bool tie = t.tie_inside[q];
    std::int64_t k_end = t.k_hi + 1;
    narrow_monotone(t.k_lo, k_end, plane[2] > 0.0, -plane[3] / plane[2], [&](std::int64_t k) {
        return face_accepts(0.0, plane[2] * static_cast<double>(k) + plane[3], tie, 0);
    });
    t.k_hi = k_end - 1;
}

// What setup_tet needs of the rest tet, which does not change between frames (the Resampler
// computes it once per kept tet): the sign of its orientation (−1, 0, 1) and whether every
// sample falls at least 1e-3 voxel inside [0, n − 1) of the source on every axis.
struct RestInfo {
    std::int8_t orientation;
    bool is_interior;
};

PLIANT_HOST_DEVICE inline RestInfo rest_info(const Vec3f r[4], const GridFrame& source) {
    Vec3d rd[4];
    for (int v = 0; v < 4; ++v) {
        rd[v] = vec3_cast<double>(r[v]);
    }
    const Vec3d f[3] = {rd[0] - rd[3], rd[1] - rd[3], rd[2] - rd[3]};
    const double rest_det = dot(f[0], cross(f[1], f[2]));
    RestInfo info{};
    info.orientation = static_cast<std::int8_t>(rest_det > 0.0 ? 1 : (rest_det < 0.0 ? -1 : 0));
    // The samples lie in the rest tet (up to the map's rounding, far below the margin).
    constexpr double MARGIN = 1e-3;
    info.is_interior = true;
    for (int a = 0; a < 3; ++a) {
        const double g0 = index_coord(rd[0][a], source, a);
        const double g1 = index_coord(rd[1][a], source, a);
        const double g2 = index_coord(rd[2][a], source, a);
        const double g3 = index_coord(rd[3][a], source, a);
        const double mn = std::min(std::min(g0, g1), std::min(g2, g3));
        const double mx = std::max(std::max(g0, g1), std::max(g2, g3));
        info.is_interior =
            info.is_interior && mn >= MARGIN && mx <= static_cast<double>(source.n[a] - 1) - MARGIN;
    }
    return info;
}

// Sets out.lo/hi (always) and the rest of out (when it returns true). False for a degenerate
// tet: zero or non-finite determinant, a face with zero normal, or a vertex on its opposite
// face's plane as computed. p: deformed vertices, ids: their vertex indices (the canonical face
// order), r: rest vertices, rest: rest_info(r, source); target: the output grid; source: the
// sampled grid.
PLIANT_HOST_DEVICE inline bool setup_tet(const Vec3f p[4], const std::int32_t ids[4],
                                         const Vec3f r[4], RestInfo rest, const GridFrame& target,
                                         const GridFrame& source, TetRaster& out) {
    Vec3d pd[4];
    for (int v = 0; v < 4; ++v) {
        pd[v] = vec3_cast<double>(p[v]);
    }
    double vertex[4][3];
    for (int v = 0; v < 4; ++v) {
        for (int a = 0; a < 3; ++a) {
            vertex[v][a] = index_coord(pd[v][a], target, a);
        }
    }
    // The box: index_coord is monotone, so this is tet_axis_range() (which bin_tets uses).
    for (int a = 0; a < 3; ++a) {
        const double mn =
            std::min(std::min(vertex[0][a], vertex[1][a]), std::min(vertex[2][a], vertex[3][a]));
        const double mx =
            std::max(std::max(vertex[0][a], vertex[1][a]), std::max(vertex[2][a], vertex[3][a]));
        axis_range(mn, mx, target, a, out.lo[a], out.hi[a]);
    }

    // λ = T⁻¹(x − d), T = [a − d, b − d, c − d]: the rows of T⁻¹ are the cross products of T's
    // columns over det T.
    const Vec3d e0 = pd[0] - pd[3];
    const Vec3d e1 = pd[1] - pd[3];
    const Vec3d e2 = pd[2] - pd[3];
    const Vec3d c12 = cross(e1, e2);
    const double det = dot(e0, c12);
    const double inv_det = 1.0 / det;
    if (!(det != 0.0) || !std::isfinite(inv_det)) {
        return false;
    }
    out.is_inverted = (det > 0.0 && rest.orientation < 0) || (det < 0.0 && rest.orientation > 0);
    out.is_interior = rest.is_interior;

    // Faces: face m is opposite the m-th vertex in vertex-index order. Its plane function is
    // computed from its vertices in that order, so the two tets sharing the face compute the same
    // numbers; the sign σ that makes the opposite vertex positive is applied last (exact).
    const Vec3d c0{target.origin[0] + 0.5 * target.spacing[0],
                   target.origin[1] + 0.5 * target.spacing[1],
                   target.origin[2] + 0.5 * target.spacing[2]};
    // The four vertices sorted by vertex index (a sorting network; the order is data).
    Vec3d sorted[4] = {pd[0], pd[1], pd[2], pd[3]};
    std::int32_t sorted_ids[4] = {ids[0], ids[1], ids[2], ids[3]};
    auto sort2 = [&](int x, int y) {
        const bool swap = sorted_ids[y] < sorted_ids[x];
        const Vec3d vx = sorted[x];
        const Vec3d vy = sorted[y];
        const std::int32_t ix = sorted_ids[x];
        const std::int32_t iy = sorted_ids[y];
        sorted[x] = swap ? vy : vx;
        sorted[y] = swap ? vx : vy;
        sorted_ids[x] = swap ? iy : ix;
        sorted_ids[y] = swap ? ix : iy;
    };
    sort2(0, 1);
    sort2(2, 3);
    sort2(0, 2);
    sort2(1, 3);
    sort2(1, 2);
    constexpr int OTHERS[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    double side_of[4];
    for (int m = 0; m < 4; ++m) {
        const int* others = OTHERS[m];
        const Vec3d& u = sorted[others[0]];
        const Vec3d n = cross(sorted[others[1]] - u, sorted[others[2]] - u);
        const double side = dot(n, sorted[m] - u);
        side_of[m] = side;
        const double sigma = side > 0.0 ? 1.0 : -1.0;
        const Vec3d c = c0 - u;
        const double delta = n.x * c.x + n.y * c.y + n.z * c.z;
        out.plane[m][0] = sigma * (n.x * target.spacing[0]);
        out.plane[m][1] = sigma * (n.y * target.spacing[1]);
        out.plane[m][2] = sigma * (n.z * target.spacing[2]);
        out.plane[m][3] = sigma * delta;
        const Vec3d inward = n * sigma;
        out.tie_inside[m] =
            inward.x != 0.0 ? inward.x > 0.0 : (inward.y != 0.0 ? inward.y > 0.0 : inward.z > 0.0);
    }
    if (!(side_of[0] != 0.0 && side_of[1] != 0.0 && side_of[2] != 0.0 && side_of[3] != 0.0)) {
        return false;
    }

    // Row spans: the root of face q along a row is β·(−1/a); flat faces (a = 0) are neutral in
    // the span and restrict the rows instead.
    constexpr double INF = std::numeric_limits<double>::infinity();
    out.is_fast = true;
    out.flat_faces = 0;
    out.k_lo = out.lo[2];
    out.k_hi = out.hi[2];
    for (int q = 0; q < 4; ++q) {
        const double a = out.plane[q][0];
        const bool is_flat = a == 0.0;
        const double m = is_flat ? 0.0 : -1.0 / a;
        out.neg_inv_a[q] = m;
        out.is_fast = out.is_fast && (is_flat || (std::isfinite(m) && m != 0.0));
        out.root_cap[q] = is_flat ? -INF : (a > 0.0 ? INF : -INF);
        out.root_floor[q] = is_flat ? INF : (a > 0.0 ? INF : -INF);
        if (is_flat && out.plane[q][1] != 0.0) {
            out.flat_faces = static_cast<std::uint8_t>(out.flat_faces | (1 << q));
        } else if (is_flat) {
            narrow_flat_layers(out, q);
        }
    }
    // Cross-sections: the edges in index space.
    constexpr int EDGES[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (int e = 0; e < 6; ++e) {
        const double* va = vertex[EDGES[e][0]];
        const double* vb = vertex[EDGES[e][1]];
        const double dz = vb[2] - va[2];
        // A flat edge (z_lo = z_hi) is left out (empty range): each of its ends also ends a
        // non-flat edge (else all four vertices would share z and the tet would be degenerate).
        const bool is_flat = !(dz != 0.0);
        out.edge_z_lo[e] =
            is_flat ? std::numeric_limits<double>::infinity() : std::min(va[2], vb[2]);
        out.edge_z_hi[e] =
            is_flat ? -std::numeric_limits<double>::infinity() : std::max(va[2], vb[2]);
        out.edge_y0[e] = va[1];
        out.edge_z0[e] = va[2];
        out.edge_slope[e] = is_flat ? 0.0 : (vb[1] - va[1]) / dz;
    }
    for (int e = 6; e < 8; ++e) {
        out.edge_z_lo[e] = std::numeric_limits<double>::infinity();
        out.edge_z_hi[e] = -std::numeric_limits<double>::infinity();
        out.edge_y0[e] = 0.0;
        out.edge_z0[e] = 0.0;
        out.edge_slope[e] = 0.0;
    }

    const Vec3d row[3] = {c12 * inv_det, cross(e2, e0) * inv_det, cross(e0, e1) * inv_det};
    Vec3d rd[4];
    for (int v = 0; v < 4; ++v) {
        rd[v] = vec3_cast<double>(r[v]);
    }
    const Vec3d f[3] = {rd[0] - rd[3], rd[1] - rd[3], rd[2] - rd[3]};
    // rest(x) = r_d + F·T⁻¹(x − d), F = [r_a − r_d, r_b − r_d, r_c − r_d]; M = F·T⁻¹.
    double mm[3][3];
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            mm[a][b] = f[0][a] * row[0][b] + f[1][a] * row[1][b] + f[2][a] * row[2][b];
        }
    }
    // x(i, j, k) = c0 + (i, j, k)·spacing_t;  g = (rest − origin_s) / spacing_s − 0.5.
    const Vec3d x0 = c0 - pd[3];
    for (int a = 0; a < 3; ++a) {
        const double inv_s = source.inv_spacing[a];
        for (int b = 0; b < 3; ++b) {
            out.map[a][b] = mm[a][b] * target.spacing[b] * inv_s;
        }
        const double rest0 = rd[3][a] + (mm[a][0] * x0.x + mm[a][1] * x0.y + mm[a][2] * x0.z);
        out.map[a][3] = (rest0 - source.origin[a]) * inv_s - 0.5;
    }
    return true;
}

// setup_tet computing the rest information itself (for one-off uses: the brute force).
PLIANT_HOST_DEVICE inline bool setup_tet(const Vec3f p[4], const std::int32_t ids[4],
                                         const Vec3f r[4], const GridFrame& target,
                                         const GridFrame& source, TetRaster& out) {
    return setup_tet(p, ids, r, rest_info(r, source), target, source, out);
}

// Source grid coordinate of target voxel (i, j, k) on the axis of map row m, in the order
// every caller uses (per layer, then per row, then per voxel).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE double map_coord(const double m[4], std::int64_t i,
                                                        std::int64_t j, std::int64_t k) {
    return ((m[3] + m[2] * static_cast<double>(k)) + m[1] * static_cast<double>(j)) +
           m[0] * static_cast<double>(i);
}

// The rows [j_begin, j_end) of a cross-section whose y extent is [y_min, y_max] (empty when not
// y_min ≤ y_max), grown by 1e-6 voxel like the bounding box, within [lo, hi].
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void rows_of_extent(const TetRaster& t, double y_min,
                                                           double y_max, std::int64_t& j_begin,
                                                           std::int64_t& j_end) {
    constexpr double GROW = 1e-6;
    if (!(y_min <= y_max)) {
        j_begin = j_end = 0;
        return;
    }
    const double lo = static_cast<double>(t.lo[1]);
    const double hi = static_cast<double>(t.hi[1]);
    j_begin = std::max(t.lo[1], ceil_to_int(std::clamp(y_min - GROW, lo - 1.0, hi + 1.0)));
    j_end = std::min(t.hi[1], floor_to_int(std::clamp(y_max + GROW, lo - 1.0, hi + 1.0))) + 1;
}

// The rows [j_begin, j_end) of layer k that can hold centres inside the tet: the y extent of the
// tet's cross-section with the plane of the layer (from its edges' crossings, each edge's z
// clamped to its range), grown by 1e-6 voxel like the bounding box, within [lo, hi].
// Conservative: row_span() decides the voxels; this only skips rows that cannot hold any.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void slice_rows(const TetRaster& t, std::int64_t k,
                                                       std::int64_t& j_begin, std::int64_t& j_end) {
    constexpr double GROW = 1e-6;
    const double z = static_cast<double>(k);
    double y_min = std::numeric_limits<double>::infinity();
    double y_max = -y_min;
    for (int e = 0; e < 6; ++e) {
        const bool is_crossed = z >= t.edge_z_lo[e] - GROW && z <= t.edge_z_hi[e] + GROW;
        const double zc = std::min(std::max(z, t.edge_z_lo[e]), t.edge_z_hi[e]);
        const double y = t.edge_y0[e] + (zc - t.edge_z0[e]) * t.edge_slope[e];
        y_min = is_crossed ? std::min(y_min, y) : y_min;
        y_max = is_crossed ? std::max(y_max, y) : y_max;
    }
    rows_of_extent(t, y_min, y_max, j_begin, j_end);
}

PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE double face_beta(const double plane[4], std::int64_t j,
                                                        std::int64_t k) {
    return plane[1] * static_cast<double>(j) + (plane[2] * static_cast<double>(k) + plane[3]);
}

// Voxel centre (i, j, k) inside the tet under the tie rule (the brute-force form).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE bool inside(const TetRaster& t, std::int64_t i,
                                                   std::int64_t j, std::int64_t k) {
    for (int q = 0; q < 4; ++q) {
        if (!face_accepts(t.plane[q][0], face_beta(t.plane[q], j, k), t.tie_inside[q], i)) {
            return false;
        }
    }
    return true;
}

// Narrows the rows [j_begin, j_end) of layer k to those the tet's flat faces (a = 0, b ≠ 0)
// accept. On such a face h_f(i, j, k) = a·i + β(j) is ±0 + β(j) for every i, so it accepts a
// whole row or none of it; β(j) = b·j + γ (face_beta's order) is monotone in j also after
// rounding, so the accepted rows are a suffix (b > 0) or a prefix (b < 0). The boundary −γ/b is
// only a first guess, corrected by the exact test: the result is exactly the rows inside()
// accepts on these faces. (Faces with a = b = 0 accept whole layers: setup_tet narrows
// [k_lo, k_hi] the same way.)
PLIANT_HOST_DEVICE inline void flat_rows(const TetRaster& t, std::int64_t k, std::int64_t& j_begin,
                                         std::int64_t& j_end) {
    const double kd = static_cast<double>(k);
    for (int q = 0; q < 4; ++q) {
        if (((t.flat_faces >> q) & 1) == 0) {
            continue;
        }
        const double* plane = t.plane[q];
        const double gamma = plane[2] * kd + plane[3];
        const double b = plane[1];
        const bool tie = t.tie_inside[q];
        narrow_monotone(j_begin, j_end, b > 0.0, -gamma / b, [&](std::int64_t j) {
            return face_accepts(plane[0], b * static_cast<double>(j) + gamma, tie, 0);
        });
    }
}

// The voxels [begin, end) of row (j, k) inside the tet: exactly the voxels of [lo, hi] that
// inside() accepts, without evaluating it at every voxel. h_f is monotone in i, also after
// rounding, so a face with a > 0 accepts a suffix of the row and one with a < 0 a prefix. The
// computed root r = −β/a differs from where the computed h_f changes sign by at most 2 ulps of
// |r| (≤ 5e-7 voxel for |r| < 2^31; roots are clamped to [lo − ½, hi + ½]), so with
// x_lo = max of the suffix roots and x_hi = min of the prefix roots, every i in
// [x_lo + TOL, x_hi − TOL] is inside and every i outside [x_lo − TOL, x_hi + TOL] is not. Only
// an integer within TOL of x_lo or x_hi (a centre on or within rounding of a face: the ties)
// is decided by inside() itself.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void row_span(const TetRaster& t, std::int64_t j,
                                                     std::int64_t k, std::int64_t& begin,
                                                     std::int64_t& end) {
    constexpr double TOL = 1e-6;
    const double r_lo = static_cast<double>(t.lo[0]) - 0.5;
    const double r_hi = static_cast<double>(t.hi[0]) + 0.5;
    double x_lo = r_lo;
    double x_hi = r_hi;
    bool is_empty = false;
    for (int q = 0; q < 4; ++q) {
        const double a = t.plane[q][0];
        const double beta = face_beta(t.plane[q], j, k);
        if (a > 0.0) {
            x_lo = std::max(x_lo, std::clamp(-beta / a, r_lo, r_hi));
        } else if (a < 0.0) {
            x_hi = std::min(x_hi, std::clamp(-beta / a, r_lo, r_hi));
        } else {
            is_empty = is_empty || !(beta > 0.0 || (beta == 0.0 && t.tie_inside[q]));
        }
    }
    if (is_empty || x_lo > x_hi + TOL) {
        begin = end = t.lo[0];
        return;
    }
    std::int64_t b = ceil_to_int(x_lo - TOL);
    if (static_cast<double>(b) < x_lo + TOL && !inside(t, b, j, k)) {
        ++b;
    }
    std::int64_t e = floor_to_int(x_hi + TOL);
    if (static_cast<double>(e) > x_hi - TOL && !inside(t, e, j, k)) {
        --e;
    }
    begin = std::max(b, t.lo[0]);
    end = std::max(begin, std::min(e, t.hi[0]) + 1);
}

// row_span() for a tet with is_fast, given the layer's gamma[q] = plane[q][2]·k + plane[q][3],
// on a row that its flat faces accept (flat_rows()): the same voxels. The roots are β·(−1/a)
// instead of −β/a (one more rounding: within 3 ulps of |r| of where the computed h_f changes sign,
// still ≤ 7e-7 voxel for |r| < 2^31), routed to the lower or upper end by min/max with the per-face
// caps and floors instead of branches.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void row_span_fast(const TetRaster& t, const double gamma[4],
                                                          std::int64_t j, std::int64_t k,
                                                          std::int64_t& begin, std::int64_t& end) {
    constexpr double TOL = 1e-6;
    const double r_lo = static_cast<double>(t.lo[0]) - 0.5;
    const double r_hi = static_cast<double>(t.hi[0]) + 0.5;
    const double jd = static_cast<double>(j);
    double x_lo = r_lo;
    double x_hi = r_hi;
    for (int q = 0; q < 4; ++q) {
        const double beta = t.plane[q][1] * jd + gamma[q];
        const double root = beta * t.neg_inv_a[q];
        x_lo = std::max(x_lo, std::min(root, t.root_cap[q]));
        x_hi = std::min(x_hi, std::max(root, t.root_floor[q]));
    }
    // No early exit for an empty row (a quarter of the rows: a branch it would mispredict):
    // the bounds are only kept within a voxel of the box, which keeps the conversions in range
    // and leaves an empty row empty (b > e, no centre within TOL of a bound).
    x_lo = std::min(x_lo, r_hi + 1.0);
    x_hi = std::max(x_hi, r_lo - 1.0);
    std::int64_t b = ceil_to_int(x_lo - TOL);
    if (static_cast<double>(b) < x_lo + TOL && !inside(t, b, j, k)) {
        ++b;
    }
    std::int64_t e = floor_to_int(x_hi + TOL);
    if (static_cast<double>(e) > x_hi - TOL && !inside(t, e, j, k)) {
        --e;
    }
    begin = std::max(b, t.lo[0]);
    end = std::max(begin, std::min(e, t.hi[0]) + 1);
}

// A batch of voxels to sample, in the order they are written (tet order, then layer, row, i):
// per voxel its source grid coordinate per axis and its linear index in the target. Filled
// across tets by append_spans(), so that sampling is one flat loop over independent voxels (a
// row of a tet holds ~1.3 voxels with cells of 4 voxels: a loop per row would have an
// unpredictable trip count).
struct SpanBatch {
    static constexpr int CAPACITY = 512;
    // A row is written SLACK voxels at a time, whatever its length (branch-free).
    static constexpr int SLACK = 4;
    int num_voxels = 0;
    // Every voxel's tet has is_interior (its samples need no bounds test).
    bool is_interior = true;
    alignas(32) double g[3][CAPACITY + SLACK];
    alignas(32) std::int64_t index[CAPACITY + SLACK];
};

// Appends the voxels of the tet in layers [k_begin, k_end) (clipped to its box) to the batch,
// layer by layer, rows increasing, i increasing: exactly the voxels inside() accepts. When the
// batch is full it is passed to flush(batch), which must consume it (the batch is reset after
// the call); the caller flushes what is left at the end. Source coordinates are
// ((map[a][3] + map[a][2]·k) + map[a][1]·j) + map[a][0]·i, map_coord()'s order. nx, nxy: target
// row and layer sizes. Returns the number of voxels appended.
template <typename Flush>
PLIANT_FORCE_INLINE std::int64_t append_spans(const TetRaster& t, std::int64_t k_begin,
                                              std::int64_t k_end, std::int64_t nx, std::int64_t nxy,
                                              SpanBatch& batch, Flush&& flush) {
    std::int64_t num_voxels = 0;
    auto drain = [&] {
        if (batch.num_voxels > 0) {
            flush(static_cast<const SpanBatch&>(batch));
        }
        batch.num_voxels = 0;
        batch.is_interior = true;
    };
    const double m0 = t.map[0][0];
    const double m1 = t.map[1][0];
    const double m2 = t.map[2][0];
    // The voxels [ib, ie) of a row whose coordinates at i = 0 are g0, g1, g2.
    auto emit_row = [&](double g0, double g1, double g2, std::int64_t base, std::int64_t ib,
                        std::int64_t ie) {
        if (batch.num_voxels > SpanBatch::CAPACITY - SpanBatch::SLACK) {
            drain();
        }
        batch.is_interior = batch.is_interior && t.is_interior;
        // SLACK entries unconditionally, then the rest of a longer row (rare).
        const int at = batch.num_voxels;
        for (int w = 0; w < SpanBatch::SLACK; ++w) {
            const double id = static_cast<double>(ib + w);
            batch.g[0][at + w] = g0 + m0 * id;
            batch.g[1][at + w] = g1 + m1 * id;
            batch.g[2][at + w] = g2 + m2 * id;
            batch.index[at + w] = base + ib + w;
        }
        const std::int64_t n = ie - ib;
        num_voxels += n;
        if (n <= SpanBatch::SLACK) {
            batch.num_voxels += static_cast<int>(n);
            return;
        }
        batch.num_voxels += SpanBatch::SLACK;
        for (std::int64_t i = ib + SpanBatch::SLACK; i < ie; ++i) {
            if (batch.num_voxels == SpanBatch::CAPACITY) {
                drain();
                batch.is_interior = t.is_interior;
            }
            const double id = static_cast<double>(i);
            const int v = batch.num_voxels++;
            batch.g[0][v] = g0 + m0 * id;
            batch.g[1][v] = g1 + m1 * id;
            batch.g[2][v] = g2 + m2 * id;
            batch.index[v] = base + i;
        }
    };
    const std::int64_t k0 = std::max(t.k_lo, k_begin);
    const std::int64_t k1 = std::min(t.k_hi + 1, k_end);
    for (std::int64_t k = k0; k < k1; ++k) {
        std::int64_t j0 = 0;
        std::int64_t j1 = 0;
        slice_rows(t, k, j0, j1);
        if (t.is_fast && t.flat_faces != 0) {
            flat_rows(t, k, j0, j1);
        }
        const double kd = static_cast<double>(k);
        const double gk0 = t.map[0][3] + t.map[0][2] * kd;
        const double gk1 = t.map[1][3] + t.map[1][2] * kd;
        const double gk2 = t.map[2][3] + t.map[2][2] * kd;
        const std::int64_t layer_base = k * nxy;
        const double gamma[4] = {
            t.plane[0][2] * kd + t.plane[0][3], t.plane[1][2] * kd + t.plane[1][3],
            t.plane[2][2] * kd + t.plane[2][3], t.plane[3][2] * kd + t.plane[3][3]};
        for (std::int64_t j = j0; j < j1; ++j) {
            std::int64_t ib = 0;
            std::int64_t ie = 0;
            if (t.is_fast) {
                row_span_fast(t, gamma, j, k, ib, ie);
            } else {
                row_span(t, j, k, ib, ie);
            }
            const double jd = static_cast<double>(j);
            emit_row(gk0 + t.map[0][1] * jd, gk1 + t.map[1][1] * jd, gk2 + t.map[2][1] * jd,
                     layer_base + j * nx, ib, ie);
        }
    }
    return num_voxels;
}

// u + f·(v − u) nested along x, y, z over 8 corner values (x fastest): the trilinear
// interpolation in the order of operations of the AVX2 samplers.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE float trilinear(const float v[8], float fx, float fy,
                                                       float fz) {
    const float v00 = v[0] + fx * (v[1] - v[0]);
    const float v10 = v[2] + fx * (v[3] - v[2]);
    const float v01 = v[4] + fx * (v[5] - v[4]);
    const float v11 = v[6] + fx * (v[7] - v[6]);
    const float v0 = v00 + fy * (v10 - v00);
    const float v1 = v01 + fy * (v11 - v01);
    return v0 + fz * (v1 - v0);
}

// The trilinear interpolation of the 8 voxels at p, p + ox, p + oy, … (C channels of type S
// each) with fractions fx, fy, fz.
// Scalars (C = 1): the value. RGBA (C = 4, straight colour and opacity): opacity-weighted colour
// interpolation (Wittenbrink, Malzbender & Goss 1998, "Opacity-weighted color interpolation for
// volume sampling"): α = Σ w_k α_k and colour = Σ w_k α_k c_k / α, i.e. the premultiplied colour
// the ray caster interpolates (render/raycast.hpp), stored straight; where α = 0 (no corner with
// opacity weighs) the plain interpolation of the corners' colours, so that a sample at a voxel
// centre is that voxel, transparent or not. A plain interpolation of straight colours everywhere
// would pull transparent voxels' colour into the visible ones at every surface. rgba8: the
// corner products α_k c_k are exact in float.
template <typename S, int C>
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void interpolate_corners(const S* p, std::int64_t ox,
                                                                std::int64_t oy, std::int64_t oz,
                                                                float fx, float fy, float fz,
                                                                float out[C]) {
    const std::int64_t at[8] = {0, ox, oy, oy + ox, oz, oz + ox, oz + oy, oz + oy + ox};
    float v[C][8];
    for (int c = 0; c < C; ++c) {
        for (int k = 0; k < 8; ++k) {
            v[c][k] = static_cast<float>(p[at[k] + c]);
        }
    }
    if constexpr (C == 4) {
        const float alpha = trilinear(v[3], fx, fy, fz);
        out[3] = alpha;
        for (int c = 0; c < 3; ++c) {
            if (alpha > 0.0f) {
                float weighted[8];
                for (int k = 0; k < 8; ++k) {
                    weighted[k] = v[c][k] * v[3][k];
                }
                const float sum = trilinear(weighted, fx, fy, fz);
                if constexpr (std::is_integral_v<S>) {
                    out[c] = sum / alpha;
                } else {
                    // Σ w α c / α written as plain + (Σ w α c − plain α) / α: the same value up to
                    // rounding, and exactly the voxel's colour at a voxel centre (float products
                    // are not exact).
                    const float plain = trilinear(v[c], fx, fy, fz);
                    out[c] = plain + (sum - plain * alpha) / alpha;
                }
            } else {
                out[c] = trilinear(v[c], fx, fy, fz);
            }
        }
    } else {
        for (int c = 0; c < C; ++c) {
            out[c] = trilinear(v[c], fx, fy, fz);
        }
    }
}

// Trilinear sample of a source grid (C channels of type S per voxel, x fastest) at grid
// coordinate g (voxel centres at integers; RGBA opacity-weighted, interpolate_corners): 0 outside
// [−0.5, n − 0.5] on any axis (NaN too), clamped to the edge voxels within half a voxel of the box
// faces.
template <typename S, int C>
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void sample_trilinear(const S* data, const std::int64_t n[3],
                                                             double gx, double gy, double gz,
                                                             float out[C]) {
    if (!(gx >= -0.5 && gy >= -0.5 && gz >= -0.5 && gx <= static_cast<double>(n[0]) - 0.5 &&
          gy <= static_cast<double>(n[1]) - 0.5 && gz <= static_cast<double>(n[2]) - 0.5)) {
        for (int c = 0; c < C; ++c) {
            out[c] = 0.0f;
        }
        return;
    }
    gx = std::clamp(gx, 0.0, static_cast<double>(n[0] - 1));
    gy = std::clamp(gy, 0.0, static_cast<double>(n[1] - 1));
    gz = std::clamp(gz, 0.0, static_cast<double>(n[2] - 1));
    const std::int64_t ix = static_cast<std::int64_t>(gx);
    const std::int64_t iy = static_cast<std::int64_t>(gy);
    const std::int64_t iz = static_cast<std::int64_t>(gz);
    const float fx = static_cast<float>(gx - static_cast<double>(ix));
    const float fy = static_cast<float>(gy - static_cast<double>(iy));
    const float fz = static_cast<float>(gz - static_cast<double>(iz));
    const std::int64_t ox = ix < n[0] - 1 ? C : 0;
    const std::int64_t oy = iy < n[1] - 1 ? C * n[0] : 0;
    const std::int64_t oz = iz < n[2] - 1 ? C * n[0] * n[1] : 0;
    interpolate_corners<S, C>(data + C * (ix + n[0] * (iy + n[1] * iz)), ox, oy, oz, fx, fy, fz,
                              out);
}

// sample_trilinear for a coordinate known to lie in [0, n − 1) on every axis (is_interior).
template <typename S, int C>
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void sample_interior(const S* data, const std::int64_t n[3],
                                                            double gx, double gy, double gz,
                                                            float out[C]) {
    const std::int64_t ix = static_cast<std::int64_t>(gx);
    const std::int64_t iy = static_cast<std::int64_t>(gy);
    const std::int64_t iz = static_cast<std::int64_t>(gz);
    const float fx = static_cast<float>(gx - static_cast<double>(ix));
    const float fy = static_cast<float>(gy - static_cast<double>(iy));
    const float fz = static_cast<float>(gz - static_cast<double>(iz));
    const std::int64_t ox = C;
    const std::int64_t oy = C * n[0];
    const std::int64_t oz = C * n[0] * n[1];
    interpolate_corners<S, C>(data + C * (ix + n[0] * (iy + n[1] * iz)), ox, oy, oz, fx, fy, fz,
                              out);
}

// A sample converted to the target's channel type: floats scaled (1/255 from rgba8 to rgba32f,
// else 1), integers rounded to nearest (halves up) and clamped to the type's range.
template <typename D>
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE D convert_sample(float v, float scale) {
    if constexpr (std::is_floating_point_v<D>) {
        return static_cast<D>(v * scale);
    } else {
        constexpr float LO = static_cast<float>(std::numeric_limits<D>::min());
        constexpr float HI = static_cast<float>(std::numeric_limits<D>::max());
        // NaN → LO; shifted to be non-negative so that truncation rounds half up.
        const float c = v > LO ? (v < HI ? v : HI) : LO;
        return static_cast<D>(static_cast<std::int32_t>(c - LO + 0.5f) +
                              static_cast<std::int32_t>(LO));
    }
}

}  // namespace pliant::volume::detail
