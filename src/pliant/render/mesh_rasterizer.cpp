#include "pliant/render/mesh_rasterizer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/normals.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::render {

using detail::ClipVertex;
using detail::FIXED_ONE;
using detail::RasterTriangle;
using detail::ScreenVertex;

namespace {

// Tiles are TILE × TILE samples; each is rasterized by one task.
constexpr std::int32_t TILE = 64;
// Guard band around the image, in samples: clipping keeps every fixed-point coordinate within
// ±2^25, so edge functions (products of two coordinate differences) stay below 2^53.
constexpr double GUARD = 65536.0;
constexpr std::int64_t MAX_SAMPLES_PER_SIDE = 65536;
constexpr int NUM_PLANES = 5;  // near, x ≥ −G, x ≤ Ws + G, y ≥ −G, y ≤ Hs + G
constexpr int MAX_POLYGON = 3 + NUM_PLANES;

struct Frame {
    Vec3d eye, right, up, forward;
    double focal = 1.0;                 // samples per unit (of cx/depth or cx)
    double half_w = 0.0, half_h = 0.0;  // half the sample-space size
    double width_s = 0.0, height_s = 0.0;
    double near = 0.0;
    bool is_perspective = true;
};

ClipVertex to_clip(const Frame& f, Vec3d p) {
    const Vec3d d = p - f.eye;
    const double cx = dot(d, f.right), cy = dot(d, f.up), depth = dot(d, f.forward);
    if (f.is_perspective) {
        return {f.half_w * depth + f.focal * cx, f.half_h * depth - f.focal * cy, depth, depth};
    }
    return {f.half_w + f.focal * cx, f.half_h - f.focal * cy, 1.0, depth};
}

// Signed distances to the clip planes (inside ≥ 0).
std::array<double, NUM_PLANES> plane_distances(const Frame& f, const ClipVertex& v) {
    return {v.depth - f.near, v.X + GUARD * v.W, (f.width_s + GUARD) * v.W - v.X, v.Y + GUARD * v.W,
            (f.height_s + GUARD) * v.W - v.Y};
}

std::uint32_t outcode(const Frame& f, const ClipVertex& v) {
    const auto d = plane_distances(f, v);
    std::uint32_t code = 0;
    for (int p = 0; p < NUM_PLANES; ++p) {
        // NaN-safe: a NaN distance counts as outside (positions are validated finite, but huge
        // coordinates can still overflow).
        if (!(d[static_cast<std::size_t>(p)] >= 0.0)) {
            code |= 1u << p;
        }
    }
    return code;
}

// Projects a clip vertex. The fixed-point fields are meaningful when the vertex is inside every
// clip plane (outcode 0) or lies on the boundary of the clipped region (clipped vertices, which
// rounding may put a hair outside): coordinates are clamped to the guard band so they always fit.
ScreenVertex to_screen(const Frame& f, const ClipVertex& c) {
    ScreenVertex s{};
    s.clip = c;
    s.outcode = outcode(f, c);
    if (c.W > 0.0) {
        const double inv_w = 1.0 / c.W;
        const double x = std::clamp(c.X * inv_w, -GUARD, f.width_s + GUARD);
        const double y = std::clamp(c.Y * inv_w, -GUARD, f.height_s + GUARD);
        s.fx = static_cast<std::int32_t>(std::llround(x * FIXED_ONE));
        s.fy = static_cast<std::int32_t>(std::llround(y * FIXED_ONE));
        s.inv_w = static_cast<float>(inv_w);
        s.zkey = static_cast<float>(f.is_perspective ? inv_w : -c.depth);
    }
    return s;
}

// The first sample index whose centre k·ONE + ONE/2 is ≥ v, and the last whose centre is ≤ v.
std::int32_t first_sample_at_or_after(std::int64_t v) {
    const std::int64_t num = v - FIXED_ONE / 2;
    // ceil(num / ONE) for any sign
    return static_cast<std::int32_t>(num >= 0 ? (num + FIXED_ONE - 1) / FIXED_ONE
                                              : -((-num) / FIXED_ONE));
}
std::int32_t last_sample_at_or_before(std::int64_t v) {
    const std::int64_t num = v - FIXED_ONE / 2;
    return static_cast<std::int32_t>(num >= 0 ? num / FIXED_ONE
                                              : -((-num + FIXED_ONE - 1) / FIXED_ONE));
}

enum class Setup { drawn, degenerate, culled };

// Fills `out` from three screen vertices (outcode 0) and their source barycentrics. Orders the
// corners so that the doubled signed area is positive; front faces (counter-clockwise in the
// world seen from the eye) have a negative area in y-down sample space and are swapped.
Setup setup_triangle(const std::array<const ScreenVertex*, 3>& v,
                     const std::array<std::array<float, 3>, 3>& bary, std::int32_t width_s,
                     std::int32_t height_s, RasterTriangle& out) {
    const std::int64_t x0 = v[0]->fx, y0 = v[0]->fy;
    const std::int64_t area2 =
        (v[1]->fx - x0) * (v[2]->fy - y0) - (v[2]->fx - x0) * (v[1]->fy - y0);
    if (area2 == 0) {
        return Setup::degenerate;
    }
    std::array<int, 3> order{0, 1, 2};
    out.is_back_face = area2 > 0 ? 1u : 0u;
    if (area2 < 0) {
        order = {0, 2, 1};
    }
    std::int64_t lo_x = std::numeric_limits<std::int64_t>::max(), hi_x = -lo_x;
    std::int64_t lo_y = lo_x, hi_y = -lo_x;
    for (int k = 0; k < 3; ++k) {
        const ScreenVertex& s = *v[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
        out.fx[k] = s.fx;
        out.fy[k] = s.fy;
        out.zkey[k] = s.zkey;
        out.inv_w[k] = s.inv_w;
        for (int c = 0; c < 3; ++c) {
            out.bary[k][c] = bary[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])]
                                 [static_cast<std::size_t>(c)];
        }
        lo_x = std::min<std::int64_t>(lo_x, s.fx);
        hi_x = std::max<std::int64_t>(hi_x, s.fx);
        lo_y = std::min<std::int64_t>(lo_y, s.fy);
        hi_y = std::max<std::int64_t>(hi_y, s.fy);
    }
    out.min_x = std::max(0, first_sample_at_or_after(lo_x));
    out.max_x = std::min(width_s - 1, last_sample_at_or_before(hi_x));
    out.min_y = std::max(0, first_sample_at_or_after(lo_y));
    out.max_y = std::min(height_s - 1, last_sample_at_or_before(hi_y));
    if (out.min_x > out.max_x || out.min_y > out.max_y) {
        return Setup::culled;
    }
    return Setup::drawn;
}

