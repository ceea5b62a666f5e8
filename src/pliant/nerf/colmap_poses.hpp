// COLMAP sparse models (io/colmap_model.hpp) → posed frames in the radiance-field convention
// (nerf/dataset.hpp: camera-to-world, OpenGL axes), normalized so the scene sits in the unit
// box — shared by `pliant nerf train SPARSE_DIR` and `pliant nerf poses`.
//
// Per image, COLMAP stores world-to-camera x_cam = R(q) x + t with OpenCV camera axes (x right,
// y down, z forward). The camera-to-world pose in OpenGL axes (y up, looking down −z) is
//   [Rᵀ · diag(1, −1, −1) | C],   C = −Rᵀ t   (the camera centre),
// then the world similarity x' = s · Q · (x − c) is applied: R' = Q Rᵀ diag(1, −1, −1) (no scale
// in the rotation), t' = s · Q · (C − c).
//
// Normalization (ColmapConversionOptions, defaults in brackets):
//   - orientation Q [identity]: with orient_up, the rotation taking the mean of the cameras' up
//     axes to +z (nerfstudio's "up" orientation; the smallest rotation, Rodrigues).
//   - centre c [focus]: `focus` the point nearest, in least squares, to every camera's optical
//     axis (what a capture walking around an object looks at; instant-ngp's colmap2nerf does
//     the same), falling back to the cameras' mean when the axes are nearly parallel;
//     `camera_mean` nerfstudio's "poses" centring; `none` c = 0.
//   - scale s [points]: `points` the 3-D points' distance quantile: s = 1 / q where q is the
//     `points_quantile` (0.95) quantile over points3D of max(|x' − c|) per axis, so that that
//     fraction of the sparse points (the object, mostly) falls inside [−1, 1]³; with fewer than
//     8 points it falls back to `cameras`: s = 1 / max over cameras and axes of |C − c|
//     (nerfstudio's auto_scale_poses: the cameras inside [−1, 1]³); `none` s = 1.
// Frames come sorted by image name (the order nerfstudio and `nerf poses` use).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pliant/io/colmap_model.hpp"
#include "pliant/nerf/dataset.hpp"

namespace pliant::nerf {

enum class ColmapCentre { none, focus, camera_mean };
enum class ColmapScale { none, cameras, points };

struct ColmapConversionOptions {
    bool orient_up = false;
    ColmapCentre centre = ColmapCentre::focus;
    ColmapScale scale = ColmapScale::points;
    double points_quantile = 0.95;  // in (0, 1]
};

struct ColmapFrame {
    std::string file_path;  // the image's name in the model (relative to its image directory)
    std::uint32_t image_id = 0;
    Intrinsics intrinsics;  // of the image's camera (every frame carries its own)
    Pose camera_to_world;   // OpenGL axes, normalized world
};

struct ColmapTransforms {
    std::vector<ColmapFrame> frames;  // sorted by file_path
    // The similarity applied to COLMAP's world: x' = world_from_colmap · [x; 1], row-major 3 × 4
    // (s · Q | −s · Q · c); nerfstudio files call the rotation part `applied_transform`.
    std::array<double, 12> world_from_colmap{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    Vec3d centre;                                // c, COLMAP world
    double scale = 1.0;                          // s
    ColmapScale scale_used = ColmapScale::none;  // `points` may have fallen back to `cameras`
    std::vector<Vec3d> points;                   // points3D in the normalized world
    std::vector<std::array<std::uint8_t, 3>> point_colors;
};

// The intrinsics of a COLMAP camera (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV,
// OPENCV_FISHEYE; their parameter orders as in COLMAP). Unsupported naming the model for the
// others (FULL_OPENCV, FOV, …): convert them with `colmap image_undistorter`.
Intrinsics intrinsics_from_colmap(const io::ColmapCamera& camera);
// The COLMAP camera of intrinsics (the inverse: the model of intrinsics.lens, its parameters).
io::ColmapCamera colmap_camera_from_intrinsics(const Intrinsics& intrinsics, std::uint32_t id);

// World-to-camera (qvec (w, x, y, z), tvec) → camera-to-world OpenGL axes, unnormalized. The
// quaternion is normalized first; InvalidInput when its norm is ~0.
Pose pose_from_colmap(const std::array<double, 4>& qvec, const std::array<double, 3>& tvec);
// The inverse for a pose with an orthonormal rotation (det +1): qvec with qw ≥ 0.
void colmap_from_pose(const Pose& pose, std::array<double, 4>& qvec, std::array<double, 3>& tvec);

// All registered images of the model as frames, normalized (see the header comment).
// InvalidInput when the model has no images, Unsupported for unusable camera models.
ColmapTransforms transforms_from_colmap(const io::ColmapModel& model,
                                        const ColmapConversionOptions& options = {});

}  // namespace pliant::nerf
