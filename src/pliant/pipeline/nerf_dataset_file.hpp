// NeRF-synthetic / instant-ngp `transforms.json` datasets (docs/formats.md, "Radiance-field
// datasets"), read into nerf::Dataset and written by `pliant dataset`.
//
// Read:
//   - intrinsics: `w`, `h` (else the first image's size); `fl_x` / `fl_y` in pixels, else
//     `camera_angle_x` (horizontal field of view, radians: fx = w / 2 / tan(angle / 2)) and
//     `camera_angle_y` (fy likewise; default fy = fx); `cx`, `cy` (default w / 2, h / 2).
//   - `frames[]`: `file_path` relative to the JSON file's directory (with or without extension:
//     a path that does not name a file is tried with ".png" appended), `transform_matrix`
//     camera-to-world 4 × 4 (or 3 × 4) in OpenGL axes (nerf/dataset.hpp). Frames that name their
//     own intrinsics (instant-ngp's per-frame `fl_x` …) must agree with the file's.
//   - images: PNG (8 or 16 bit, grey, grey+alpha, RGB, RGBA; JPEG also decodes) through stb,
//     straight alpha composited over `background`: c · a + background · (1 − a).
//   - `aabb` [[xmin, ymin, zmin], [xmax, ymax, zmax]] (optional) → Dataset::box.
//   - instant-ngp's `scale`, `offset` and `aabb_scale` are not applied (Unsupported when `scale`
//     or `offset` differ from 1 and 0: they would move the scene).
// Errors: IoError "<json>: …" for a missing or unparsable file, missing keys, non-numeric or
// wrongly shaped matrices, "frames[i]: …" for a missing or undecodable image ("<resolved path>:
// no such file") or one whose size differs from w × h (checked from the image's header, before it
// is decoded), `w` / `h` outside [1, 65536]; InvalidInput (nerf::validate) for singular matrices
// and non-positive intrinsics, and, before any image is decoded, when the decoded images (12
// bytes per pixel) would need more than ReadNerfDatasetOptions::max_bytes.
//
// Write: write_transforms() writes `camera_angle_x`, `camera_angle_y`, `fl_x`, `fl_y`, `cx`, `cy`,
// `w`, `h`, `aabb` (when given) and `frames` (`file_path` without extension, as the Blender
// exports do, and the 4 × 4 `transform_matrix`), atomically.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "pliant/nerf/dataset.hpp"

namespace pliant::pipeline {

struct ReadNerfDatasetOptions {
    render::Color background{0.0f, 0.0f, 0.0f};  // what transparent pixels are composited over
    bool load_images = true;  // false: intrinsics and poses only (views' rgb left empty)
    std::size_t max_bytes = std::size_t{16} << 30;  // limit on the decoded images (bytes)
};

nerf::Dataset read_nerf_dataset(const std::filesystem::path& transforms_json,
                                const ReadNerfDatasetOptions& options = {});

// file_paths[i] (relative to the JSON's directory) and poses[i] per frame; InvalidInput when the
// counts differ.
void write_transforms(const std::filesystem::path& transforms_json,
                      const nerf::Intrinsics& intrinsics, std::span<const std::string> file_paths,
                      std::span<const nerf::Pose> poses, const std::optional<AABBd>& box);

}  // namespace pliant::pipeline
