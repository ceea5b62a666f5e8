#include "pliant/volume/inverse_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/detail/tet_map_avx2.hpp"
#include "pliant/volume/resample.hpp"

namespace pliant::volume {

namespace {

using detail::GridFrame;

using detail::HeldValue;
using detail::TetMap;

Vec3d grid_coordinate(const Vec3f& x, const GridFrame& f) {
    return {(x.x - f.origin[0]) * f.inv_spacing[0] - 0.5,
            (x.y - f.origin[1]) * f.inv_spacing[1] - 0.5,
            (x.z - f.origin[2]) * f.inv_spacing[2] - 0.5};
}

// The vertices of a tet from per-vertex grid coordinates (grid_coordinate() of each vertex).
void tet_vertices(const geometry::Tet& tet, std::span<const Vec3d> grid, Vec3d p[4]) {
    for (int v = 0; v < 4; ++v) {
        p[v] = grid[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
    }
}

// The barycentric rows of FRAME_BATCH tets from their deformed vertices (target grid
// coordinates), structure of arrays: p[vertex][axis][lane] in, det[lane] and rows[k][axis][lane]
// out. With ek = pk − p3 and det = e0 · (e1 × e2): rows = (e1 × e2, e2 × e0, e0 × e1) / det, the
// products of core/vec3.hpp's cross() and dot() in their order (no contraction,
// -ffp-contract=off), so that any other place computing a tet's rows this way gets the same
// bits. A tet is degenerate (its rows unused) when det is 0 or not finite.
constexpr int FRAME_BATCH = detail::TET_BATCH;
struct FrameBatch {
    double p[4][3][FRAME_BATCH];
    double det[FRAME_BATCH];
    double rows[3][3][FRAME_BATCH];

    void compute() {
        for (int i = 0; i < FRAME_BATCH; ++i) {
            const double e0x = p[0][0][i] - p[3][0][i], e0y = p[0][1][i] - p[3][1][i],
                         e0z = p[0][2][i] - p[3][2][i];
            const double e1x = p[1][0][i] - p[3][0][i], e1y = p[1][1][i] - p[3][1][i],
                         e1z = p[1][2][i] - p[3][2][i];
            const double e2x = p[2][0][i] - p[3][0][i], e2y = p[2][1][i] - p[3][1][i],
                         e2z = p[2][2][i] - p[3][2][i];
            // cross(e1, e2), cross(e2, e0), cross(e0, e1) as core/vec3.hpp's cross().
            const double c0x = e1y * e2z - e1z * e2y, c0y = e1z * e2x - e1x * e2z,
                         c0z = e1x * e2y - e1y * e2x;
            const double c1x = e2y * e0z - e2z * e0y, c1y = e2z * e0x - e2x * e0z,
                         c1z = e2x * e0y - e2y * e0x;
            const double c2x = e0y * e1z - e0z * e1y, c2y = e0z * e1x - e0x * e1z,
                         c2z = e0x * e1y - e0y * e1x;
            const double d = e0x * c0x + e0y * c0y + e0z * c0z;  // dot(e0, cross(e1, e2))
            const double inv = 1.0 / d;
            det[i] = d;
            rows[0][0][i] = c0x * inv;
            rows[0][1][i] = c0y * inv;
            rows[0][2][i] = c0z * inv;
            rows[1][0][i] = c1x * inv;
            rows[1][1][i] = c1y * inv;
            rows[1][2][i] = c1z * inv;
            rows[2][0][i] = c2x * inv;
            rows[2][1][i] = c2y * inv;
            rows[2][2][i] = c2z * inv;
        }
    }
};

// Lane i of f: the vertices of `tet` in `grid` (its deformed vertices in target grid
// coordinates).
void load_lane(std::span<const Vec3d> grid, const geometry::Tet& tet, int i, FrameBatch& f) {
    for (int v = 0; v < 4; ++v) {
        const Vec3d& x = grid[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
        f.p[v][0][i] = x.x;
        f.p[v][1][i] = x.y;
        f.p[v][2][i] = x.z;
    }
}

// The node range [lo, hi] along axis a that the box of deformed vertices p covers (nodes at
// B·i, clamped to the grid of `nodes` nodes); empty when lo > hi. inv_b: 1 / B when that is exact
// (B a power of two: x · inv_b has the bits of x / B), else 0 (divided).
void node_range(const Vec3d p[4], int a, double b, double inv_b, std::int64_t nodes,
                std::int64_t& lo, std::int64_t& hi) {
    const double mn = std::min({p[0][a], p[1][a], p[2][a], p[3][a]});
    const double mx = std::max({p[0][a], p[1][a], p[2][a], p[3][a]});
    const double lo_nodes = inv_b > 0.0 ? mn * inv_b : mn / b;
    const double hi_nodes = inv_b > 0.0 ? mx * inv_b : mx / b;
    lo = static_cast<std::int64_t>(std::max(0.0, std::ceil(lo_nodes)));
    hi = static_cast<std::int64_t>(std::min(static_cast<double>(nodes - 1), std::floor(hi_nodes)));
}

// Pass (a) of InverseMap::build: raises holder[node] to the index of a tet holding the node (its
// smallest barycentric coordinate ≥ −1e-9, the node inside the tet's box), an atomic maximum, so
// that after every tet has been visited, in any order and on any number of threads, holder[node]
// is the highest index of the tets holding it (−1: none).
constexpr double INSIDE = -1e-9;

struct HoldPass {
    std::span<const geometry::Tet> tets;
    std::span<const Vec3d> deformed_grid;
    std::span<const Vec3d> rest_grid;
    std::int32_t* holder;
    std::array<std::int64_t, 3> nodes;
    double b;
    double inv_b;

    Vec3d node_at(std::int64_t x, std::int64_t y, std::int64_t z) const {
        return {static_cast<double>(x) * b, static_cast<double>(y) * b, static_cast<double>(z) * b};
    }

    // Raises the holder of node (x, y, z) to index; whether it was below (then tet `index` may
    // be the node's holder in the end, and its value at the node is recorded).
    bool raise(std::int64_t x, std::int64_t y, std::int64_t z, std::int32_t index) const {
        std::atomic_ref<std::int32_t> h(holder[x + nodes[0] * (y + nodes[1] * z)]);
        std::int32_t current = h.load(std::memory_order_relaxed);
        while (current < index) {
            if (h.compare_exchange_weak(current, index, std::memory_order_relaxed)) {
                return true;
            }
        }
        return false;
    }

    // Records the value at node (x, y, z) of tet t's map (barycentric coordinates l there), as
    // detail::TetMap::rest() computes it.
    void record(std::int64_t x, std::int64_t y, std::int64_t z, std::int32_t t, const double l[3],
                std::vector<HeldValue>& out) const {
        Vec3d r[4];
        tet_vertices(tets[static_cast<std::size_t>(t)], rest_grid, r);
        TetMap full;
        full.r3 = r[3];
        for (int k = 0; k < 3; ++k) {
            full.dr[k] = r[k] - r[3];
        }
        const Vec3d v = full.rest(l);
        out.push_back(
            {x + nodes[0] * (y + nodes[1] * z),
             t,
             {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}});
    }

    // The node box of deformed vertices p[0..3]; false when empty.
    bool box(const Vec3d p[4], std::int64_t lo[3], std::int64_t hi[3]) const {
        bool is_empty = false;
        for (int a = 0; a < 3; ++a) {
            node_range(p, a, b, inv_b, nodes[static_cast<std::size_t>(a)], lo[a], hi[a]);
            is_empty = is_empty || lo[a] > hi[a];
        }
        return !is_empty;
    }

    // Gathers the deformed vertices of tets [first, first + FRAME_BATCH) into f (lanes past
    // `end` repeat tet `first`: computed, not used) and computes their frames.
    void frames(std::int64_t first, std::int64_t end, FrameBatch& f) const {
        for (int i = 0; i < FRAME_BATCH; ++i) {
            load_lane(deformed_grid,
                      tets[static_cast<std::size_t>(first + i < end ? first + i : first)], i, f);
        }
        f.compute();
    }

    // Lane i of f as a tet: its vertices p and its frame m (m.ok false when degenerate); its det.
    static double lane(const FrameBatch& f, int i, Vec3d p[4], TetMap& m) {
        for (int v = 0; v < 4; ++v) {
            p[v] = Vec3d{f.p[v][0][i], f.p[v][1][i], f.p[v][2][i]};
        }
        const double det = f.det[i];
        m.ok = std::abs(det) > 0.0 && std::isfinite(det);
        for (int k = 0; k < 3; ++k) {
            m.rows[k] = Vec3d{f.rows[k][0][i], f.rows[k][1][i], f.rows[k][2][i]};
        }
        m.p3 = p[3];
        return det;
    }

    // tets_one_by_one() with the boxes and their first nodes' tests 8 tets at a time
    // (detail::box_first_avx2(), the same bits); false (nothing done) without AVX2.
    bool tets_batched(std::int64_t first, std::int64_t end, std::vector<HeldValue>& out) const {
        FrameBatch f;
        frames(first, end, f);
        detail::BoxFirst boxes;
        const std::int64_t n[3] = {nodes[0], nodes[1], nodes[2]};
        if (!detail::box_first_avx2(f.p, f.rows, f.det, b, inv_b, n, boxes)) {
            return false;
        }
        unsigned todo =
            static_cast<unsigned>(boxes.boxes) & ((1u << static_cast<unsigned>(end - first)) - 1u);
        while (todo != 0) {
            const int i = std::countr_zero(todo);
            todo &= todo - 1;
            const auto index = static_cast<std::int32_t>(first + i);
            const std::int64_t lo[3] = {boxes.lo[0][i], boxes.lo[1][i], boxes.lo[2][i]};
            const std::int64_t hi[3] = {boxes.hi[0][i], boxes.hi[1][i], boxes.hi[2][i]};
            if ((boxes.inside >> i & 1) != 0 && raise(lo[0], lo[1], lo[2], index)) {
                const double l[3] = {boxes.l[0][i], boxes.l[1][i], boxes.l[2][i]};
                record(lo[0], lo[1], lo[2], index, l, out);
            }
            if (lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2]) {
                continue;  // one node (most boxes)
            }
            Vec3d p[4];
            TetMap m;
            lane(f, i, p, m);
            for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                    for (std::int64_t x = z == lo[2] && y == lo[1] ? lo[0] + 1 : lo[0]; x <= hi[0];
                         ++x) {
                        double l[3];
                        if (m.lambda(node_at(x, y, z), l) >= INSIDE && raise(x, y, z, index)) {
                            record(x, y, z, index, l, out);
                        }
                    }
                }
            }
        }
        return true;
    }

