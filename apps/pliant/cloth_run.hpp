// Running a cloth scene to files: shared by `pliant cloth` and `pliant demo`.
//
// Writes DIR/frames/frame_0000.<format> (the initial state) … frame_NNNN and DIR/stats.json
// (schema in docs/formats.md), each atomically; returns stats.json's object. Throws InvalidInput
// or IoError for a scene that cannot be built (before anything is written) and IoError when DIR
// cannot be written. progress: a progress bar on stderr.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "pliant/cloth/scene.hpp"

namespace pliant::cli {

nlohmann::ordered_json run_cloth_scene(const cloth::ClothScene& scene,
                                       const std::string& scene_name,
                                       const std::filesystem::path& out, int frames, bool progress);

}  // namespace pliant::cli
