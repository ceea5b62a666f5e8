// bench_resample: volume::Resampler (row spans from the face planes, slab-parallel) beside the
// naive brute force (one thread, every tet, every voxel of its bounding box tested against the
// four face planes) on the issue-6 workload: an N³ volume (the Shepp–Logan phantom, f32, or the
// RGBA test object, rgba8), a full-box pbd::TetGrid of cells of 4 voxels ((N/4)³ cells, 5 tets
// each: 1.31 M tets at N = 256), rotated rigidly by 30° about z through the box centre and
// resampled into a grid like the source. Kind 2 is the source system's scale (issue 29,
// source_scale_phantom.hpp; N = 256 only): the 256³ rgba8 phantom with a grid of 64³ cells over
// its visible voxels, twisted about z through the box centre by 0° at the bottom to 60° at the top
// (a frame of the twist driver).
//
// Items processed = target voxels. Wall time (UseRealTime). Arguments: N, threads. The brute force
// runs on one thread and checks once that its output is bitwise equal to the Resampler's (same
// kernels, same tie rule; counter `identical`). Prepare = the Resampler's constructor (visibility
// of the source, per-tet rest-footprint test), paid once per rest mesh.
// Debian's libbenchmark prints "***WARNING*** Library was built as DEBUG": that is how the
// package was built, not pliant's flags (cosmetic).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/detail/resample_kernel.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/resample.hpp"
#include "source_scale_phantom.hpp"

