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
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/resample.hpp"

namespace pliant::volume {

namespace {

using detail::GridFrame;

// A deformed tet's affine map in target grid coordinates: λk = rows[k] · (x − p3) for k < 3,
// λ3 = 1 − λ0 − λ1 − λ2, rest r = r3 + Σ λk dr[k] (source grid coordinates).
struct TetMap {
    Vec3d p3, r3;
    Vec3d rows[3];
    Vec3d dr[3];
    bool ok = false;

    // The smallest barycentric coordinate of x (≥ 0: inside); l[0..2] = λ0..2.
    double lambda(const Vec3d& x, double l[3]) const {
        const Vec3d d = x - p3;
        l[0] = dot(rows[0], d);
        l[1] = dot(rows[1], d);
        l[2] = dot(rows[2], d);
        return std::min({l[0], l[1], l[2], 1.0 - l[0] - l[1] - l[2]});
    }
    Vec3d rest(const double l[3]) const { return r3 + dr[0] * l[0] + dr[1] * l[1] + dr[2] * l[2]; }
};

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

// The barycentric rows of a tet from its deformed vertices p (target grid coordinates); ok is
// false for a degenerate tet. The rest part (r3, dr) is left unset.
TetMap tet_frame(const Vec3d p[4]) {
    TetMap m;
    const Vec3d e0 = p[0] - p[3];
    const Vec3d e1 = p[1] - p[3];
    const Vec3d e2 = p[2] - p[3];
    const double det = dot(e0, cross(e1, e2));
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) {
        return m;
    }
    const double inv = 1.0 / det;
    m.rows[0] = cross(e1, e2) * inv;
    m.rows[1] = cross(e2, e0) * inv;
    m.rows[2] = cross(e0, e1) * inv;
    m.p3 = p[3];
    m.ok = true;
    return m;
}

// tet_frame() for FRAME_BATCH tets at once, structure of arrays: p[vertex][axis][lane] in,
// det[lane] and rows[k][axis][lane] out (rows for a degenerate tet are whatever the division
// gives; tet_frame() refuses a det that is 0 or not finite). Lane by lane the operations and their
// order are tet_frame()'s, so the rows are its bits.
constexpr int FRAME_BATCH = 8;
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

// The map of a tet from its deformed vertices p and its rest vertices (source grid coordinates,
// per vertex).
TetMap tet_map(const geometry::Tet& tet, std::span<const Vec3d> rest_grid, const Vec3d p[4]) {
    TetMap m = tet_frame(p);
    if (!m.ok) {
        return m;
    }
    Vec3d r[4];
    tet_vertices(tet, rest_grid, r);
    m.r3 = r[3];
    for (int k = 0; k < 3; ++k) {
        m.dr[k] = r[k] - r[3];
    }
    return m;
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

void check_positions(std::span<const Vec3f> positions, const char* what) {
    for (std::size_t v = 0; v < positions.size(); ++v) {
        if (!is_finite(positions[v])) {
            throw InvalidInput(
                fmt::format("volume::InverseMap::build: {}[{}] is not finite", what, v));
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
    const auto num_vertices = static_cast<std::int64_t>(rest_positions.size());
    for (std::size_t t = 0; t < tets.size(); ++t) {
        for (const std::int32_t v : tets[t]) {
            if (v < 0 || v >= num_vertices) {
                throw InvalidInput(fmt::format(
                    "volume::InverseMap::build: tet {} has vertex index {} outside [0, {})", t, v,
                    num_vertices));
            }
        }
    }
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
    m_g.assign(static_cast<std::size_t>(3 * num_nodes), std::numeric_limits<float>::quiet_NaN());
    m_holder.assign(static_cast<std::size_t>(num_nodes), -1);
    std::vector<std::int32_t>& holder = m_holder;
    auto store = [&](std::int64_t q, const Vec3d& r) {
        float* out = m_g.data() + 3 * q;
        out[0] = static_cast<float>(r.x);
        out[1] = static_cast<float>(r.y);
        out[2] = static_cast<float>(r.z);
    };

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
    // Node (x, y, z) in target grid coordinates.
    const auto node_at = [b](std::int64_t x, std::int64_t y, std::int64_t z) {
        return Vec3d{static_cast<double>(x) * b, static_cast<double>(y) * b,
                     static_cast<double>(z) * b};
    };
    // The map of tet t (its deformed frame and rest part).
    const auto map_of = [&](std::int32_t t) {
        const geometry::Tet& tet = tets[static_cast<std::size_t>(t)];
        Vec3d p[4];
        tet_vertices(tet, deformed_grid, p);
        return tet_map(tet, rest_grid, p);
    };

    // 1. Inside nodes: the highest index of the tets holding a node wins, a rule independent of
    // the order tets are visited in. (a) Every tet, in parallel, raises the holder of each node it
    // holds to its index (an atomic maximum); (b) every held node, in parallel, takes its
    // holder's map.
    InverseMapStats stats;
    stats.num_nodes = num_nodes;
    // Tets in batches of FRAME_BATCH: their barycentric rows as tet_frame() computes them, the
    // same operations in the same order lane by lane (arrays the compiler can vectorize; no
    // contraction, -ffp-contract=off), then each tet's nodes.
    const auto num_tets = static_cast<std::int64_t>(tets.size());
    parallel_for(
        (num_tets + FRAME_BATCH - 1) / FRAME_BATCH,
        [&](std::int64_t batch) {
            const std::int64_t first = batch * FRAME_BATCH;
            const int count =
                static_cast<int>(std::min<std::int64_t>(FRAME_BATCH, num_tets - first));
            FrameBatch f;
            for (int i = 0; i < FRAME_BATCH; ++i) {
                // Lanes past the end repeat the first tet (computed, not used).
                const geometry::Tet& tet =
                    tets[static_cast<std::size_t>(first + (i < count ? i : 0))];
                for (int v = 0; v < 4; ++v) {
                    const Vec3d& x =
                        deformed_grid[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
                    f.p[v][0][i] = x.x;
                    f.p[v][1][i] = x.y;
                    f.p[v][2][i] = x.z;
                }
            }
            f.compute();
            for (int i = 0; i < count; ++i) {
                Vec3d p[4];
                for (int v = 0; v < 4; ++v) {
                    p[v] = Vec3d{f.p[v][0][i], f.p[v][1][i], f.p[v][2][i]};
                }
                std::int64_t lo[3], hi[3];
                bool is_empty = false;
                for (int a = 0; a < 3; ++a) {
                    node_range(p, a, b, exact_inv_b, m_nodes[static_cast<std::size_t>(a)], lo[a],
                               hi[a]);
                    is_empty = is_empty || lo[a] > hi[a];
                }
                if (is_empty) {
                    continue;
                }
                const double det = f.det[i];
                if (!(std::abs(det) > 0.0) || !std::isfinite(det)) {
                    continue;  // degenerate (tet_frame(): not ok)
                }
                TetMap m;  // λ only: the rest part is taken in (b)
                for (int k = 0; k < 3; ++k) {
                    m.rows[k] = Vec3d{f.rows[k][0][i], f.rows[k][1][i], f.rows[k][2][i]};
                }
                m.p3 = p[3];
                m.ok = true;
                const auto index = static_cast<std::int32_t>(first + i);
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                            double l[3];
                            if (!(m.lambda(node_at(x, y, z), l) >= -1e-9)) {
                                continue;
                            }
                            std::atomic_ref<std::int32_t> h(
                                holder[static_cast<std::size_t>(x + nx * y + nxy * z)]);
                            std::int32_t current = h.load(std::memory_order_relaxed);
                            while (current < index &&
                                   !h.compare_exchange_weak(current, index,
                                                            std::memory_order_relaxed)) {
                            }
                        }
                    }
                }
            }
        },
        128);
    parallel_for(
        m_nodes[2],
        [&](std::int64_t z) {
            for (std::int64_t y = 0; y < m_nodes[1]; ++y) {
                for (std::int64_t x = 0; x < nx; ++x) {
                    const std::int64_t q = x + nx * y + nxy * z;
                    const std::int32_t t = holder[static_cast<std::size_t>(q)];
                    if (t < 0) {
                        continue;
                    }
                    const TetMap m = map_of(t);
                    double l[3];
                    m.lambda(node_at(x, y, z), l);
                    store(q, m.rest(l));
                }
            }
        },
        1);

    // 2. Nodes next to inside ones: a neighbour's tet map, extrapolated. Reads `holder` (inside
    // nodes only), writes only its own node: parallel over layers.
    // First, per node, whether a node of its 3 × 3 in x and y is held (a separable dilation);
    // a node whose 3 × 3 × 3 has none (most nodes away from the body) is passed over at once.
    const std::int64_t ny = m_nodes[1];
    std::vector<std::uint8_t> near_x(static_cast<std::size_t>(num_nodes));
    std::vector<std::uint8_t> near_xy(static_cast<std::size_t>(num_nodes));
    const auto held = [&](std::int64_t q) {
        return holder[static_cast<std::size_t>(q)] >= 0 ? 1 : 0;
    };
    parallel_for(
        m_nodes[2],
        [&](std::int64_t z) {
            for (std::int64_t q = nxy * z; q < nxy * (z + 1); q += nx) {
                for (std::int64_t x = 0; x < nx; ++x) {
                    int any = held(q + x);
                    any |= x > 0 ? held(q + x - 1) : 0;
                    any |= x + 1 < nx ? held(q + x + 1) : 0;
                    near_x[static_cast<std::size_t>(q + x)] = static_cast<std::uint8_t>(any);
                }
            }
            for (std::int64_t y = 0; y < ny; ++y) {
                const std::uint8_t* row = near_x.data() + nx * y + nxy * z;
                const std::uint8_t* below = y > 0 ? row - nx : row;
                const std::uint8_t* above = y + 1 < ny ? row + nx : row;
                std::uint8_t* out = near_xy.data() + nx * y + nxy * z;
                for (std::int64_t x = 0; x < nx; ++x) {
                    out[x] = static_cast<std::uint8_t>(row[x] | below[x] | above[x]);
                }
            }
        },
        1);
    std::vector<std::int64_t> extrapolated(static_cast<std::size_t>(m_nodes[2]), 0);
    parallel_for(
        m_nodes[2],
        [&](std::int64_t z) {
            const std::uint8_t* layer = near_xy.data() + nxy * z;
            const std::uint8_t* layer_below = z > 0 ? layer - nxy : layer;
            const std::uint8_t* layer_above = z + 1 < m_nodes[2] ? layer + nxy : layer;
            for (std::int64_t y = 0; y < m_nodes[1]; ++y) {
                for (std::int64_t x = 0; x < nx; ++x) {
                    const std::int64_t q = x + nx * y + nxy * z;
                    const std::int64_t in_layer = x + nx * y;
                    if (holder[static_cast<std::size_t>(q)] >= 0 ||
                        (layer[in_layer] | layer_below[in_layer] | layer_above[in_layer]) == 0) {
                        continue;
                    }
                    const Vec3d node = node_at(x, y, z);
                    double best = -std::numeric_limits<double>::infinity();
                    Vec3d best_rest{};
                    for (std::int64_t cz = std::max<std::int64_t>(0, z - 1);
                         cz <= std::min(m_nodes[2] - 1, z + 1); ++cz) {
                        for (std::int64_t cy = std::max<std::int64_t>(0, y - 1);
                             cy <= std::min(m_nodes[1] - 1, y + 1); ++cy) {
                            for (std::int64_t cx = std::max<std::int64_t>(0, x - 1);
                                 cx <= std::min(nx - 1, x + 1); ++cx) {
                                const std::int32_t t =
                                    holder[static_cast<std::size_t>(cx + nx * cy + nxy * cz)];
                                if (t < 0) {
                                    continue;
                                }
                                const TetMap m = map_of(t);
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
                        ++extrapolated[static_cast<std::size_t>(z)];
                    }
                }
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
