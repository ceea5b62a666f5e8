// Mouse gestures on the scene, frame by frame: cursor position in framebuffer pixels (the
// image coordinates of render::Camera, y downwards), motion since the last frame, buttons,
// modifiers and wheel notches. A button pressed over the ImGui overlay belongs to the overlay
// until it is released (is_captured false), so dragging a slider never turns the camera.
#pragma once

#include "orbit_controller.hpp"
#include "window.hpp"

namespace pliant::viewer {

struct MouseFrame {
    double x = 0.0, y = 0.0;    // framebuffer pixels
    double dx = 0.0, dy = 0.0;  // since the last frame
    // Held, pressed this frame, released this frame; index 0 left, 1 right, 2 middle. held and
    // pressed only for presses that started on the scene, not on the overlay.
    bool held[3] = {false, false, false};
    bool pressed[3] = {false, false, false};
    bool released[3] = {false, false, false};
    bool shift = false, ctrl = false, alt = false;
    double scroll = 0.0;  // wheel notches over the scene (0 over the overlay)
    bool any_held() const { return held[0] || held[1] || held[2]; }
    // Any motion, button or wheel activity this frame.
    bool any_activity() const {
        return dx != 0.0 || dy != 0.0 || any_held() || released[0] || released[1] || released[2] ||
               scroll != 0.0;
    }
};

class MouseTracker {
public:
    MouseFrame update(Window& window);

private:
    double m_x = 0.0, m_y = 0.0;
    bool m_first = true;
    bool m_down[3] = {false, false, false};
    bool m_on_scene[3] = {false, false, false};
};

// Keys pressed since the last frame (edge-detected), ignored while the overlay has the keyboard:
// Escape closes the window, Space pauses, N steps once, R resets, C resets the camera.
struct KeyFrame {
    bool escape = false, space = false, n = false, r = false, c = false;
    bool any() const { return escape || space || n || r || c; }
};

class KeyTracker {
public:
    KeyFrame update(Window& window);

private:
    bool m_down[5] = {false, false, false, false, false};
};

// The camera gestures both viewers share: left drag orbits (when `left_orbits`), right or middle
// drag pans, the wheel zooms. Returns whether the view changed.
bool apply_camera_gestures(const MouseFrame& mouse, bool left_orbits, int height,
                           OrbitController& controller);

}  // namespace pliant::viewer
