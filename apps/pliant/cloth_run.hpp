// Running a cloth scene to files: shared by `pliant cloth` and `pliant demo`.
//
// Writes DIR/frames/frame_0000.<format> (the initial state) … frame_NNNN, the preview
// (DIR/preview.mp4, or DIR/preview/frame_NNNN.png without ffmpeg) and DIR/stats.json (schema in
// docs/formats.md), each atomically; returns stats.json's object. A cloth that intersects itself
// at the start is reported as a warning and in stats.json (initial_intersecting_pairs) and, unless
// the scene says "untangle": false, untangled before frame 0 (stats.json's untangle). Throws
// InvalidInput or IoError for a scene that cannot be built (before anything is written) and IoError
// when DIR cannot be written. progress: a progress bar on stderr.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

#include "pliant/cloth/scene.hpp"

namespace pliant::cli {

struct ClothRunOptions {
    int frames = 0;         // frames to simulate after frame 0
    bool progress = false;  // progress bar on stderr
    bool preview = true;    // DIR/preview.mp4 (or PNG frames): cloth_preview.hpp
    int preview_width = 640;
    int preview_height = 480;
    // A cloth that needs more memory is refused before it is generated (memory_budget.hpp);
    // 0: the memory available.
    std::uint64_t max_memory_bytes = 0;
};

nlohmann::ordered_json run_cloth_scene(const cloth::ClothScene& scene,
                                       const std::string& scene_name,
                                       const std::filesystem::path& out,
                                       const ClothRunOptions& options);

}  // namespace pliant::cli
