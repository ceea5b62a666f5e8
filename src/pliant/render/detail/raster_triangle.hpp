// Internal data of the mesh rasterizer (mesh_rasterizer.cpp): per-vertex screen records and the
// set-up triangles that are binned and rasterized. Trivially copyable, no pointers.
//
// Sample space: pixel coordinates times samples_per_axis s; sample (k, l) has its centre at
// (k + 0.5, l + 0.5). Fixed point: sample-space coordinates times FIXED_ONE (1/256 sample),
// rounded to nearest; the sample centre k + 0.5 is k·FIXED_ONE + FIXED_ONE/2.
#pragma once

#include <cstdint>
#include <type_traits>

namespace pliant::render::detail {

inline constexpr std::int64_t FIXED_ONE = 256;

// A vertex in homogeneous sample space: x_s = X / W, y_s = Y / W; W = depth (perspective) or 1
// (orthographic); depth along the camera's forward axis.
struct ClipVertex {
    double X, Y, W, depth;
};

struct ScreenVertex {
    ClipVertex clip;
    std::int32_t fx, fy;    // fixed-point sample coordinates (valid when outcode == 0)
    float zkey;             // depth-test key, larger is nearer: 1/depth or −depth
    float inv_w;            // 1/W, for perspective-correct interpolation
    std::uint32_t outcode;  // bit p set: outside clip plane p
};

struct RasterTriangle {
    std::int32_t fx[3], fy[3];  // fixed-point corners, ordered so that the doubled signed area > 0
    float zkey[3];
    float inv_w[3];
    float bary[3][3];  // barycentric coordinates in the source triangle of each corner
    std::int32_t min_x, min_y, max_x, max_y;  // covered sample range, inclusive, inside the image
    std::int32_t mesh, triangle;              // the source triangle
    std::uint32_t is_back_face;               // 1 when the source triangle faces away
};
static_assert(std::is_trivially_copyable_v<RasterTriangle>);

}  // namespace pliant::render::detail
