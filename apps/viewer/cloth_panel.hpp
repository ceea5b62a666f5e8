// The overlay of `pliant view cloth` (Dear ImGui): frame rate, simulated time and speed, the
// solver's stage times of the last frame (step, refit, traverse, narrow, response) and drawing,
// contacts, the exact intersecting-pair count (every few frames, with the frame it is of), and
// the controls: pause, single step, reset, reset camera, speed (substeps per frame).
#pragma once

#include <string>

#include "cloth_session.hpp"
#include "frame_clock.hpp"

namespace pliant::viewer {

// What the panel asks the loop to do, and what it shows besides the session.
struct ClothViewState {
    bool paused = false;
    bool step_requested = false;  // one frame while paused
    bool reset_requested = false;
    bool reset_camera = false;
    double draw_ms = 0.0;         // CPU time of the last frame's upload and draw calls
    double simulation_fps = 0.0;  // simulated frames published per second (recent)
    std::string title;            // scene name
    std::string renderer;         // GL_RENDERER
};

// Builds the panel (between Window::begin_ui_frame and end_ui_frame).
void draw_cloth_panel(ClothSession& session, ClothViewState& state, const FrameClock& clock);

}  // namespace pliant::viewer