namespace {

using namespace pliant;
using volume::Volume;
using volume::VoxelType;

enum Kind : std::int64_t { PHANTOM = 0, RGBA = 1, SOURCE_SCALE = 2 };

struct Workload {
    Volume source;
    pbd::TetGrid grid;
    std::vector<Vec3f> deformed;
    std::unique_ptr<volume::Resampler> resampler;
};

// Cached per (kind, N); nothing random.
const Workload& workload(Kind kind, std::int64_t n) {
    static std::map<std::pair<std::int64_t, std::int64_t>, std::unique_ptr<Workload>> cache;
    std::unique_ptr<Workload>& slot = cache[{kind, n}];
    if (!slot) {
        slot = std::make_unique<Workload>();
        Workload& w = *slot;
        if (kind == SOURCE_SCALE) {
            const bench::SourceScaleWorkload& s = bench::source_scale_workload();
            w.source = s.source;
            w.grid = s.grid;
        } else {
            w.source = kind == PHANTOM ? volume::shepp_logan_3d({n, n, n})
                                       : volume::rgba_test_object({n, n, n}, VoxelType::rgba8);
            w.grid = pbd::build_tet_grid(w.source, {.cell_voxels = 4, .full_box = true});
        }
        const AABBd box = w.source.bounds();
        const Vec3d c = (box.lo + box.hi) * 0.5;
        w.deformed.resize(w.grid.mesh.positions.size());
        for (std::size_t v = 0; v < w.deformed.size(); ++v) {
            const Vec3d d = vec3_cast<double>(w.grid.mesh.positions[v]) - c;
            const double height = (d.z + (box.hi.z - box.lo.z) * 0.5) / (box.hi.z - box.lo.z);
            const double a =
                (kind == SOURCE_SCALE ? 60.0 * height : 30.0) * std::numbers::pi / 180.0;
            w.deformed[v] = vec3_cast<float>(Vec3d{std::cos(a) * d.x - std::sin(a) * d.y,
                                                   std::sin(a) * d.x + std::cos(a) * d.y, d.z} +
                                             c);
        }
        w.resampler =
            std::make_unique<volume::Resampler>(w.source, w.grid.mesh.tets, w.grid.mesh.positions);
    }
    return *slot;
}

Volume make_target(const Volume& source) {
    return Volume::allocate(source.dims(), source.type(), source.spacing(), source.origin());
}

using volume::detail::frame_of;

// The naive baseline: one thread, every tet in index order, every voxel centre of its bounding
// box tested against the four face planes (the same tie rule), trilinear sample, write.
template <typename S, int C>
void brute_force(const Workload& w, Volume& target) {
    std::memset(target.bytes().data(), 0, target.size_bytes());
    const volume::detail::GridFrame tf = frame_of(target);
    const volume::detail::GridFrame sf = frame_of(w.source);
    const S* src = reinterpret_cast<const S*>(w.source.bytes().data());
    S* dst = reinterpret_cast<S*>(target.bytes().data());
    for (const geometry::Tet& tet : w.grid.mesh.tets) {
        Vec3f p[4];
        Vec3f r[4];
        for (int v = 0; v < 4; ++v) {
            p[v] = w.deformed[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
            r[v] =
                w.grid.mesh.positions[static_cast<std::size_t>(tet[static_cast<std::size_t>(v)])];
        }
        volume::detail::TetRaster t;
        if (!volume::detail::setup_tet(p, tet.data(), r, tf, sf, t)) {
            continue;
        }
        for (std::int64_t k = t.lo[2]; k <= t.hi[2]; ++k) {
            for (std::int64_t j = t.lo[1]; j <= t.hi[1]; ++j) {
                for (std::int64_t i = t.lo[0]; i <= t.hi[0]; ++i) {
                    if (!volume::detail::inside(t, i, j, k)) {
                        continue;
                    }
                    float s[C];
                    volume::detail::sample_trilinear<S, C>(
                        src, sf.n, volume::detail::map_coord(t.map[0], i, j, k),
                        volume::detail::map_coord(t.map[1], i, j, k),
                        volume::detail::map_coord(t.map[2], i, j, k), s);
                    S* out = dst + C * (i + tf.n[0] * (j + tf.n[1] * k));
                    for (int c = 0; c < C; ++c) {
                        out[c] = volume::detail::convert_sample<S>(s[c], 1.0f);
                    }
                }
            }
        }
    }
}

void run_brute_force(const Workload& w, Volume& target) {
    if (w.source.type() == VoxelType::f32) {
        brute_force<float, 1>(w, target);
    } else {
        brute_force<std::uint8_t, 4>(w, target);
    }
}

void set_counters(benchmark::State& state, const Workload& w, std::int64_t n) {
    state.SetItemsProcessed(state.iterations() * n * n * n);
    state.counters["tets"] = static_cast<double>(w.grid.mesh.tets.size());
    state.counters["kept_tets"] = static_cast<double>(w.resampler->kept_tets().size());
}

void BM_Resample(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    set_num_threads(static_cast<int>(state.range(2)));
    Volume target = make_target(w.source);
    volume::ResampleStats stats;
    for (auto _ : state) {
        stats = w.resampler->resample(w.deformed, target);
        benchmark::DoNotOptimize(target.bytes().data());
    }
    set_counters(state, w, n);
    state.counters["voxels_written"] = static_cast<double>(stats.num_voxels_written);
    state.counters["threads"] = num_threads();
}

void BM_BruteForce(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    Volume target = make_target(w.source);
    for (auto _ : state) {
        run_brute_force(w, target);
        benchmark::DoNotOptimize(target.bytes().data());
    }
    set_counters(state, w, n);
    // Same output as the Resampler, bit for bit?
    Volume fast = make_target(w.source);
    w.resampler->resample(w.deformed, fast);
    state.counters["identical"] =
        std::memcmp(fast.bytes().data(), target.bytes().data(), fast.size_bytes()) == 0 ? 1 : 0;
}

void BM_Prepare(benchmark::State& state) {
    const Kind kind = static_cast<Kind>(state.range(0));
    const std::int64_t n = state.range(1);
    const Workload& w = workload(kind, n);
    set_num_threads(static_cast<int>(state.range(2)));
    for (auto _ : state) {
        volume::Resampler r(w.source, w.grid.mesh.tets, w.grid.mesh.positions);
        benchmark::DoNotOptimize(r.kept_tets().data());
    }
    set_counters(state, w, n);
}

// A route weighed for issue 29, measured here and not used by the pipeline: instead of
// resampling the whole volume every frame, rasterize the rest coordinates of the deformed tets at
// the nodes of a coarse grid over the target (every B-th voxel centre, B = cell_voxels) — an
// inverse map — and let the ray caster sample the source through it (trilinear in the map, then
// trilinear in the source). The map is exact at its nodes (each node inside a tet gets that
// tet's affine rest coordinate; the highest tet index wins) and trilinear between them, so it
// differs from the exact resample inside tets that the map's trilinear interpolation bends, and
// near the deformed body's surface: a node outside every tet next to one inside takes the affine
// map of a tet near it, extrapolated (it points outside the rest body, where the source is
// empty); a sample with a node near no tet is 0. BM_InverseMapRoute times the
// map's construction (one thread) and reports, against the exact resample of the same
// deformation, the PSNR (premultiplied colour and alpha) over all voxels and over the voxels the
// exact resample gives alpha > 0.
struct InverseMap {
    int b = 4;
    std::int64_t m[3]{};
    std::vector<double> g;  // 3 per node, source grid coordinates; NaN: no tet near the node
    std::vector<std::int32_t> tet;  // per node: the tet holding it, −1: none

    std::int64_t node(std::int64_t a, std::int64_t c1, std::int64_t c2) const {
        return a + m[0] * (c1 + m[1] * c2);
    }
};

// The affine map of a deformed tet in target grid coordinates: barycentric λ0..2 = rows · (x − p3)
// (λ3 = 1 − λ0 − λ1 − λ2) and rest source coordinates r3 + Σ λk (rk − r3).
struct TetMap {
    Vec3d p3, r3;
    Vec3d rows[3];  // cofactor rows / det
    Vec3d dr[3];    // rk − r3
    bool ok = false;

    double lambda(const Vec3d& x, double l[3]) const {
        const Vec3d d = x - p3;
        l[0] = dot(rows[0], d);
        l[1] = dot(rows[1], d);
        l[2] = dot(rows[2], d);
        return std::min({l[0], l[1], l[2], 1.0 - l[0] - l[1] - l[2]});
    }
    Vec3d rest(const double l[3]) const { return r3 + dr[0] * l[0] + dr[1] * l[1] + dr[2] * l[2]; }
};

TetMap tet_map(const Workload& w, std::int32_t t, const volume::detail::GridFrame& tf,
               const volume::detail::GridFrame& sf, Vec3d p[4]) {
    auto index_of = [](const Vec3f& x, const volume::detail::GridFrame& f) {
        return Vec3d{(x.x - f.origin[0]) * f.inv_spacing[0] - 0.5,
                     (x.y - f.origin[1]) * f.inv_spacing[1] - 0.5,
                     (x.z - f.origin[2]) * f.inv_spacing[2] - 0.5};
    };
    const geometry::Tet& tet = w.grid.mesh.tets[static_cast<std::size_t>(t)];
    Vec3d r[4];
    for (int v = 0; v < 4; ++v) {
        const auto id = static_cast<std::size_t>(tet[static_cast<std::size_t>(v)]);
        p[v] = index_of(w.deformed[id], tf);
        r[v] = index_of(w.grid.mesh.positions[id], sf);
    }
    TetMap m;
    const Vec3d e0 = p[0] - p[3];
    const Vec3d e1 = p[1] - p[3];
    const Vec3d e2 = p[2] - p[3];
    const double det = dot(e0, cross(e1, e2));
    if (!(std::abs(det) > 0.0)) {
        return m;
    }
    const double inv = 1.0 / det;
    m.rows[0] = cross(e1, e2) * inv;
    m.rows[1] = cross(e2, e0) * inv;
    m.rows[2] = cross(e0, e1) * inv;
    m.p3 = p[3];
    m.r3 = r[3];
    for (int k = 0; k < 3; ++k) {
        m.dr[k] = r[k] - r[3];
    }
    m.ok = true;
    return m;
}

// Pass 1: every node inside a deformed tet gets its rest coordinate (the highest tet index wins)
// and remembers the tet. Pass 2: every node outside all tets but next to an inside node
// (26-neighbourhood) takes the extrapolated map of the neighbours' tet with the largest smallest
// barycentric coordinate. One thread.
void build_inverse_map(const Workload& w, const Volume& target, InverseMap& map) {
    const volume::detail::GridFrame tf = frame_of(target);
    const volume::detail::GridFrame sf = frame_of(w.source);
    const auto b = static_cast<double>(map.b);
    for (int a = 0; a < 3; ++a) {
        map.m[a] = (tf.n[a] - 1) / map.b + 2;
    }
    const auto num_nodes = static_cast<std::size_t>(map.m[0] * map.m[1] * map.m[2]);
    map.g.assign(3 * num_nodes, std::numeric_limits<double>::quiet_NaN());
    map.tet.assign(num_nodes, -1);
    for (const std::int32_t t : w.resampler->kept_tets()) {
        Vec3d p[4];
        const TetMap m = tet_map(w, t, tf, sf, p);
        if (!m.ok) {
            continue;
        }
        std::int64_t lo[3];
        std::int64_t hi[3];
        bool empty = false;
        for (int a = 0; a < 3; ++a) {
            const double mn = std::min({p[0][a], p[1][a], p[2][a], p[3][a]});
            const double mx = std::max({p[0][a], p[1][a], p[2][a], p[3][a]});
            lo[a] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(mn / b)));
            hi[a] =
                std::min<std::int64_t>(map.m[a] - 1, static_cast<std::int64_t>(std::floor(mx / b)));
            empty = empty || lo[a] > hi[a];
        }
        if (empty) {
            continue;
        }
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                    double l[3];
                    const Vec3d node{static_cast<double>(x) * b, static_cast<double>(y) * b,
                                     static_cast<double>(z) * b};
                    if (!(m.lambda(node, l) >= -1e-9)) {
                        continue;
                    }
                    const Vec3d rest = m.rest(l);
                    const std::int64_t q = map.node(x, y, z);
                    map.tet[static_cast<std::size_t>(q)] = t;
                    double* out = map.g.data() + 3 * q;
                    out[0] = rest.x;
                    out[1] = rest.y;
                    out[2] = rest.z;
                }
            }
        }
    }
    const std::vector<std::int32_t> inside = map.tet;
    for (std::int64_t z = 0; z < map.m[2]; ++z) {
        for (std::int64_t y = 0; y < map.m[1]; ++y) {
            for (std::int64_t x = 0; x < map.m[0]; ++x) {
                const std::int64_t q = map.node(x, y, z);
                if (inside[static_cast<std::size_t>(q)] >= 0) {
                    continue;
                }
                const Vec3d node{static_cast<double>(x) * b, static_cast<double>(y) * b,
                                 static_cast<double>(z) * b};
                double best = -std::numeric_limits<double>::infinity();
                for (std::int64_t dz = std::max<std::int64_t>(0, z - 1);
                     dz <= std::min(map.m[2] - 1, z + 1); ++dz) {
                    for (std::int64_t dy = std::max<std::int64_t>(0, y - 1);
                         dy <= std::min(map.m[1] - 1, y + 1); ++dy) {
                        for (std::int64_t dx = std::max<std::int64_t>(0, x - 1);
                             dx <= std::min(map.m[0] - 1, x + 1); ++dx) {
                            const std::int32_t t =
                                inside[static_cast<std::size_t>(map.node(dx, dy, dz))];
                            if (t < 0) {
                                continue;
                            }
                            Vec3d p[4];
                            const TetMap m = tet_map(w, t, tf, sf, p);
                            double l[3];
                            const double score = m.lambda(node, l);
                            if (score > best) {
                                best = score;
                                const Vec3d rest = m.rest(l);
                                double* out = map.g.data() + 3 * q;
                                out[0] = rest.x;
                                out[1] = rest.y;
                                out[2] = rest.z;
                            }
                        }
                    }
                }
            }
        }
    }
}