    // Tets [first, end), end − first ≤ FRAME_BATCH, each over the nodes of its box.
    void tets_one_by_one(std::int64_t first, std::int64_t end, std::vector<HeldValue>& out) const {
        FrameBatch f;
        frames(first, end, f);
        for (int i = 0; i < end - first; ++i) {
            Vec3d p[4];
            TetMap m;
            lane(f, i, p, m);
            std::int64_t lo[3], hi[3];
            if (!m.ok || !box(p, lo, hi)) {
                continue;
            }
            const auto index = static_cast<std::int32_t>(first + i);
            for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                    for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                        double l[3];
                        if (m.lambda(node_at(x, y, z), l) >= INSIDE && raise(x, y, z, index)) {
                            record(x, y, z, index, l, out);
                        }
                    }
                }
            }
        }
    }
};

// The held nodes' maps and the shell (steps 1 (b) and 2 of InverseMap::build), layer by layer,
// over chunks of layers: 2 per thread, 1 on one thread (a chunk also computes the maps of the
// layers on either side of it, so fewer chunks compute fewer maps twice; the map is the same for
// any chunking).
constexpr std::int64_t CHUNKS_PER_THREAD = 2;

struct NodePass {
    std::span<const geometry::Tet> tets;
    std::span<const Vec3d> deformed_grid;  // target grid coordinates
    std::span<const Vec3d> rest_grid;      // source grid coordinates
    const std::int32_t* holder;            // per node, −1: none
    const std::uint8_t* near_xy;           // per node: bit 0, 1 of the dilation, erosion (build())
    std::int32_t* slot;                    // per held node: its index in its layer's list
    float* g;                              // 3 per node: the map's values
    std::int32_t* row_extents;             // 2 per row of nodes (InverseMap::node_row_extents())
    std::array<std::int64_t, 3> nodes;
    double b;

