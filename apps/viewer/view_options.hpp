// What `pliant view cloth` and `pliant view volume` take (apps/pliant/cmd_view.cpp parses the
// command line into these, whether or not this build has the viewer).
#pragma once

#include <filesystem>
#include <string>

#include "cloth_session.hpp"
#include "volume_session.hpp"
#include "window.hpp"

namespace pliant::viewer {

struct ViewRunOptions {
    WindowOptions window;
    // Azimuth, elevation (degrees) and distance from the target (world units; ≤ 0 frames the
    // scene), orbit_controller.hpp.
    double azimuth = 0.0;
    double elevation = 0.0;
    double distance = 0.0;
    int frames = 0;                    // > 0: stop after this many frames (headless runs)
    std::filesystem::path screenshot;  // the last frame as PNG (empty: none)
    bool paused = false;               // start with the simulation paused
    // false: the simulation runs a frame ahead in the background and the window shows its latest
    // frame, so the camera stays smooth however slow a step is; true: every displayed frame
    // waits for one simulated frame (lock step: reproducible screenshots after --frames N).
    bool sync = false;
};

struct ClothViewOptions {
    ViewRunOptions run;
    ClothSessionOptions session;
};

struct VolumeViewOptions {
    ViewRunOptions run;
    VolumeSessionOptions session;
    // While the user drags or changes a setting, frames are ray-cast at 1 / preview_divisor of
    // the window's resolution per axis (≥ 1; 1: always full); the full image follows when idle.
    int preview_divisor = 2;
    double max_memory_mib = 16384.0;  // largest volume to read
    // Resample an oblique volume onto an axis-aligned grid first (io::Orientation::axis_aligned)
    // instead of showing it as it lies; --deform always does.
    bool axis_aligned = false;
};

}  // namespace pliant::viewer
