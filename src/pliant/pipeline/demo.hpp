// The steps of `pliant demo` (everything pliant does, end to end, on embedded and installed data)
// as library calls, so that a C++ or Python caller can run any of them; the CLI's demo command
// calls them in order and prints what they return. Each step writes its files under the
// directory it is given (created if missing, each file atomically) and returns its numbers as the
// JSON object that summary.json holds for it (docs/formats.md). Throws IoError when a directory
// cannot be created or written and what the pipelines it runs throw.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "pliant/nerf/trainer.hpp"
#include "pliant/pipeline/progress.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {

// The demo's volume: the first installed of the Colin27 MRI brain (Debian mricron-data) and the
// InVesalius head CT (invesalius-examples), else a generated 128³ Shepp-Logan phantom, with the
// transfer-function preset that suits it.
struct DemoVolume {
    volume::Volume volume;
    std::string source = "generated: 3D Shepp-Logan phantom, 128^3";
    std::string preset = "grayscale";
};
DemoVolume load_demo_volume();

// A step's JSON and the file a person should look at (a video, or a PNG without ffmpeg).
struct DemoStep {
    nlohmann::ordered_json json;
    std::string watch;
};

// The volume ray-cast (shaded) into DIR/volume/volume.png (512²) and a 36-frame turntable
// DIR/volume/turntable.mp4 (384²; PNG frames without ffmpeg). JSON: source, dims,
// transfer_function, png, png_ms, turntable, turntable_ms_per_frame.
nlohmann::ordered_json render_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo);

// The deformable-volume pipeline on `source` with the twist driver: the slab at +y turned 90°
// against the slab at −y over 2 s, 24 frames per second, resampled and ray-cast (shaded, 384²)
// every frame: OUT/twist.mp4 (none without ffmpeg), twist.png (the last frame) and
// twisted.nrrd. tf: for a scalar source, nullptr for RGBA. JSON: run_deform's (deform_run.hpp).
DemoStep twist_volume(const volume::Volume& source, const volume::TransferFunction* tf,
                      const std::filesystem::path& out, int frames, const ProgressFn& progress);

// The demo volume twisted (twist_volume) into DIR/deform.
DemoStep deform_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo, int frames,
                            const ProgressFn& progress);

struct ReconstructOptions {
    int views = 100;              // the dataset's views (every 10th held out)
    double minutes = 2.0;         // the training budget
    std::int64_t iterations = 0;  // > 0: a fixed iteration count instead (reproducible)
    int resolution = 128;         // the field's final grid, voxels on the longest side
    int deform_frames = 48;       // frames of the twist of the reconstruction
    ProgressFn progress;          // the twist's frames
    std::function<void(const nerf::TrainProgress&)> on_train_progress;  // every iteration
};

// The source system's pipeline from images: a posed-image dataset rendered from the demo volume
// (DIR/nerf/dataset, 200 × 200), a radiance field trained on the training views and exported as
// an RGBA volume (DIR/nerf/reconstructed.nrrd), scored on the held-out views (PSNR, SSIM;
// DIR/nerf/compare.png: held-out view 0, its reconstruction, the cleaned reconstruction), cleaned
// as in the paper (threshold 5 on the 0–255 alpha scale, then alpha normalization:
// DIR/nerf/cleaned.nrrd), then twisted like deform_demo_volume: DIR/nerf/twist.mp4, twist.png,
// twisted.nrrd. JSON: dataset, train, held_out_psnr, held_out_ssim, cleaned_held_out_psnr,
// compare_png, cleaned, deform.
DemoStep reconstruct_demo_volume(const std::filesystem::path& dir, const DemoVolume& demo,
                                 const ReconstructOptions& options);

// Frames the drape falls without self-collision before it is untangled.
inline constexpr int UNTANGLE_FALL_FRAMES = 16;

// Untangling: the drape scene (drape_json) without self-collision for UNTANGLE_FALL_FRAMES frames,
// DIR/untangle/fall/scene.json run into DIR/untangle/fall (the sheet falls through itself); a
// scene whose cloth is that run's last frame, DIR/untangle/scene.json (the drape's other keys,
// `frames` frames; the frame is the new cloth's rest shape), run into DIR/untangle: untangled
// before frame 0, then simulated with self-collision; and two sheets crossing like an X,
// untangled by a region move and dropped on the ground: DIR/untangle/crossing/. Each scene is
// written beside its outputs and read back from there, so `pliant cloth SCENE --out DIR`
// reproduces it. JSON: fall_scene, fall_dir, fall_frames, fall_intersecting_pairs, fall_preview,
// scene, dir, frames, initial_intersecting_pairs, untangle, max_intersecting_pairs,
// mean_ms_per_frame, preview, crossing {scene, dir, initial_intersecting_pairs, untangle,
// max_intersecting_pairs, preview}.
nlohmann::ordered_json untangle_demo(const std::filesystem::path& dir, const char* drape_json,
                                     int frames, const ProgressFn& progress);

// A cloth run's preview (its stats.json object): the path, or null when none was made.
nlohmann::ordered_json preview_of(const nlohmann::ordered_json& stats);

}  // namespace pliant::pipeline