    Vec3d node_at(std::int64_t x, std::int64_t y, std::int64_t z) const {
        return {static_cast<double>(x) * b, static_cast<double>(y) * b, static_cast<double>(z) * b};
    }

    void store(std::int64_t q, const Vec3d& r) const {
        float* out = g + 3 * q;
        out[0] = static_cast<float>(r.x);
        out[1] = static_cast<float>(r.y);
        out[2] = static_cast<float>(r.z);
    }

    // Widens a row's extent [first, end) of nodes that are not empty (first = end: none yet) to
    // node x, the row's nodes visited in increasing x.
    static void widen(std::int32_t extent[2], std::int64_t x) {
        if (extent[0] == extent[1]) {
            extent[0] = static_cast<std::int32_t>(x);
        }
        extent[1] = static_cast<std::int32_t>(x + 1);
    }

    void store_empty(std::int64_t q) const {
        float* out = g + 3 * q;
        out[0] = out[1] = out[2] = std::numeric_limits<float>::quiet_NaN();
    }

    // The maps (frames and rest parts) of the holders of nodes q[0..n) (n ≤ FRAME_BATCH),
    // appended to list (at slot[q], layer_slots()).
    void flush(const std::int64_t q[FRAME_BATCH], int n, std::vector<TetMap>& list) const {
        FrameBatch f;
        for (int i = 0; i < FRAME_BATCH; ++i) {
            // Lanes past n repeat the first node's tet (computed, not used).
            load_lane(deformed_grid, tets[static_cast<std::size_t>(holder[q[i < n ? i : 0]])], i,
                      f);
        }
        f.compute();
        for (int i = 0; i < n; ++i) {
            TetMap m;
            const double det = f.det[i];
            m.ok = std::abs(det) > 0.0 && std::isfinite(det);
            for (int k = 0; k < 3; ++k) {
                m.rows[k] = Vec3d{f.rows[k][0][i], f.rows[k][1][i], f.rows[k][2][i]};
            }
            m.p3 = Vec3d{f.p[3][0][i], f.p[3][1][i], f.p[3][2][i]};
            Vec3d r[4];
            tet_vertices(tets[static_cast<std::size_t>(holder[q[i]])], rest_grid, r);
            m.r3 = r[3];
            for (int k = 0; k < 3; ++k) {
                m.dr[k] = r[k] - r[3];
            }
            list.push_back(m);
        }
    }