// Every target voxel sampled through the map (what the ray caster would do per sample).
void sample_through_map(const Workload& w, const InverseMap& map, Volume& target) {
    const volume::detail::GridFrame tf = frame_of(target);
    const volume::detail::GridFrame sf = frame_of(w.source);
    const auto* src = reinterpret_cast<const std::uint8_t*>(w.source.bytes().data());
    auto* dst = reinterpret_cast<std::uint8_t*>(target.bytes().data());
    const double inv_b = 1.0 / map.b;
    for (std::int64_t k = 0; k < tf.n[2]; ++k) {
        for (std::int64_t j = 0; j < tf.n[1]; ++j) {
            for (std::int64_t i = 0; i < tf.n[0]; ++i) {
                const std::int64_t q[3] = {i / map.b, j / map.b, k / map.b};
                const double f[3] = {static_cast<double>(i % map.b) * inv_b,
                                     static_cast<double>(j % map.b) * inv_b,
                                     static_cast<double>(k % map.b) * inv_b};
                double g[3] = {0, 0, 0};
                bool valid = true;
                for (int corner = 0; corner < 8 && valid; ++corner) {
                    const int cx = corner & 1;
                    const int cy = (corner >> 1) & 1;
                    const int cz = corner >> 2;
                    const double weight = (cx != 0 ? f[0] : 1 - f[0]) *
                                          (cy != 0 ? f[1] : 1 - f[1]) * (cz != 0 ? f[2] : 1 - f[2]);
                    const double* v = map.g.data() + 3 * map.node(q[0] + cx, q[1] + cy, q[2] + cz);
                    valid = !std::isnan(v[0]);
                    for (int a = 0; a < 3; ++a) {
                        g[a] += weight * v[a];
                    }
                }
                std::uint8_t* out = dst + 4 * (i + tf.n[0] * (j + tf.n[1] * k));
                float s[4] = {0, 0, 0, 0};
                if (valid) {
                    volume::detail::sample_trilinear<std::uint8_t, 4>(src, sf.n, g[0], g[1], g[2],
                                                                      s);
                }
                for (int c = 0; c < 4; ++c) {
                    out[c] = volume::detail::convert_sample<std::uint8_t>(s[c], 1.0f);
                }
            }
        }
    }
}