struct PolygonVertex {
    ClipVertex c;
    std::array<float, 3> bary;
};

// Sutherland–Hodgman against every plane in `planes` (bit mask). A new vertex on an edge is
// interpolated from the edge's inside end towards its outside end, so two triangles sharing the
// edge produce bitwise the same point.
int clip_polygon(const Frame& f, std::uint32_t planes, PolygonVertex (&poly)[MAX_POLYGON],
                 int count) {
    PolygonVertex next[MAX_POLYGON];
    for (int p = 0; p < NUM_PLANES && count > 0; ++p) {
        if ((planes & (1u << p)) == 0) {
            continue;
        }
        int n = 0;
        for (int i = 0; i < count; ++i) {
            const PolygonVertex& a = poly[i];
            const PolygonVertex& b = poly[(i + 1) % count];
            const double da = plane_distances(f, a.c)[static_cast<std::size_t>(p)];
            const double db = plane_distances(f, b.c)[static_cast<std::size_t>(p)];
            const bool a_in = da >= 0.0, b_in = db >= 0.0;
            if (a_in) {
                next[n++] = a;
            }
            if (a_in != b_in) {
                const PolygonVertex& in = a_in ? a : b;
                const PolygonVertex& out = a_in ? b : a;
                const double d_in = a_in ? da : db, d_out = a_in ? db : da;
                const double t = d_in / (d_in - d_out);
                PolygonVertex m;
                m.c = {in.c.X + t * (out.c.X - in.c.X), in.c.Y + t * (out.c.Y - in.c.Y),
                       in.c.W + t * (out.c.W - in.c.W),
                       in.c.depth + t * (out.c.depth - in.c.depth)};
                for (std::size_t k = 0; k < 3; ++k) {
                    m.bary[k] = static_cast<float>(in.bary[k] + t * (out.bary[k] - in.bary[k]));
                }
                next[n++] = m;
            }
        }
        count = n;
        std::copy(next, next + n, poly);
    }
    return count;
}

