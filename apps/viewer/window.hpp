// The viewer's window: GLFW initialised, one window with an OpenGL 3.3 core context (optionally
// multisampled), and, unless the overlay is off, a Dear ImGui context on it (glfw + opengl3
// backends, no imgui.ini written). One Window per process at a time; not thread safe (GLFW's
// rules: the main thread only).
//
// Failure is an error, never a crash: no display (DISPLAY unset, no X server), GLFW failing to
// initialise or no OpenGL 3.3 context throw pliant::Unsupported naming GLFW's reason and what to
// do ("run under xvfb-run for headless use").
#pragma once

#include <string>

struct GLFWwindow;

namespace pliant::viewer {

struct WindowOptions {
    int width = 1280;  // window size in screen coordinates (the framebuffer may differ on HiDPI)
    int height = 720;
    // Multisample anti-aliasing samples; AUTO_MSAA: 4 on hardware OpenGL, none on software
    // renderers (Mesa llvmpipe pays about 2.5 times per frame for 4 samples).
    static constexpr int AUTO_MSAA = -1;
    int msaa_samples = AUTO_MSAA;
    bool vsync = true;    // false for measurements and headless runs
    bool show_ui = true;  // the ImGui overlay
};

class Window {
public:
    Window(const std::string& title, const WindowOptions& options);
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    GLFWwindow* handle() const { return m_window; }
    bool should_close() const;
    void request_close();
    // Processes pending events; with timeout_seconds > 0 waits up to that long for one (idle
    // views), so an unchanging view costs no CPU.
    void poll_events(double timeout_seconds = 0.0);
    void framebuffer_size(int& width, int& height) const;
    // Scale from window (cursor) coordinates to framebuffer pixels.
    double pixel_scale() const;
    void swap_buffers();

    bool has_ui() const { return m_has_ui; }
    // Between these two the caller builds the ImGui frame; end_ui_frame draws it.
    void begin_ui_frame();
    void end_ui_frame();
    // True when ImGui uses the mouse / keyboard (a panel is hovered or an item active).
    bool ui_wants_mouse() const;
    bool ui_is_active() const;
    bool ui_wants_keyboard() const;

    // Wheel notches since the last call.
    double take_scroll();

    std::string gl_renderer() const;
    std::string gl_version() const;
    int msaa_samples() const { return m_samples; }  // samples of the window's framebuffer

private:
    // Creates the window and makes its context current (Unsupported when it cannot).
    void open(const std::string& title, const WindowOptions& options, int samples);

    GLFWwindow* m_window = nullptr;
    bool m_has_ui = false;
    double m_scroll = 0.0;
    int m_samples = 0;
};

// True for Mesa's software renderers (GL_RENDERER "llvmpipe …", "softpipe", "swrast").
bool is_software_renderer(const std::string& renderer);

}  // namespace pliant::viewer