// PSNR (dB, peak 255) of b against a, premultiplied (r·α, g·α, b·α, α with α in [0, 1]: what a
// ray caster composites; colour under α = 0 does not count), over all voxels or over the voxels
// where a's alpha > 0.
double psnr_rgba8(const Volume& a, const Volume& b, bool visible_only) {
    const auto* x = reinterpret_cast<const std::uint8_t*>(a.bytes().data());
    const auto* y = reinterpret_cast<const std::uint8_t*>(b.bytes().data());
    double sum = 0.0;
    std::int64_t count = 0;
    for (std::int64_t v = 0; v < a.num_voxels(); ++v) {
        if (visible_only && x[4 * v + 3] == 0) {
            continue;
        }
        const double ax = x[4 * v + 3] / 255.0;
        const double ay = y[4 * v + 3] / 255.0;
        for (int c = 0; c < 4; ++c) {
            const double wx = c < 3 ? ax : 1.0;
            const double wy = c < 3 ? ay : 1.0;
            const double d = wx * x[4 * v + c] - wy * y[4 * v + c];
            sum += d * d;
        }
        count += 4;
    }
    return count == 0 || sum == 0.0 ? 999.0 : 10.0 * std::log10(255.0 * 255.0 * count / sum);
}

void BM_InverseMapRoute(benchmark::State& state) {
    const Workload& w = workload(SOURCE_SCALE, 256);
    set_num_threads(1);
    Volume exact = make_target(w.source);
    w.resampler->resample(w.deformed, exact);
    InverseMap map;
    map.b = w.grid.cell_voxels;
    for (auto _ : state) {
        build_inverse_map(w, exact, map);
        benchmark::DoNotOptimize(map.g.data());
    }
    Volume through = make_target(w.source);
    sample_through_map(w, map, through);
    state.counters["nodes"] = static_cast<double>(map.g.size() / 3);
    state.counters["psnr_all_dB"] = psnr_rgba8(exact, through, false);
    state.counters["psnr_visible_dB"] = psnr_rgba8(exact, through, true);
    set_num_threads(0);
}
BENCHMARK(BM_InverseMapRoute)->Unit(benchmark::kMillisecond)->UseRealTime();

// Arguments: kind (0 phantom f32, 1 RGBA rgba8, 2 source scale rgba8), N, threads.
void resample_args(benchmark::internal::Benchmark* b) {
    b->ArgNames({"rgba", "N", "threads"});
    for (const std::int64_t kind : {PHANTOM, RGBA}) {
        for (const std::int64_t n : {128, 256}) {
            for (const std::int64_t threads : {1, 2}) {
                b->Args({kind, n, threads});
            }
        }
    }
    for (const std::int64_t threads : {1, 2}) {
        b->Args({SOURCE_SCALE, 256, threads});
    }
}

void brute_force_args(benchmark::internal::Benchmark* b) {
    b->ArgNames({"rgba", "N"});
    for (const std::int64_t kind : {PHANTOM, RGBA}) {
        for (const std::int64_t n : {128, 256}) {
            b->Args({kind, n});
        }
    }
    b->Args({SOURCE_SCALE, 256});
}

BENCHMARK(BM_Resample)->Apply(resample_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BruteForce)
    ->Apply(brute_force_args)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);
BENCHMARK(BM_Prepare)->Apply(resample_args)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
