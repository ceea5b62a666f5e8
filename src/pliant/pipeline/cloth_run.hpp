// Running a cloth scene to files (a ClothSimulation, cloth_simulation.hpp, frame by frame): what
// `pliant cloth` and `pliant demo` run.
//
// Writes DIR/frames/frame_0000.<format> (the initial state) … frame_NNNN, the preview
// (DIR/preview.mp4, or DIR/preview/frame_NNNN.png without ffmpeg) and DIR/stats.json (schema in
// docs/formats.md), each atomically; returns stats.json's object. A cloth that intersects itself
// at the start is reported as a warning and in stats.json (initial_intersecting_pairs) and, unless
// the scene says "untangle": false, untangled before frame 0 (stats.json's untangle). Throws
// InvalidInput or IoError for a scene that cannot be built (before anything is written) and IoError
// when DIR cannot be written.
//
// Checkpoints (io/checkpoint.hpp): every checkpoint_every frames, at the last frame and when
// interrupted, the simulation's whole state, the per-frame stats so far and the frame number go
// to DIR/checkpoint.bin (atomically). With resume, the run continues from that checkpoint: the
// frames after it are simulated again and are bitwise identical to those of an uninterrupted run,
// stats.json holds every frame (those before the checkpoint from the checkpoint), and the preview
// is rebuilt from the frames on disk. resume without DIR/checkpoint.bin starts from frame 0 (a
// run killed before its first checkpoint). A checkpoint of another scene or options, or a
// corrupt or truncated one, is InvalidInput naming the file; so is a checkpoint whose frames are
// missing from DIR/frames. A run without resume removes an earlier run's checkpoint first.
//
// Write failures (a full disk): when a frame, the checkpoint or stats.json cannot be written,
// the run stops; the frames written so far stay, stats.json is rewritten to describe exactly
// those (with "error"), no partial or temporary file is left, and IoError names what failed.
// Rerunning with resume once there is space continues from the last checkpoint.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

#include "pliant/cloth/scene.hpp"
#include "pliant/pipeline/progress.hpp"

namespace pliant::pipeline {

struct ClothRunOptions {
    int frames = 0;       // frames to simulate after frame 0
    ProgressFn progress;  // after every frame (progress.hpp)
    // Asked before every frame: false stops the run after the frame in progress; the frames so
    // far, the preview and stats.json ("interrupted": true) are written, then Interrupted is
    // thrown.
    KeepGoingFn keep_going;
    bool preview = true;  // DIR/preview.mp4 (or PNG frames): cloth_preview.hpp
    int preview_width = 640;
    int preview_height = 480;
    // A cloth that needs more memory is refused before it is generated (memory_budget.hpp);
    // 0: the memory available.
    std::uint64_t max_memory_bytes = 0;
    // Frames between checkpoints (DIR/checkpoint.bin); 0: no checkpoints.
    int checkpoint_every = 12;
    bool resume = false;  // continue from DIR/checkpoint.bin
};

nlohmann::ordered_json run_cloth_scene(const cloth::ClothScene& scene,
                                       const std::string& scene_name,
                                       const std::filesystem::path& out,
                                       const ClothRunOptions& options);

}  // namespace pliant::pipeline