    // Whether node i of layer z (i = x + nodes[0] · y) is held and next to the shell (a node not
    // held in its 3 × 3 × 3).
    bool next_to_shell(std::int64_t z, std::int64_t i) const {
        const std::int64_t nxy = nodes[0] * nodes[1];
        const std::uint8_t* layer = near_xy + nxy * z;
        const std::uint8_t* layer_below = z > 0 ? layer - nxy : layer;
        const std::uint8_t* layer_above = z + 1 < nodes[2] ? layer + nxy : layer;
        return holder[nxy * z + i] >= 0 && (layer[i] & layer_below[i] & layer_above[i] & 2) == 0;
    }

    // slot[q] for layer z's held nodes next to the shell: their index in node order, the index
    // of their map in layer_maps()' list. Written once per layer before any list is built, so
    // that the chunks of the shell pass, which build the lists of the layers beside them too,
    // only read it.
    void layer_slots(std::int64_t z) const {
        const std::int64_t nxy = nodes[0] * nodes[1];
        std::int32_t count = 0;
        for (std::int64_t i = 0; i < nxy; ++i) {
            if (next_to_shell(z, i)) {
                slot[nxy * z + i] = count++;
            }
        }
    }

    // The maps of layer z's held nodes next to the shell, in node order, into list (replacing
    // its contents; slot[q]: the index, layer_slots()).
    void layer_maps(std::int64_t z, std::vector<TetMap>& list) const {
        const std::int64_t nxy = nodes[0] * nodes[1];
        list.clear();
        std::int64_t q[FRAME_BATCH];
        int n = 0;
        for (std::int64_t i = 0; i < nxy; ++i) {
            if (!next_to_shell(z, i)) {
                continue;
            }
            q[n++] = nxy * z + i;
            if (n == FRAME_BATCH) {
                flush(q, n, list);
                n = 0;
            }
        }
        if (n > 0) {
            flush(q, n, list);
        }
    }

