// Posed-image datasets for radiance-field reconstruction (the in-memory form; io/nerf_dataset.hpp
// reads and writes the NeRF-synthetic / instant-ngp `transforms.json` files).
//
// Conventions (docs/formats.md, "Radiance-field datasets"):
//   - Pose: the camera-to-world matrix of the file, OpenGL axes: the camera looks down its −z
//     axis, +y is the image's up, +x its right. Rows r0, r1, r2 of the 3 × 4 matrix [R | t]: the
//     columns of R are the camera's x, y, z axes in world coordinates, t is the eye. R may carry a
//     uniform scale (rays are normalized); it must not be singular.
//   - Pixels: continuous coordinates (x, y) with the origin at the image's top-left corner, y
//     down; pixel (i, j) has its centre at (i + 0.5, j + 0.5) (instant-ngp's convention, and the
//     one of render::Camera). The ray through (x, y) has the camera-frame direction
//       ((x − cx) / fx, −(y − cy) / fy, −1)
//     rotated by R and normalized; it starts at the eye t.
//   - Colours: linear floats in [0, 1] as stored in the PNG (no gamma curve), already composited
//     over the dataset's background colour where the image had an alpha channel.
//   - World units: whatever the file uses (the Blender scenes: metres; `pliant dataset`: the
//     volume's units, millimetres for medical volumes).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/nerf/lens.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"

namespace pliant::nerf {

// Intrinsics in pixels: a pinhole projection through a lens model (nerf/lens.hpp).
struct Intrinsics {
    int width = 0;
    int height = 0;
    double fx = 0.0;  // focal length along x, pixels
    double fy = 0.0;  // focal length along y, pixels
    double cx = 0.0;  // principal point, continuous pixel coordinates
    double cy = 0.0;
    Lens lens;  // PINHOLE (no distortion) unless the dataset names a model
};

// Camera-to-world 3 × 4 matrix [R | t], row-major (m[4 r + c]).
struct Pose {
    std::array<double, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    Vec3d axis(int c) const { return {m[c], m[4 + c], m[8 + c]}; }  // column c of R
    Vec3d eye() const { return {m[3], m[7], m[11]}; }
    double determinant() const;  // det R
};

struct View {
    std::string name;  // the frame's file_path as written in the file
    Pose camera_to_world;
    std::vector<float> rgb;  // 3 · width · height, row-major from the top-left, in [0, 1]
};

struct Dataset {
    Intrinsics intrinsics;
    std::vector<View> views;
    std::optional<AABBd> box;  // the scene box of the file (`aabb`), when it has one
    render::Color background{0.0f, 0.0f, 0.0f};  // what transparent pixels were composited over
};

// The ray through continuous pixel coordinates (x, y) (see the header comment).
render::Ray view_ray(const Intrinsics& intrinsics, const Pose& pose, double x, double y);

// The pose and intrinsics of a perspective render::Camera (its right, up, −forward as the axes,
// its eye as t; fx = fy = focal_pixels, principal point at the image centre), so that view_ray
// gives the rays of Camera::ray. InvalidInput for an orthographic camera.
Pose pose_from_camera(const render::Camera& camera);
Intrinsics intrinsics_from_camera(const render::Camera& camera);

// The render::Camera of a view, for the volume ray caster. Needs what render::Camera models:
// square pixels (|fx − fy| ≤ 1e-6 fx), the principal point at the image centre (within 1e-3
// pixel) and a rotation without scale or shear (orthonormal within 1e-4); Unsupported naming the
// values otherwise.
render::Camera camera_from_view(const Intrinsics& intrinsics, const Pose& pose);

// The dataset's scene box: `box` when the file has one, otherwise one derived from the cameras:
// centred at the point nearest (least squares) to all optical axes, a cube of half-side
// r = min over views of (distance to the centre) · tan(half the smaller field of view) / √3
// (the largest cube whose bounding sphere every camera sees whole). InvalidInput when there are
// no views or the optical axes are all parallel.
AABBd scene_box(const Dataset& dataset);

// InvalidInput (naming the view and the values) unless the intrinsics are positive and finite,
// there is at least one view, every pose is finite with |det R| > 1e-12 · (scale of R)³, and
// every image has 3 · width · height values.
void validate(const Dataset& dataset);

// A view's colours as an 8-bit image (rounded, clamped), and back.
render::Image to_image(const Intrinsics& intrinsics, const View& view);
std::vector<float> from_image(const render::Image& image);

}  // namespace pliant::nerf
