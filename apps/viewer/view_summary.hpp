// What both views report when they end (`pliant view --json`, docs/formats.md): the frame times,
// the screenshot, the camera of the last full frame (so that the offline renderers can reproduce
// it with render::Camera::perspective) and the OpenGL driver. Each view adds its own keys.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>

#include "frame_clock.hpp"
#include "pliant/render/camera.hpp"
#include "view_options.hpp"
#include "window.hpp"

namespace pliant::viewer {

nlohmann::ordered_json camera_json(const render::Camera& camera);

// Adds frames, mean_frame_ms, fps, screenshot, camera, gl_renderer, gl_version, msaa_samples.
void add_run_summary(nlohmann::ordered_json& result, const FrameClock& clock,
                     const ViewRunOptions& run, const Window& window,
                     const std::optional<render::Camera>& camera);

}  // namespace pliant::viewer