    // The extrapolated nodes of layer z: a node not held, with a held node among its 26
    // neighbours, takes the map of the neighbours' tet with the largest smallest barycentric
    // coordinate at the node (the first in z, y, x order on a tie), extrapolated; the other nodes
    // not held are empty (NaN). lists[k % 3]: the maps of layer k's held nodes next to the shell
    // for k = z − 1 … z + 1 (layer_maps()). Returns the count of extrapolated nodes.
    std::int64_t shell(std::int64_t z, std::vector<TetMap>* const lists[3]) const {
        const std::int64_t nx = nodes[0];
        const std::int64_t ny = nodes[1];
        const std::int64_t nxy = nx * ny;
        const std::uint8_t* layer = near_xy + nxy * z;
        const std::uint8_t* layer_below = z > 0 ? layer - nxy : layer;
        const std::uint8_t* layer_above = z + 1 < nodes[2] ? layer + nxy : layer;
        std::int64_t count = 0;
        for (std::int64_t y = 0; y < ny; ++y) {
            std::int32_t* extent = row_extents + 2 * (y + ny * z);
            extent[0] = extent[1] = 0;
            for (std::int64_t x = 0; x < nx; ++x) {
                const std::int64_t q = x + nx * y + nxy * z;
                const std::int64_t in_layer = x + nx * y;
                if (holder[q] >= 0) {
                    widen(extent, x);
                    continue;  // written by layer_maps()
                }
                if (((layer[in_layer] | layer_below[in_layer] | layer_above[in_layer]) & 1) == 0) {
                    store_empty(q);
                    continue;
                }
                const Vec3d node = node_at(x, y, z);
                double best = -std::numeric_limits<double>::infinity();
                Vec3d best_rest{};
                for (std::int64_t cz = std::max<std::int64_t>(0, z - 1);
                     cz <= std::min(nodes[2] - 1, z + 1); ++cz) {
                    for (std::int64_t cy = std::max<std::int64_t>(0, y - 1);
                         cy <= std::min(ny - 1, y + 1); ++cy) {
                        for (std::int64_t cx = std::max<std::int64_t>(0, x - 1);
                             cx <= std::min(nx - 1, x + 1); ++cx) {
                            const std::int64_t c = cx + nx * cy + nxy * cz;
                            if (holder[c] < 0) {
                                continue;
                            }
                            const TetMap& m = (*lists[cz % 3])[static_cast<std::size_t>(slot[c])];
                            double l[3];
                            const double score = m.lambda(node, l);
                            if (score > best) {
                                best = score;
                                best_rest = m.rest(l);
                            }
                        }
                    }
                }
                if (best > -std::numeric_limits<double>::infinity()) {
                    store(q, best_rest);
                    widen(extent, x);
                    ++count;
                } else {
                    store_empty(q);
                }
            }
        }
        return count;
    }
};

void check_positions(std::span<const Vec3f> positions, const char* what) {
    // Any coordinate with all exponent bits set (infinite or NaN), without a branch per vertex;
    // then the first one, for the message.
    std::uint32_t bad = 0;
    const float* x = &positions.data()->x;
    for (std::size_t i = 0; i < 3 * positions.size(); ++i) {
        const auto bits = std::bit_cast<std::uint32_t>(x[i]);
        bad |= (bits & 0x7f800000u) == 0x7f800000u ? 1u : 0u;
    }
    if (bad == 0) {
        return;
    }
    for (std::size_t v = 0; v < positions.size(); ++v) {
        if (!is_finite(positions[v])) {
            throw InvalidInput(
                fmt::format("volume::InverseMap::build: {}[{}] is not finite", what, v));
        }
    }
}

void check_tets(std::span<const geometry::Tet> tets, std::int64_t num_vertices) {
    // Every index as unsigned below min(#V, 2³¹) (a negative index is ≥ 2³¹ as unsigned),
    // without a branch per tet; then the first one outside, for the message.
    const auto limit =
        static_cast<std::uint32_t>(std::min<std::int64_t>(num_vertices, std::int64_t{1} << 31));
    std::uint32_t bad = 0;
    for (const geometry::Tet& tet : tets) {
        for (const std::int32_t v : tet) {
            bad |= static_cast<std::uint32_t>(v) >= limit ? 1u : 0u;
        }
    }
    if (bad == 0) {
        return;
    }
    for (std::size_t t = 0; t < tets.size(); ++t) {
        for (const std::int32_t v : tets[t]) {
            if (v < 0 || v >= num_vertices) {
                throw InvalidInput(fmt::format(
                    "volume::InverseMap::build: tet {} has vertex index {} outside [0, {})", t, v,
                    num_vertices));
            }
        }
    }
}

template <typename S, int C, typename D>
void resample_through_typed(const InverseMap& map, const Volume& source, Volume& target) {
    const GridFrame sf = detail::frame_of(source);
    const GridFrame tf = detail::frame_of(target);
    const S* src = reinterpret_cast<const S*>(source.bytes().data());
    D* dst = reinterpret_cast<D*>(target.bytes().data());
    const float scale = std::is_floating_point_v<D> && std::is_same_v<S, std::uint8_t> && C == 4
                            ? 1.0f / 255.0f
                            : 1.0f;
    parallel_for(
        tf.n[2],
        [&](std::int64_t k) {
            for (std::int64_t j = 0; j < tf.n[1]; ++j) {
                for (std::int64_t i = 0; i < tf.n[0]; ++i) {
                    const double t[3] = {static_cast<double>(i), static_cast<double>(j),
                                         static_cast<double>(k)};
                    double g[3];
                    float s[C] = {};
                    if (map.source_coordinate(t, g)) {
                        detail::sample_trilinear<S, C>(src, sf.n, g[0], g[1], g[2], s);
                    }
                    D* out = dst + C * (i + tf.n[0] * (j + tf.n[1] * k));
                    for (int c = 0; c < C; ++c) {
                        out[c] = detail::convert_sample<D>(s[c], scale);
                    }
                }
            }
        },
        1);
}

}  // namespace

