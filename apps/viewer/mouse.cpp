#include "mouse.hpp"

#include "gl.hpp"

namespace pliant::viewer {

MouseFrame MouseTracker::update(Window& window) {
    GLFWwindow* handle = window.handle();
    MouseFrame frame;
    double cx = 0.0, cy = 0.0;
    glfwGetCursorPos(handle, &cx, &cy);
    const double scale = window.pixel_scale();
    frame.x = cx * scale;
    frame.y = cy * scale;
    if (!m_first) {
        frame.dx = frame.x - m_x;
        frame.dy = frame.y - m_y;
    }
    m_first = false;
    m_x = frame.x;
    m_y = frame.y;
    const bool over_ui = window.ui_wants_mouse();
    constexpr int BUTTONS[3] = {GLFW_MOUSE_BUTTON_LEFT, GLFW_MOUSE_BUTTON_RIGHT,
                                GLFW_MOUSE_BUTTON_MIDDLE};
    for (int b = 0; b < 3; ++b) {
        const bool down = glfwGetMouseButton(handle, BUTTONS[b]) == GLFW_PRESS;
        if (down && !m_down[b]) {
            m_on_scene[b] = !over_ui;
            frame.pressed[b] = m_on_scene[b];
        }
        if (!down && m_down[b]) {
            frame.released[b] = m_on_scene[b];
            m_on_scene[b] = false;
        }
        m_down[b] = down;
        frame.held[b] = down && m_on_scene[b];
    }
    frame.shift = glfwGetKey(handle, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                  glfwGetKey(handle, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    frame.ctrl = glfwGetKey(handle, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                 glfwGetKey(handle, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
    frame.alt = glfwGetKey(handle, GLFW_KEY_LEFT_ALT) == GLFW_PRESS ||
                glfwGetKey(handle, GLFW_KEY_RIGHT_ALT) == GLFW_PRESS;
    const double scroll = window.take_scroll();
    frame.scroll = over_ui ? 0.0 : scroll;
    return frame;
}

KeyFrame KeyTracker::update(Window& window) {
    constexpr int KEYS[5] = {GLFW_KEY_ESCAPE, GLFW_KEY_SPACE, GLFW_KEY_N, GLFW_KEY_R, GLFW_KEY_C};
    bool pressed[5] = {false, false, false, false, false};
    const bool ui_has_keyboard = window.ui_wants_keyboard();
    for (int k = 0; k < 5; ++k) {
        const bool down = glfwGetKey(window.handle(), KEYS[k]) == GLFW_PRESS;
        pressed[k] = down && !m_down[k] && !ui_has_keyboard;
        m_down[k] = down;
    }
    return {pressed[0], pressed[1], pressed[2], pressed[3], pressed[4]};
}

bool apply_camera_gestures(const MouseFrame& mouse, bool left_orbits, int height,
                           OrbitController& controller) {
    bool changed = false;
    if (left_orbits && mouse.held[0] && (mouse.dx != 0.0 || mouse.dy != 0.0)) {
        controller.orbit(mouse.dx, mouse.dy);
        changed = true;
    }
    if ((mouse.held[1] || mouse.held[2]) && (mouse.dx != 0.0 || mouse.dy != 0.0)) {
        controller.pan(mouse.dx, mouse.dy, height);
        changed = true;
    }
    if (mouse.scroll != 0.0) {
        controller.zoom(mouse.scroll);
        changed = true;
    }
    return changed;
}

}  // namespace pliant::viewer
