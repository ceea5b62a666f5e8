// The radiance-field pipeline's steps, as `pliant dataset`, `pliant nerf train`, `pliant nerf eval`
// and `pliant demo` run them.
//
//   render_dataset:  a volume → a posed-image dataset on disk (PNGs + transforms_*.json);
//   train_volume:    a dataset → a trained radiance field exported as an RGBA volume, optionally
//                    cleaned (threshold on the 0–255 alpha scale, alpha normalization);
//   evaluate_volume: an RGBA volume ray-cast from a dataset's views → PSNR / SSIM per view.
// Each returns its numbers as the JSON object of its command (docs/formats.md).
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <functional>
#include <optional>

#include "pliant/core/function_ref.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/nerf/environment_map.hpp"
#include "pliant/nerf/export.hpp"
#include "pliant/nerf/render.hpp"
#include "pliant/nerf/trainer.hpp"
#include "pliant/volume/clean.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {

struct DatasetRunOptions {
    int views = 100;                           // train + test
    std::array<int, 2> size{200, 200};         // pixels
    double fov = 40.0;                         // vertical field of view, degrees
    int test_every = 10;                       // view i is a test view when i % test_every == 0
    std::array<float, 3> background{0, 0, 0};  // what the rays end on
    double step = 0.0;  // ray-casting step, world units (0: half the smallest spacing)
};

// Renders `options.views` views of `source` on a Fibonacci sphere (view i at height
// z_i = 1 − (2 i + 1) / N, azimuth i · 137.508°), each framing the volume's world box
// (Volume::world_bounds, render::frame_box; an oblique volume is rendered as it lies), into
// dir/train/r_<i>.png and dir/test/r_<i>.png with dir/transforms_train.json and
// dir/transforms_test.json (the box as `aabb`). tf: the transfer function of a scalar source,
// nullptr for RGBA. Returns {output, views, train, test, width, height, ms}. IoError when the
// directories cannot be made.
nlohmann::ordered_json render_dataset(const volume::Volume& source,
                                      const volume::TransferFunction* tf,
                                      const DatasetRunOptions& options,
                                      const std::filesystem::path& dir);

struct TrainRunOptions {
    nerf::TrainOptions train;
    nerf::ExportOptions exported;
    std::optional<volume::CleanOptions> clean;  // none: the exported volume as it is
    // Called after every training iteration (nerf::train's progress); empty: none.
    std::function<void(const nerf::TrainProgress&)> on_progress;
    // Checkpoints (io/checkpoint.hpp, nerf::TrainCheckpoints): the trainer's state every
    // checkpoint_every iterations and when stopped, to `checkpoint` (atomically; empty: none);
    // removed once training completes. With resume, training continues from `checkpoint` when
    // it exists (from the start otherwise): with --iterations and the same thread count the
    // volume is bitwise identical to an uninterrupted run's. A corrupt, truncated or foreign
    // checkpoint (another dataset or training options) is InvalidInput naming the file.
    std::filesystem::path checkpoint;
    std::int64_t checkpoint_every = 0;
    bool resume = false;
    // Held-out views (e.g. transforms_test.json, read as `dataset` was): after training, the
    // field itself — with its learned environment map, or over the dataset's background — is
    // rendered from them and scored (evaluate_field), into json["test"]; compare: that
    // function's side-by-side PNG. nullptr: none.
    const nerf::Dataset* test = nullptr;
    std::filesystem::path compare;
    // The exported region: none the scene box; a box in the dataset's frame; auto_crop the
    // object found by nerf::auto_crop (nerf/crop.hpp) in the trained field.
    std::optional<AABBd> crop;
    bool auto_crop = false;
    // With camera refinement (train.refine_poses / refine_focal): the held-out views are scored
    // from their poses moved by nerf::transfer_refinement and with the refined focal lengths;
    // refined_poses (non-empty): the training views' refined cameras written there as a
    // transforms.json (nerf_dataset_file.hpp's write_transforms; file_path as read).
    std::filesystem::path refined_poses;
};

// clang-tidy 14 cannot see that the implicit members (moving a Volume and a JSON object) do not
// throw.
struct TrainRunResult {           // NOLINT(bugprone-exception-escape)
    volume::Volume volume;        // exported (and cleaned)
    bool stopped = false;         // keep_going returned false
    nlohmann::ordered_json json;  // iterations, seconds, train_psnr, resolution, grid_dims,
                                  // occupied_cells, volume_dims, volume_spacing, peak_rss_bytes,
                                  // interrupted
};

// Trains a field on `dataset` (nerf::train) and exports it. keep_going is asked after every
// iteration; false stops training and the field so far is exported. InvalidInput before training
// when the exported volume would exceed options.exported.max_bytes.
TrainRunResult train_volume(const nerf::Dataset& dataset, const TrainRunOptions& options,
                            FunctionRef<bool()> keep_going);

// Renders the trained field (nerf::render_view with `environment`, or over `background` when it
// is empty) from every view of `dataset` and compares with the views' images as evaluate_volume
// does (masks likewise). With compare_png: up to 4 views evenly spaced in the list, each a column
// of the photo above its render, written atomically. Returns {psnr, ssim, views: [{file_path,
// psnr, ssim}]}.
nlohmann::ordered_json evaluate_field(const nerf::Dataset& dataset, const nerf::RadianceGrid& grid,
                                      const nerf::EnvironmentMap& environment,
                                      const std::array<float, 3>& background,
                                      const std::filesystem::path& compare_png = {});

// Ray-casts the RGBA `volume` (render::RayCaster's defaults) from every view of `dataset` over
// `background` and compares with the views' images: views that render::Camera models (square
// pixels, centred principal point, no distortion) through it, others through their per-pixel
// rays (nerf::view_ray, RayCaster::render_rays); a view's masked pixels are left out of its PSNR
// and set to the reference for its SSIM. With images_dir, writes the renders as
// images_dir/<i>.png. Returns {psnr, ssim, views: [{file_path, psnr, ssim}]} (means over the
// views). InvalidInput when the volume is not RGBA.
nlohmann::ordered_json evaluate_volume(const nerf::Dataset& dataset, const volume::Volume& volume,
                                       const std::array<float, 3>& background,
                                       const std::filesystem::path& images_dir = {});

// The process's peak resident set size so far (bytes).
std::int64_t peak_rss_bytes();

}  // namespace pliant::pipeline