InverseMapStats InverseMap::build(const Volume& source, const Volume& target,
                                  std::span<const geometry::Tet> tets,
                                  std::span<const Vec3f> rest_positions,
                                  std::span<const Vec3f> deformed_positions,
                                  const InverseMapOptions& options) {
    if (source.empty() || target.empty()) {
        throw InvalidInput("volume::InverseMap::build: the source and target must not be empty");
    }
    if (options.node_voxels < 1) {
        throw InvalidInput(fmt::format("volume::InverseMap::build: node_voxels ({}) must be ≥ 1",
                                       options.node_voxels));
    }
    if (rest_positions.size() != deformed_positions.size()) {
        throw InvalidInput(fmt::format(
            "volume::InverseMap::build: deformed_positions.size() ({}) != rest_positions.size() "
            "({})",
            deformed_positions.size(), rest_positions.size()));
    }
    check_tets(tets, static_cast<std::int64_t>(rest_positions.size()));
    check_positions(rest_positions, "rest_positions");
    check_positions(deformed_positions, "deformed_positions");

    const GridFrame tf = detail::frame_of(target);
    const GridFrame sf = detail::frame_of(source);
    m_b = options.node_voxels;
    const auto b = static_cast<double>(m_b);
    const double exact_inv_b = std::has_single_bit(static_cast<unsigned>(m_b)) ? 1.0 / b : 0.0;
    for (int a = 0; a < 3; ++a) {
        m_nodes[static_cast<std::size_t>(a)] = (tf.n[a] - 1) / m_b + 2;
    }
    const std::int64_t nx = m_nodes[0];
    const std::int64_t nxy = m_nodes[0] * m_nodes[1];
    const std::int64_t num_nodes = nxy * m_nodes[2];
    m_g.resize(static_cast<std::size_t>(3 * num_nodes));  // every node written below
    m_holder.assign(static_cast<std::size_t>(num_nodes), -1);
    m_row_extents.resize(static_cast<std::size_t>(2 * m_nodes[1] * m_nodes[2]));
    std::vector<std::int32_t>& holder = m_holder;

    // 0. Every vertex in grid coordinates: deformed in the target's, rest in the source's.
    m_deformed_grid.resize(deformed_positions.size());
    m_rest_grid.resize(rest_positions.size());
    std::vector<Vec3d>& deformed_grid = m_deformed_grid;
    std::vector<Vec3d>& rest_grid = m_rest_grid;
    parallel_for(static_cast<std::int64_t>(deformed_positions.size()), [&](std::int64_t v) {
        const auto i = static_cast<std::size_t>(v);
        deformed_grid[i] = grid_coordinate(deformed_positions[i], tf);
        rest_grid[i] = grid_coordinate(rest_positions[i], sf);
    });
    // 1. Inside nodes: the highest index of the tets holding a node wins, a rule independent of
    // the order tets are visited in. (a) Every tet, in parallel, raises the holder of each node it
    // holds to its index (an atomic maximum) and, where the holder was below its index, records
    // its map's value at the node (per fixed chunk of tets); (b) every held node takes the value
    // its holder recorded.
    InverseMapStats stats;
    stats.num_nodes = num_nodes;
    const HoldPass hold{.tets = tets,
                        .deformed_grid = deformed_grid,
                        .rest_grid = rest_grid,
                        .holder = holder.data(),
                        .nodes = m_nodes,
                        .b = b,
                        .inv_b = exact_inv_b};
    const auto num_tets = static_cast<std::int64_t>(tets.size());
    const std::int64_t num_batches = (num_tets + FRAME_BATCH - 1) / FRAME_BATCH;
    constexpr std::int64_t BATCHES_PER_CHUNK = 128;
    const std::int64_t num_value_lists = num_chunks(num_batches, BATCHES_PER_CHUNK);
    if (m_held_values.size() < static_cast<std::size_t>(num_value_lists)) {
        m_held_values.resize(static_cast<std::size_t>(num_value_lists));
    }
    const bool use_avx2 = has_avx2();
    parallel_for_chunks(
        num_batches, BATCHES_PER_CHUNK, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            std::vector<HeldValue>& out = m_held_values[static_cast<std::size_t>(c)];
            out.clear();
            for (std::int64_t batch = begin; batch < end; ++batch) {
                const std::int64_t first = batch * FRAME_BATCH;
                const std::int64_t last = std::min(num_tets, first + FRAME_BATCH);
                if (!use_avx2 || !hold.tets_batched(first, last, out)) {
                    hold.tets_one_by_one(first, last, out);
                }
            }
        });
    // (b) Each held node's value: the one its holder recorded (exactly one record per node has
    // the holder's index; nodes written once, so in parallel).
    parallel_for(
        num_value_lists,
        [&](std::int64_t c) {
            for (const HeldValue& h : m_held_values[static_cast<std::size_t>(c)]) {
                if (holder[static_cast<std::size_t>(h.node)] == h.tet) {
                    float* out = m_g.data() + 3 * h.node;
                    out[0] = h.value[0];
                    out[1] = h.value[1];
                    out[2] = h.value[2];
                }
            }
        },
        1);

    // 2. Nodes next to inside ones: a neighbour's tet map, extrapolated.
    // First, per node, whether a node of its 3 × 3 in x and y is held (a separable dilation);
    // a node whose 3 × 3 × 3 has none (most nodes away from the body) is passed over at once.
    const std::int64_t ny = m_nodes[1];
    m_near_x.resize(static_cast<std::size_t>(num_nodes));
    m_near_xy.resize(static_cast<std::size_t>(num_nodes));
    std::vector<std::uint8_t>& near_x = m_near_x;
    std::vector<std::uint8_t>& near_xy = m_near_xy;
    // Bit 0: some node of the 3 × 3 (in x, y) is held; bit 1: every node of it inside the grid
    // is held (an erosion: a held node whose 3 × 3 × 3 has bit 1 everywhere has no neighbour in
    // the shell, and no shell node reads its map).
    parallel_for(
        m_nodes[2],
        [&](std::int64_t z) {
            // Per row: 3 where held, 0 where not, 2 past either end (no node: not held, and no
            // obstacle to the erosion); two loops without branches, which the compiler
            // vectorizes.
            std::vector<std::uint8_t> h(static_cast<std::size_t>(nx + 2), 2);
            for (std::int64_t q = nxy * z; q < nxy * (z + 1); q += nx) {
                const std::int32_t* in = holder.data() + q;
                for (std::int64_t x = 0; x < nx; ++x) {
                    h[static_cast<std::size_t>(x + 1)] = in[x] >= 0 ? 3 : 0;
                }
                std::uint8_t* out = near_x.data() + q;
                const std::uint8_t* l = h.data();
                const std::uint8_t* c = l + 1;
                const std::uint8_t* r = l + 2;
                for (std::int64_t x = 0; x < nx; ++x) {
                    out[x] = static_cast<std::uint8_t>(((c[x] | l[x] | r[x]) & 1) |
                                                       (c[x] & l[x] & r[x] & 2));
                }
            }
            for (std::int64_t y = 0; y < ny; ++y) {
                const std::uint8_t* row = near_x.data() + nx * y + nxy * z;
                const std::uint8_t* below = y > 0 ? row - nx : row;
                const std::uint8_t* above = y + 1 < ny ? row + nx : row;
                std::uint8_t* out = near_xy.data() + nx * y + nxy * z;
                for (std::int64_t x = 0; x < nx; ++x) {
                    out[x] = static_cast<std::uint8_t>(((row[x] | below[x] | above[x]) & 1) |
                                                       (row[x] & below[x] & above[x] & 2));
                }
            }
        },
        1);
    // Then the shell, over chunks of layers in parallel: per chunk, layer by layer, the maps of
    // the held nodes next to the shell (a list per layer, kept for three layers), then the shell
    // nodes of the layer before, which read their held neighbours' maps from the lists. A chunk
    // also computes the lists of the layers on either side of it.
    const NodePass pass{.tets = tets,
                        .deformed_grid = deformed_grid,
                        .rest_grid = rest_grid,
                        .holder = holder.data(),
                        .near_xy = near_xy.data(),
                        .slot = nullptr,
                        .g = m_g.data(),
                        .row_extents = m_row_extents.data(),
                        .nodes = m_nodes,
                        .b = b};
    const std::int64_t nz = m_nodes[2];
    const std::int64_t chunks_wanted = num_threads() > 1 ? CHUNKS_PER_THREAD * num_threads() : 1;
    const std::int64_t layers_per_chunk =
        std::max<std::int64_t>(1, (nz + chunks_wanted - 1) / chunks_wanted);
    const std::int64_t num_chunks = (nz + layers_per_chunk - 1) / layers_per_chunk;
    m_slot.resize(static_cast<std::size_t>(num_nodes));
    if (m_lists.size() < static_cast<std::size_t>(3 * num_chunks)) {
        m_lists.resize(static_cast<std::size_t>(3 * num_chunks));
    }
    NodePass with_slots = pass;
    with_slots.slot = m_slot.data();
    std::vector<std::int64_t> extrapolated(static_cast<std::size_t>(nz), 0);
    parallel_for(
        nz, [&](std::int64_t z) { with_slots.layer_slots(z); }, 1);
    parallel_for(
        num_chunks,
        [&](std::int64_t chunk) {
            const std::int64_t z0 = chunk * layers_per_chunk;
            const std::int64_t z1 = std::min(nz, z0 + layers_per_chunk);
            std::vector<TetMap>* lists[3];
            for (int k = 0; k < 3; ++k) {
                lists[k] = &m_lists[static_cast<std::size_t>(3 * chunk + k)];
            }
            for (std::int64_t z = std::max<std::int64_t>(0, z0 - 1); z <= std::min(nz - 1, z1);
                 ++z) {
                with_slots.layer_maps(z, *lists[z % 3]);
                if (z - 1 >= z0 && z - 1 < z1) {
                    extrapolated[static_cast<std::size_t>(z - 1)] = with_slots.shell(z - 1, lists);
                }
            }
            if (z1 == nz) {
                extrapolated[static_cast<std::size_t>(nz - 1)] = with_slots.shell(nz - 1, lists);
            }
        },
        1);
    for (const std::int32_t h : holder) {
        stats.num_inside += h >= 0 ? 1 : 0;
    }
    for (const std::int64_t e : extrapolated) {
        stats.num_extrapolated += e;
    }
    return stats;
}