struct SetupCounts {
    std::int64_t degenerate = 0, clipped = 0, culled = 0;
    SetupCounts& operator+=(const SetupCounts& o) {
        degenerate += o.degenerate;
        clipped += o.clipped;
        culled += o.culled;
        return *this;
    }
};

void validate_options(const RasterOptions& o) {
    if (o.samples_per_axis < 1 || o.samples_per_axis > 8) {
        throw InvalidInput(
            fmt::format("render: samples_per_axis {}, expected 1 to 8", o.samples_per_axis));
    }
    const auto non_negative = [](float v, const char* name) {
        if (!(v >= 0.0f) || !std::isfinite(v)) {
            throw InvalidInput(fmt::format("render: {} {}, expected a finite value >= 0", name, v));
        }
    };
    non_negative(o.key_intensity, "key_intensity");
    non_negative(o.fill_intensity, "fill_intensity");
    non_negative(o.ambient, "ambient");
    if (!(o.back_tint_weight >= 0.0f && o.back_tint_weight <= 1.0f)) {
        throw InvalidInput(fmt::format("render: back_tint_weight {}, expected a value in [0, 1]",
                                       o.back_tint_weight));
    }
    if (!is_finite(o.key_direction) || !(norm(o.key_direction) > 0.0)) {
        throw InvalidInput(
            fmt::format("render: key_direction ({}, {}, {}), expected a finite "
                        "nonzero vector",
                        o.key_direction.x, o.key_direction.y, o.key_direction.z));
    }
}

}  // namespace

MeshRasterizer::Source MeshRasterizer::source_of(std::uint32_t drawn) const {
    const RasterTriangle& t = m_triangles.at(drawn);
    return {t.mesh, t.triangle};
}

