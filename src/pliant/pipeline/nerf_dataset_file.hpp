// Radiance-field datasets on disk (docs/formats.md, "Radiance-field datasets"), read into
// nerf::Dataset: NeRF-synthetic / instant-ngp / nerfstudio `transforms.json` files and COLMAP
// sparse models; `transforms.json` written by `pliant dataset`.
//
// transforms.json, read:
//   - intrinsics, global or per frame (a frame's keys override the file's): `w`, `h` (else the
//     first image's size; per-frame sizes must equal the dataset's); `fl_x` / `fl_y` in pixels,
//     else `camera_angle_x` (horizontal field of view, radians: fx = w / 2 / tan(angle / 2)) and
//     `camera_angle_y` (fy likewise; default fy = fx); `cx`, `cy` (default w / 2, h / 2);
//     `camera_model` (nerf/lens.hpp: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV,
//     OPENCV_FISHEYE; absent: OPENCV when a distortion key is present — nerfstudio's and
//     instant-ngp's reading — with instant-ngp's `is_fisheye` OPENCV_FISHEYE, else PINHOLE)
//     and its coefficients `k1` `k2` `k3` `k4` `p1` `p2` (a coefficient the model lacks:
//     InvalidInput).
//   - `frames[]`: `file_path` relative to the JSON file's directory (a path that does not name a
//     file is tried with ".png", ".jpg", ".jpeg" appended), `transform_matrix` camera-to-world
//     4 × 4 (or 3 × 4) in OpenGL axes (nerf/dataset.hpp); `mask_path` (optional): an image of the
//     same size whose zero pixels are ignored in training and evaluation.
//   - images: PNG (8 or 16 bit, grey, grey+alpha, RGB, RGBA) or JPEG through stb, straight alpha
//     composited over `background`: c · a + background · (1 − a); with alpha_mask, pixels of
//     alpha 0 are also masked out.
//   - `aabb` [[xmin, ymin, zmin], [xmax, ymax, zmax]] (optional) → Dataset::box.
//   - instant-ngp's `aabb_scale` (a power of two in [1, 128]: the region beyond the unit cube it
//     renders as background) is validated; pliant reconstructs only the scene box, so a value
//     above 1 gives a warning. `scale` and `offset` other than 1 and 0: Unsupported (they would
//     move the scene).
//   - nerfstudio's `applied_transform` (the transform ns-process-data already applied to the
//     COLMAP world: the matrices are in the transformed frame) is validated as a 3 × 4 or 4 × 4
//     matrix and needs nothing more; `orientation_override` other than "none" gives a warning
//     (pliant never re-orients poses: they are used as written).
//   - Metadata read and not needed: `colmap_im_id` and `sharpness` per frame. Any other key
//     gives a warning that names it (log_warning); nothing is ignored silently.
// Errors: IoError "<json>: …" for a missing or unparsable file, missing keys, non-numeric or
// wrongly shaped matrices, "frames[i]: …" for a missing or undecodable image ("<resolved path>:
// no such file") or one whose size differs from w × h (checked from the image's header, before it
// is decoded), `w` / `h` outside [1, 65536]; InvalidInput (nerf::validate) for singular matrices,
// non-positive intrinsics and lenses that fold back inside the image, and, before any image is
// decoded, when the decoded images (12 bytes per pixel) would need more than
// ReadNerfDatasetOptions::max_bytes.
//
// COLMAP sparse models (read_colmap_dataset): a directory with cameras, images and points3D
// (io/colmap_model.hpp), converted and normalized by nerf::transforms_from_colmap (defaults:
// centre on the cameras' focus, the sparse points' 95 % extent scaled to the unit box), photos
// read from `images_dir` by their names in the model (default: <model>/../../images, COLMAP's
// layout sparse/0 beside images/); every frame carries its camera's intrinsics.
//
// Downscale N (> 1): each image (and mask) is box-filtered by N × N pixels (the mean of linear
// values; a mask keeps a pixel when all N × N do), ⌊w / N⌋ × ⌊h / N⌋ pixels (the right and bottom
// remainders dropped), and the intrinsics scale by 1 / N: fx, fy, cx, cy all divide by N. With
// pixel centres at (i + 0.5), pixel i' of the small image covers the large pixels
// [N i', N i' + N), whose extent's centre N (i' + 0.5) is exactly where the scaled cx puts it: no
// half-pixel shift. Lens coefficients act on normalized coordinates and do not change.
//
// Write: write_transforms() writes `camera_angle_x`, `camera_angle_y`, `fl_x`, `fl_y`, `cx`, `cy`,
// `w`, `h`, with a lens other than a distortion-free one `camera_model` and its coefficients,
// `aabb` (when given) and `frames` (`file_path` without extension, as the Blender exports do, and
// the 4 × 4 `transform_matrix`), atomically.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "pliant/nerf/colmap_poses.hpp"
#include "pliant/nerf/dataset.hpp"

namespace pliant::pipeline {

struct ReadNerfDatasetOptions {
    render::Color background{0.0f, 0.0f, 0.0f};  // what transparent pixels are composited over
    bool load_images = true;  // false: intrinsics and poses only (views' rgb left empty)
    std::size_t max_bytes = std::size_t{16} << 30;  // limit on the decoded images (bytes)
    int downscale = 1;        // box filter of N × N pixels (≥ 1; see the header comment)
    bool alpha_mask = false;  // pixels of alpha 0 are ignored (masked), besides composited
    std::filesystem::path images_dir{};      // COLMAP models: where the photos are (empty: default)
    nerf::ColmapConversionOptions colmap{};  // COLMAP models: the normalization
};

// A transforms.json file; a directory: a COLMAP model in it (read_colmap_dataset), else its
// transforms.json, else IoError saying what was expected.
nerf::Dataset read_nerf_dataset(const std::filesystem::path& transforms_json,
                                const ReadNerfDatasetOptions& options = {});

// A COLMAP sparse model directory and its photos (see the header comment).
nerf::Dataset read_colmap_dataset(const std::filesystem::path& model_dir,
                                  const ReadNerfDatasetOptions& options = {});

// file_paths[i] (relative to the JSON's directory) and poses[i] per frame; InvalidInput when the
// counts differ.
void write_transforms(const std::filesystem::path& transforms_json,
                      const nerf::Intrinsics& intrinsics, std::span<const std::string> file_paths,
                      std::span<const nerf::Pose> poses, const std::optional<AABBd>& box);

}  // namespace pliant::pipeline