bool InverseMap::source_coordinate(const double t[3], double out[3]) const {
    const double inv_b = 1.0 / static_cast<double>(m_b);
    std::int64_t q[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        const double u = t[a] * inv_b;
        if (!(u >= 0.0) || !(u < static_cast<double>(m_nodes[static_cast<std::size_t>(a)] - 1))) {
            return false;
        }
        q[a] = static_cast<std::int64_t>(u);
        f[a] = u - static_cast<double>(q[a]);
    }
    const std::int64_t nx = m_nodes[0];
    const std::int64_t nxy = m_nodes[0] * m_nodes[1];
    double g[3] = {0.0, 0.0, 0.0};
    for (int corner = 0; corner < 8; ++corner) {
        const int cx = corner & 1;
        const int cy = (corner >> 1) & 1;
        const int cz = corner >> 2;
        const double w = (cx != 0 ? f[0] : 1.0 - f[0]) * (cy != 0 ? f[1] : 1.0 - f[1]) *
                         (cz != 0 ? f[2] : 1.0 - f[2]);
        const float* v = m_g.data() + 3 * ((q[0] + cx) + nx * (q[1] + cy) + nxy * (q[2] + cz));
        if (std::isnan(v[0])) {
            return false;
        }
        g[0] += w * v[0];
        g[1] += w * v[1];
        g[2] += w * v[2];
    }
    out[0] = g[0];
    out[1] = g[1];
    out[2] = g[2];
    return true;
}

