// The interactive viewer's entry points (GLFW + OpenGL 3.3 + Dear ImGui), run by `pliant view
// cloth` and `pliant view volume` (apps/pliant/cmd_view.cpp).
//
// Each builds its scene first (bad input fails before a window opens), then opens the window
// (pliant::Unsupported when there is no display or no OpenGL 3.3: the message names GLFW's
// reason), then loops until the window is closed (Esc) or, with run.frames > 0, for that many
// frames; with run.screenshot the last frame's image (without the overlay) is written as a PNG.
// Returns the run's summary: frames, mean frame time and fps (frames after the first), stage
// means, the camera, the GL renderer (docs/formats.md, "pliant view").
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "pliant/cloth/scene.hpp"
#include "view_options.hpp"

namespace pliant::viewer {

nlohmann::ordered_json run_cloth_view(const cloth::ClothScene& scene, const std::string& scene_name,
                                      const ClothViewOptions& options);

nlohmann::ordered_json run_volume_view(const std::filesystem::path& volume,
                                       const VolumeViewOptions& options);

}  // namespace pliant::viewer
