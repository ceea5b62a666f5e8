// Z-buffered, anti-aliased rasterization of triangle meshes into an RGB8 image: the shaded
// previews of `pliant cloth` (cloth, obstacles) and any other mesh view.
//
// Input: one or more RenderMesh views (positions #V world points, triangles #T index triples,
// counter-clockwise seen from the front side, a base colour). Nothing is copied between frames
// except per-call scratch kept by MeshRasterizer for reuse.
//
// Pipeline (one call to MeshRasterizer::render):
//   1. validate: every index in [0, #V) and every position finite, else InvalidInput;
//   2. vertex normals (smooth meshes): area-weighted sums of face normals (cross products),
//      normalized;
//   3. setup, parallel over fixed chunks of triangles: to camera space, clipped against the near
//      plane (depth ≥ camera.near()) and a guard band far outside the image (Sutherland–Hodgman,
//      a clipped edge's new vertex is computed from its inside end, so neighbours sharing the
//      edge get the same point), projected to sample space and snapped to a 1/256-sample fixed
//      point grid; zero-area and fully outside triangles are dropped (degenerate triangles are
//      data, not errors: they are counted in stats());
//   4. binning into square tiles (serial, in triangle order);
//   5. rasterization, parallel over tiles: exact integer edge functions with the top-left fill
//      rule (a sample on an edge belongs to the triangle to its right or below, so triangles
//      sharing an edge cover each sample exactly once); depth test on interpolated 1/depth
//      (perspective) or −depth (orthographic), the nearer wins, ties keep the earlier triangle
//      (meshes in order, triangles in order);
//   6. shading and resolve, parallel over rows: perspective-correct smooth normals, two-sided
//      (a back face is shaded with its normal flipped and its colour mixed with back_tint, so
//      folds of cloth read clearly), Lambert key light + headlight fill + ambient, the
//      samples_per_axis² samples of a pixel averaged (background where nothing was drawn), then
//      rounded to 8 bits.
// Samples of pixel (i, j) are at (i + (a + 0.5)/s, j + (b + 0.5)/s), a, b ∈ [0, s): with s = 1 the
// only sample is the pixel centre (i + 0.5, j + 0.5), the convention of Camera::pixel_ray.
//
// Determinism: every phase writes by index or in fixed order; the image is bitwise identical for
// any thread count. Threading only through core/parallel.hpp. Cost: O(V + T + samples);
// scratch (8 bytes per sample, about 100 bytes per drawn triangle, 4 bytes per vertex normal
// component) is kept by MeshRasterizer between calls.
// A MeshRasterizer is not safe for concurrent calls; distinct objects are independent.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/detail/raster_triangle.hpp"
#include "pliant/render/image.hpp"

namespace pliant::render {

struct RenderMesh {
    std::span<const Vec3d> positions;               // #V, world units
    std::span<const geometry::Triangle> triangles;  // #T, indices into positions
    Color color{0.75f, 0.75f, 0.78f};               // front-face base colour, components in [0, 1]
    // true: smooth shading with area-weighted vertex normals (cloth, spheres); false: flat
    // shading with face normals (boxes, planes: shapes with sharp edges).
    bool smooth = true;
};

struct RasterOptions {
    Color background{1.0f, 1.0f, 1.0f};
    int samples_per_axis = 2;  // 1 … 8: s × s samples per pixel
    // Directions towards the key light, in the camera frame (x right, y up, z towards the viewer);
    // need not be unit. The default lights from the upper left, in front of the object.
    Vec3d key_direction{-0.45, 0.6, 0.65};
    float key_intensity = 0.7f;   // Lambert key light
    float fill_intensity = 0.3f;  // Lambert headlight (from the eye)
    float ambient = 0.12f;
    // A back face's colour: (1 − back_tint_weight)·base + back_tint_weight·back_tint.
    Color back_tint{0.85f, 0.35f, 0.25f};
    float back_tint_weight = 0.55f;  // in [0, 1]
};

struct RasterStats {
    std::int64_t triangles = 0;             // input triangles, all meshes
    std::int64_t degenerate_triangles = 0;  // dropped for zero area on screen (or repeated index)
    std::int64_t clipped_triangles = 0;     // crossing the near plane or the guard band
    std::int64_t culled_triangles = 0;      // outside the view (behind near, off-screen), or
                                            // covering no sample
    std::int64_t drawn_triangles = 0;       // triangles after clipping, rasterized
};

class MeshRasterizer {
public:
    // Renders `meshes` (drawn in order) seen by `camera` into `image`, which is resized to the
    // camera's size. Throws InvalidInput (before writing anything) for a mesh with an index
    // outside [0, #V) or a non-finite position ("render: meshes[k].positions: vertex i …"), and
    // for options outside their ranges (samples_per_axis, intensities < 0 or non-finite,
    // back_tint_weight ∉ [0, 1], non-finite or zero key_direction).
    void render(const Camera& camera, std::span<const RenderMesh> meshes,
                const RasterOptions& options, Image& image);

    // Counts from the last render().
    const RasterStats& stats() const { return m_stats; }

    // Scratch for the last render(), public for tests: per sample (row-major in sample space,
    // (W·s) × (H·s)), the index of the drawn triangle that covers it (NO_TRIANGLE when none).
    static constexpr std::uint32_t NO_TRIANGLE = 0xffffffffu;
    std::span<const std::uint32_t> sample_triangles() const { return m_sample_id; }
    // Which input triangle each drawn triangle came from: mesh index and triangle index.
    struct Source {
        std::int32_t mesh;
        std::int32_t triangle;
    };
    Source source_of(std::uint32_t drawn) const;

private:
    RasterStats m_stats;
    std::vector<float> m_sample_depth;
    std::vector<std::uint32_t> m_sample_id;
    std::vector<std::vector<Vec3f>> m_normals;  // per mesh, per vertex
    std::vector<Vec3d> m_normal_sums;           // scratch of geometry::vertex_normals
    std::vector<detail::ScreenVertex> m_vertices;
    ChunkedBuffer<detail::RasterTriangle> m_chunk_triangles;
    std::vector<detail::RasterTriangle> m_mesh_triangles;
    std::vector<detail::RasterTriangle> m_triangles;  // drawn triangles, in draw order
    std::vector<std::int32_t> m_bin_offsets;          // per tile, CSR into m_bin_items
    std::vector<std::uint32_t> m_bin_items;
};

// One-off convenience: a MeshRasterizer's render into a new image.
Image render_meshes(const Camera& camera, std::span<const RenderMesh> meshes,
                    const RasterOptions& options = {});

}  // namespace pliant::render