void resample_through(const InverseMap& map, const Volume& source, Volume& target) {
    const VoxelType st = source.type();
    const VoxelType tt = target.type();
    if (!can_resample_into(st, tt)) {
        throw InvalidInput(fmt::format(
            "volume::resample_through: cannot resample a {} source into a {} target (valid: the "
            "source type, f32 from u8/i16/u16, rgba32f from rgba8)",
            name(st), name(tt)));
    }
    if (map.nodes()[0] == 0) {
        throw InvalidInput("volume::resample_through: the map was not built");
    }
    switch (st) {
        case VoxelType::u8:
            tt == st ? resample_through_typed<std::uint8_t, 1, std::uint8_t>(map, source, target)
                     : resample_through_typed<std::uint8_t, 1, float>(map, source, target);
            break;
        case VoxelType::i16:
            tt == st ? resample_through_typed<std::int16_t, 1, std::int16_t>(map, source, target)
                     : resample_through_typed<std::int16_t, 1, float>(map, source, target);
            break;
        case VoxelType::u16:
            tt == st ? resample_through_typed<std::uint16_t, 1, std::uint16_t>(map, source, target)
                     : resample_through_typed<std::uint16_t, 1, float>(map, source, target);
            break;
        case VoxelType::f32:
            resample_through_typed<float, 1, float>(map, source, target);
            break;
        case VoxelType::rgba8:
            tt == st ? resample_through_typed<std::uint8_t, 4, std::uint8_t>(map, source, target)
                     : resample_through_typed<std::uint8_t, 4, float>(map, source, target);
            break;
        case VoxelType::rgba32f:
            resample_through_typed<float, 4, float>(map, source, target);
            break;
    }
}

}  // namespace pliant::volume