void MeshRasterizer::render(const Camera& camera, std::span<const RenderMesh> meshes,
                            const RasterOptions& options, Image& image) {
    // Step 1: validation, before anything is written.
    validate_options(options);
    const std::int32_t s = options.samples_per_axis;
    const std::int64_t width_s64 = std::int64_t{camera.width()} * s;
    const std::int64_t height_s64 = std::int64_t{camera.height()} * s;
    if (width_s64 > MAX_SAMPLES_PER_SIDE || height_s64 > MAX_SAMPLES_PER_SIDE) {
        throw InvalidInput(
            fmt::format("render: image {} x {} with {} samples per axis, expected "
                        "at most {} samples per side",
                        camera.width(), camera.height(), s, MAX_SAMPLES_PER_SIDE));
    }
    for (std::size_t m = 0; m < meshes.size(); ++m) {
        const std::string what = fmt::format("render: meshes[{}]", m);
        geometry::validate_positions(meshes[m].positions, what + ".positions");
        const std::span<const geometry::Triangle> tris = meshes[m].triangles;
        const std::size_t nv = meshes[m].positions.size();
        for (std::size_t t = 0; t < tris.size(); ++t) {
            for (int k = 0; k < 3; ++k) {
                if (tris[t][k] < 0 || static_cast<std::size_t>(tris[t][k]) >= nv) {
                    throw InvalidInput(
                        fmt::format("{}.triangles: triangle {} corner {} has vertex "
                                    "index {}, expected 0 <= index < {}",
                                    what, t, k, tris[t][k], nv));
                }
            }
        }
        if (tris.size() >= (std::size_t{1} << 31)) {
            throw InvalidInput(
                fmt::format("{}: {} triangles, at most 2^31 - 1 supported", what, tris.size()));
        }
    }

    const auto width_s = static_cast<std::int32_t>(width_s64);
    const auto height_s = static_cast<std::int32_t>(height_s64);
    Frame frame;
    frame.eye = camera.eye();
    frame.right = camera.right();
    frame.up = camera.up();
    frame.forward = camera.forward();
    frame.focal = camera.focal_pixels() * s;
    frame.half_w = 0.5 * static_cast<double>(width_s);
    frame.half_h = 0.5 * static_cast<double>(height_s);
    frame.width_s = static_cast<double>(width_s);
    frame.height_s = static_cast<double>(height_s);
    frame.near = camera.near();
    frame.is_perspective = camera.projection() == Projection::perspective;

    m_stats = {};
    m_triangles.clear();
    m_normals.resize(meshes.size());

    for (std::size_t m = 0; m < meshes.size(); ++m) {
        const std::span<const Vec3d> positions = meshes[m].positions;
        const std::span<const geometry::Triangle> tris = meshes[m].triangles;
        m_stats.triangles += static_cast<std::int64_t>(tris.size());

        // Step 2: area-weighted vertex normals (serial: a scatter, O(T), deterministic).
        std::vector<Vec3f>& normals = m_normals[m];
        normals.clear();
        if (meshes[m].smooth) {
            geometry::vertex_normals(positions, tris, normals, m_normal_sums);
        }

        // Step 3a: vertices to screen space (by index).
        m_vertices.resize(positions.size());
        parallel_for(static_cast<std::int64_t>(positions.size()), [&](std::int64_t v) {
            m_vertices[static_cast<std::size_t>(v)] =
                to_screen(frame, to_clip(frame, positions[static_cast<std::size_t>(v)]));
        });

        // Step 3b: triangle setup, clipping when needed; per-chunk output gathered in order.
        constexpr std::int64_t SETUP_GRAIN = 2048;
        const auto num_tris = static_cast<std::int64_t>(tris.size());
        m_chunk_triangles.reset(num_chunks(num_tris, SETUP_GRAIN));
        std::vector<SetupCounts> chunk_counts(
            static_cast<std::size_t>(num_chunks(num_tris, SETUP_GRAIN)));
        static constexpr std::array<std::array<float, 3>, 3> UNIT{
            {{1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 1.0f}}};
        parallel_for_chunks(
            num_tris, SETUP_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                AppendBuffer<RasterTriangle>& out = m_chunk_triangles.chunk(c);
                SetupCounts& counts = chunk_counts[static_cast<std::size_t>(c)];
                for (std::int64_t t = begin; t < end; ++t) {
                    const geometry::Triangle& tri = tris[static_cast<std::size_t>(t)];
                    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
                        ++counts.degenerate;
                        continue;
                    }
                    const std::array<const ScreenVertex*, 3> v{
                        &m_vertices[static_cast<std::size_t>(tri[0])],
                        &m_vertices[static_cast<std::size_t>(tri[1])],
                        &m_vertices[static_cast<std::size_t>(tri[2])]};
                    const std::uint32_t any_out = v[0]->outcode | v[1]->outcode | v[2]->outcode;
                    const std::uint32_t all_out = v[0]->outcode & v[1]->outcode & v[2]->outcode;
                    RasterTriangle rt{};
                    rt.mesh = static_cast<std::int32_t>(m);
                    rt.triangle = static_cast<std::int32_t>(t);
                    if (all_out != 0) {
                        ++counts.culled;
                        continue;
                    }
                    if (any_out == 0) {
                        switch (setup_triangle(v, UNIT, width_s, height_s, rt)) {
                            case Setup::drawn:
                                out.push_back(rt);
                                break;
                            case Setup::degenerate:
                                ++counts.degenerate;
                                break;
                            case Setup::culled:
                                ++counts.culled;
                                break;
                        }
                        continue;
                    }
                    // Clipped path: a convex polygon of up to 8 vertices, drawn as a fan. Its
                    // facing is that of the whole triangle (the fan's pieces keep the orientation).
                    ++counts.clipped;
                    PolygonVertex poly[MAX_POLYGON];
                    for (std::size_t k = 0; k < 3; ++k) {
                        poly[k] = {v[k]->clip, UNIT[k]};
                    }
                    const int n = clip_polygon(frame, any_out, poly, 3);
                    ScreenVertex sv[MAX_POLYGON];
                    for (int k = 0; k < n; ++k) {
                        sv[k] = to_screen(frame, poly[k].c);
                        // Clipped points lie on the boundary; rounding may put them a hair outside.
                        sv[k].outcode = 0;
                    }
                    for (int k = 1; k + 1 < n; ++k) {
                        const std::array<const ScreenVertex*, 3> fan{&sv[0], &sv[k], &sv[k + 1]};
                        const std::array<std::array<float, 3>, 3> bary{poly[0].bary, poly[k].bary,
                                                                       poly[k + 1].bary};
                        if (setup_triangle(fan, bary, width_s, height_s, rt) == Setup::drawn) {
                            out.push_back(rt);
                        }
                    }
                }
            });
        m_chunk_triangles.gather(m_mesh_triangles);
        m_triangles.insert(m_triangles.end(), m_mesh_triangles.begin(), m_mesh_triangles.end());
        for (const SetupCounts& counts : chunk_counts) {
            m_stats.degenerate_triangles += counts.degenerate;
            m_stats.clipped_triangles += counts.clipped;
            m_stats.culled_triangles += counts.culled;
        }
    }
    m_stats.drawn_triangles = static_cast<std::int64_t>(m_triangles.size());
    if (m_triangles.size() >= NO_TRIANGLE) {
        throw InvalidInput(fmt::format("render: {} triangles to draw, at most {} supported",
                                       m_triangles.size(), NO_TRIANGLE - 1));
    }

    // Step 4: binning into tiles (CSR, triangles in draw order within each tile).
    const std::int32_t tiles_x = (width_s + TILE - 1) / TILE;
    const std::int32_t tiles_y = (height_s + TILE - 1) / TILE;
    const auto num_tiles = static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y);
    m_bin_offsets.assign(num_tiles + 1, 0);
    for (const RasterTriangle& t : m_triangles) {
        for (std::int32_t ty = t.min_y / TILE; ty <= t.max_y / TILE; ++ty) {
            for (std::int32_t tx = t.min_x / TILE; tx <= t.max_x / TILE; ++tx) {
                ++m_bin_offsets[static_cast<std::size_t>(ty * tiles_x + tx) + 1];
            }
        }
    }
    for (std::size_t i = 0; i < num_tiles; ++i) {
        m_bin_offsets[i + 1] += m_bin_offsets[i];
    }
    m_bin_items.resize(static_cast<std::size_t>(m_bin_offsets[num_tiles]));
    {
        std::vector<std::int32_t> cursor(m_bin_offsets.begin(), m_bin_offsets.end() - 1);
        for (std::size_t i = 0; i < m_triangles.size(); ++i) {
            const RasterTriangle& t = m_triangles[i];
            for (std::int32_t ty = t.min_y / TILE; ty <= t.max_y / TILE; ++ty) {
                for (std::int32_t tx = t.min_x / TILE; tx <= t.max_x / TILE; ++tx) {
                    m_bin_items[static_cast<std::size_t>(
                        cursor[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x) +
                               static_cast<std::size_t>(tx)]++)] = static_cast<std::uint32_t>(i);
                }
            }
        }
    }

    // Step 5: rasterization, one task per tile; each tile owns its samples.
    const std::size_t num_samples =
        static_cast<std::size_t>(width_s) * static_cast<std::size_t>(height_s);
    m_sample_depth.resize(num_samples);
    m_sample_id.resize(num_samples);
    parallel_for(
        static_cast<std::int64_t>(num_tiles),
        [&](std::int64_t tile) {
            const auto tx = static_cast<std::int32_t>(tile % tiles_x);
            const auto ty = static_cast<std::int32_t>(tile / tiles_x);
            const std::int32_t x_begin = tx * TILE, x_end = std::min(width_s, x_begin + TILE);
            const std::int32_t y_begin = ty * TILE, y_end = std::min(height_s, y_begin + TILE);
            for (std::int32_t y = y_begin; y < y_end; ++y) {
                const std::size_t row =
                    static_cast<std::size_t>(y) * static_cast<std::size_t>(width_s);
                std::fill(m_sample_depth.begin() + static_cast<std::ptrdiff_t>(row + x_begin),
                          m_sample_depth.begin() + static_cast<std::ptrdiff_t>(row + x_end),
                          -std::numeric_limits<float>::infinity());
                std::fill(m_sample_id.begin() + static_cast<std::ptrdiff_t>(row + x_begin),
                          m_sample_id.begin() + static_cast<std::ptrdiff_t>(row + x_end),
                          NO_TRIANGLE);
            }
            float* const depth = m_sample_depth.data();
            std::uint32_t* const ids = m_sample_id.data();
            for (std::int32_t item = m_bin_offsets[static_cast<std::size_t>(tile)];
                 item < m_bin_offsets[static_cast<std::size_t>(tile) + 1]; ++item) {
                const std::uint32_t id = m_bin_items[static_cast<std::size_t>(item)];
                const RasterTriangle& t = m_triangles[id];
                const std::int32_t x0 = std::max(t.min_x, x_begin);
                const std::int32_t x1 = std::min(t.max_x, x_end - 1);
                const std::int32_t y0 = std::max(t.min_y, y_begin);
                const std::int32_t y1 = std::min(t.max_y, y_end - 1);
                // Edge k runs from corner k+1 to corner k+2; E_k(p) ≥ 0 inside and E_k / area2
                // is the barycentric weight of corner k. Top-left rule: a sample exactly on an
                // edge belongs to this triangle only if the edge is a top edge (horizontal, going
                // right) or a left edge (going up) in y-down sample space.
                std::int64_t ex[3], ey[3], ox[3], oy[3], bias[3];
                for (int k = 0; k < 3; ++k) {
                    const int a = (k + 1) % 3, b = (k + 2) % 3;
                    ox[k] = t.fx[a];
                    oy[k] = t.fy[a];
                    ex[k] = std::int64_t{t.fx[b]} - t.fx[a];
                    ey[k] = std::int64_t{t.fy[b]} - t.fy[a];
                    const bool is_top_left = (ey[k] == 0 && ex[k] > 0) || ey[k] < 0;
                    bias[k] = is_top_left ? 0 : -1;
                }
                const std::int64_t area2 = ex[2] * (std::int64_t{t.fy[2]} - oy[2]) -
                                           ey[2] * (std::int64_t{t.fx[2]} - ox[2]);
                const double inv_area = 1.0 / static_cast<double>(area2);
                const double z0 = t.zkey[0];
                const double c1 = (static_cast<double>(t.zkey[1]) - z0) * inv_area;
                const double c2 = (static_cast<double>(t.zkey[2]) - z0) * inv_area;
                const std::int64_t px0 = std::int64_t{x0} * FIXED_ONE + FIXED_ONE / 2;
                for (std::int32_t y = y0; y <= y1; ++y) {
                    const std::int64_t py = std::int64_t{y} * FIXED_ONE + FIXED_ONE / 2;
                    std::int64_t e[3];
                    for (int k = 0; k < 3; ++k) {
                        e[k] = ex[k] * (py - oy[k]) - ey[k] * (px0 - ox[k]) + bias[k];
                    }
                    const std::int64_t step0 = -ey[0] * FIXED_ONE, step1 = -ey[1] * FIXED_ONE,
                                       step2 = -ey[2] * FIXED_ONE;
                    const std::size_t row =
                        static_cast<std::size_t>(y) * static_cast<std::size_t>(width_s);
                    for (std::int32_t x = x0; x <= x1; ++x) {
                        if ((e[0] | e[1] | e[2]) >= 0) {
                            // Undo the bias for the weights (it is at most one unit in 2^16).
                            const auto z =
                                static_cast<float>(z0 + static_cast<double>(e[1] - bias[1]) * c1 +
                                                   static_cast<double>(e[2] - bias[2]) * c2);
                            const std::size_t i = row + static_cast<std::size_t>(x);
                            if (z > depth[i]) {
                                depth[i] = z;
                                ids[i] = id;
                            }
                        }
                        e[0] += step0;
                        e[1] += step1;
                        e[2] += step2;
                    }
                }
            }
        },
        1);

    // Step 6: shading and resolve, by image rows.
    const Vec3d key_camera = options.key_direction / norm(options.key_direction);
    const Vec3d key = key_camera.x * frame.right + key_camera.y * frame.up -
                      key_camera.z * frame.forward;  // camera z points towards the viewer
    const Vec3d view = -frame.forward;               // towards the eye (headlight)
    const float back_w = options.back_tint_weight;
    std::vector<Color> front_colors(meshes.size()), back_colors(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) {
        const Color c = meshes[m].color;
        front_colors[m] = c;
        back_colors[m] = {(1.0f - back_w) * c.r + back_w * options.back_tint.r,
                          (1.0f - back_w) * c.g + back_w * options.back_tint.g,
                          (1.0f - back_w) * c.b + back_w * options.back_tint.b};
    }
    const Vec3f key_f = vec3_cast<float>(key), view_f = vec3_cast<float>(view);
    const auto shade = [&](std::uint32_t id, std::int32_t sx, std::int32_t sy) {
        const RasterTriangle& t = m_triangles[id];
        const std::int64_t px = std::int64_t{sx} * FIXED_ONE + FIXED_ONE / 2;
        const std::int64_t py = std::int64_t{sy} * FIXED_ONE + FIXED_ONE / 2;
        const RenderMesh& mesh = meshes[static_cast<std::size_t>(t.mesh)];
        const geometry::Triangle& tri = mesh.triangles[static_cast<std::size_t>(t.triangle)];
        Vec3f n{};
        if (mesh.smooth) {
            // Screen-linear weights, then perspective-correct ones (weights / W, renormalized),
            // then barycentrics in the source triangle.
            float w[3];
            float sum = 0.0f;
            for (int k = 0; k < 3; ++k) {
                const int a = (k + 1) % 3, b = (k + 2) % 3;
                const std::int64_t e = (std::int64_t{t.fx[b]} - t.fx[a]) * (py - t.fy[a]) -
                                       (std::int64_t{t.fy[b]} - t.fy[a]) * (px - t.fx[a]);
                w[k] = static_cast<float>(e) * t.inv_w[k];
                sum += w[k];
            }
            const float inv_sum = 1.0f / sum;
            const std::vector<Vec3f>& normals = m_normals[static_cast<std::size_t>(t.mesh)];
            for (int c = 0; c < 3; ++c) {
                const float bc =
                    (w[0] * t.bary[0][c] + w[1] * t.bary[1][c] + w[2] * t.bary[2][c]) * inv_sum;
                n += bc * normals[static_cast<std::size_t>(tri[c])];
            }
        }
        float len = norm(n);
        if (!(len > 1e-6f)) {  // flat shading, or opposite normals cancelled: the face normal
            const Vec3d p0 = mesh.positions[static_cast<std::size_t>(tri[0])];
            n = vec3_cast<float>(cross(mesh.positions[static_cast<std::size_t>(tri[1])] - p0,
                                       mesh.positions[static_cast<std::size_t>(tri[2])] - p0));
            len = norm(n);
        }
        n = len > 0.0f ? n / len : view_f;
        Color base = front_colors[static_cast<std::size_t>(t.mesh)];
        if (t.is_back_face != 0) {
            n = -n;
            base = back_colors[static_cast<std::size_t>(t.mesh)];
        }
        const float light = options.ambient +
                            options.key_intensity * std::max(0.0f, dot(n, key_f)) +
                            options.fill_intensity * std::max(0.0f, dot(n, view_f));
        return Color{base.r * light, base.g * light, base.b * light};
    };
    image = Image(camera.width(), camera.height());
    const float inv_samples = 1.0f / static_cast<float>(s * s);
    parallel_for(
        camera.height(),
        [&](std::int64_t row) {
            const auto j = static_cast<std::int32_t>(row);
            for (std::int32_t i = 0; i < camera.width(); ++i) {
                // A pixel's samples covered by one triangle share one shading evaluation (at the
                // first of them), so the cost is per pixel and triangle, not per sample.
                constexpr int CACHE = 4;
                std::uint32_t cached_id[CACHE];
                Color cached_color[CACHE];
                int num_cached = 0;
                float r = 0.0f, g = 0.0f, bl = 0.0f;
                for (std::int32_t b = 0; b < s; ++b) {
                    const std::int32_t sy = j * s + b;
                    for (std::int32_t a = 0; a < s; ++a) {
                        const std::int32_t sx = i * s + a;
                        const std::uint32_t id = m_sample_id[static_cast<std::size_t>(sy) *
                                                                 static_cast<std::size_t>(width_s) +
                                                             static_cast<std::size_t>(sx)];
                        Color c = options.background;
                        if (id != NO_TRIANGLE) {
                            int hit = -1;
                            for (int q = 0; q < num_cached; ++q) {
                                if (cached_id[q] == id) {
                                    hit = q;
                                }
                            }
                            if (hit >= 0) {
                                c = cached_color[hit];
                            } else {
                                c = shade(id, sx, sy);
                                if (num_cached < CACHE) {
                                    cached_id[num_cached] = id;
                                    cached_color[num_cached++] = c;
                                }
                            }
                        }
                        r += c.r;
                        g += c.g;
                        bl += c.b;
                    }
                }
                image.set(i, j, to_rgb8({r * inv_samples, g * inv_samples, bl * inv_samples}));
            }
        },
        8);
}

Image render_meshes(const Camera& camera, std::span<const RenderMesh> meshes,
                    const RasterOptions& options) {
    MeshRasterizer rasterizer;
    Image image;
    rasterizer.render(camera, meshes, options, image);
    return image;
}

}  // namespace pliant::render
