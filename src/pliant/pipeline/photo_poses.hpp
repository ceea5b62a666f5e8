// Camera poses and intrinsics from a folder of photos, by COLMAP (Debian package `colmap`, 3.8,
// CPU), written as a posed-image dataset in nerfstudio's convention.
//
// recover_photo_poses(photos, out, options, on_stage, keep_going):
//   Step 1 (before COLMAP runs): the photos are the regular files of `photos` ending in .jpg,
//     .jpeg or .png (any case), in name order; every one is decoded (stb) and must have the size
//     of the first (one shared camera needs one size). InvalidInput for a folder that is missing
//     or holds no photos, IoError listing every unreadable photo, InvalidInput naming two photos
//     of different sizes. Then COLMAP missing from $PATH → IoError saying to install it with
//     `apt-get install colmap`.
//   Step 2: COLMAP in `out/colmap/` (database.db and sparse/ are removed first so a rerun starts
//     afresh), its standard output and error appended to `out/colmap/log.txt`:
//       feature_extractor   --ImageReader.single_camera 1 --ImageReader.camera_model OPENCV
//                           --SiftExtraction.use_gpu 0
//       exhaustive_matcher  --SiftMatching.use_gpu 0  (sequential_matcher above
//                           options.sequential_above photos, or as options.matcher says)
//       mapper              → out/colmap/sparse/N/ (--Mapper.ba_refine_principal_point 1
//                           unless !options.refine_principal_point: COLMAP keeps the principal
//                           point at the image centre by default, and a phone's is off centre)
//     COLMAP needs no display or OpenGL for these with use_gpu 0. A stage that fails gives IoError
//     with the last lines of the log and the log's path.
//   Step 3: the model registering the most photos is read (io/colmap_model.hpp) and turned into
//     camera-to-world poses in OpenGL axes, normalised by nerf::transforms_from_colmap
//     (nerf/colmap_poses.hpp) with orient_up: the mean of the cameras' up vectors becomes +z,
//     the point nearest (least squares) to all optical axes — what the cameras look at — the
//     origin, and the scale puts 95 % of the sparse points (the object and what it stands on,
//     mostly) inside the unit box [−1, 1]³ (docs/formats.md, "`pliant nerf poses`").
//     Fewer than half of the photos registered → InvalidInput naming the photos left out and what
//     usually helps (more overlap between neighbouring photos, textured surfaces, less motion
//     blur).
//   Step 4 (outputs, each replaced atomically): out/transforms_train.json and
//     out/transforms_test.json (every options.test_every-th registered photo in name order, from
//     the first, is in test; the rest in train; test_every 0 puts all in train and writes an
//     empty test list), with `camera_model` "OPENCV", `fl_x`, `fl_y`, `cx`, `cy`, `w`, `h`, `k1`,
//     `k2`, `p1`, `p2`, `aabb` [[−1, −1, −1], [1, 1, 1]] (the unit box above: the scene box
//     `nerf train` reconstructs) and frames of `file_path` (relative to `out` when possible) and
//     `transform_matrix` (4 × 4 camera-to-world, OpenGL axes); out/points.ply (the sparse points
//     in the dataset frame, with colours); out/poses.json (the report below and the normalisation
//     dataset_from_colmap: the 4 × 4 similarity from COLMAP's world).
// Result (also `json`): photos, registered, unregistered names, mean reprojection error in pixels
// (COLMAP's: over all observations of all points), points, seconds per stage.
// keep_going is polled about every 50 ms while COLMAP runs; false kills COLMAP (SIGTERM, then
// SIGKILL) and throws Interrupted; nothing is written outside out/colmap/ then.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/pipeline/progress.hpp"

namespace pliant::pipeline {

struct PhotoPosesOptions {
    int test_every = 8;                  // every N-th registered photo is held out; 0: none
    std::string matcher = "auto";        // auto | exhaustive | sequential
    int sequential_above = 150;          // auto: sequential matching above this many photos
    int threads = 0;                     // COLMAP threads per stage; 0: all cores
    bool refine_principal_point = true;  // bundle adjustment refines cx, cy too
    std::filesystem::path colmap;        // the COLMAP executable; empty: `colmap` on $PATH
};

struct StageTime {
    std::string name;  // features, matching, mapping, export
    double seconds = 0.0;
};

struct PhotoPosesResult {  // NOLINT(bugprone-exception-escape): json's default constructor
    int num_photos = 0;
    int num_registered = 0;
    std::vector<std::string> unregistered;  // photo file names
    double mean_reprojection_error_px = 0.0;
    std::int64_t num_points = 0;
    std::vector<StageTime> stages;
    nerf::Intrinsics intrinsics;  // with the OPENCV lens (k1, k2, p1, p2)
    // dataset point = world_from_colmap · [COLMAP point; 1] (row-major 3 × 4: s · Q | −s · Q · c)
    std::array<double, 12> world_from_colmap{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    double scale = 1.0;                    // s
    std::vector<std::string> train, test;  // photo file names in each split
    nlohmann::ordered_json json;
};

// Called when a stage starts: its name, its index (0-based) and the number of stages; and while
// it runs with `fraction` in [0, 1] when COLMAP's log tells (features: files processed; mapping:
// photos registered), −1 otherwise.
using PhotoPosesStageFn =
    std::function<void(const std::string& stage, int index, int count, double fraction)>;

PhotoPosesResult recover_photo_poses(const std::filesystem::path& photos,
                                     const std::filesystem::path& out,
                                     const PhotoPosesOptions& options,
                                     const PhotoPosesStageFn& on_stage = {},
                                     const KeepGoingFn& keep_going = {});

// The photos recover_photo_poses would use (step 1's listing, without decoding): regular files
// ending in .jpg, .jpeg, .png in any case, sorted by name. InvalidInput for a missing folder.
std::vector<std::filesystem::path> list_photos(const std::filesystem::path& photos);

}  // namespace pliant::pipeline
