#include "window.hpp"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <cstdlib>
#include <string>

#include "gl.hpp"
#include "pliant/core/error.hpp"

namespace pliant::viewer {
namespace {

// GLFW reports errors through a callback; the last one is kept for the exception's message.
std::string g_last_error;

extern "C" void on_glfw_error(int code, const char* description) {
    g_last_error =
        fmt::format("{} (GLFW error 0x{:x})", description != nullptr ? description : "", code);
}

extern "C" void on_scroll(GLFWwindow* window, double /*x*/, double y) {
    auto* self = static_cast<double*>(glfwGetWindowUserPointer(window));
    if (self != nullptr) {
        *self += y;
    }
}

[[noreturn]] void fail(const std::string& what) {
    const char* display = std::getenv("DISPLAY");
    const std::string hint =
        display == nullptr || *display == '\0'
            ? "no display: DISPLAY is not set (for headless use run under xvfb-run -a, e.g. "
              "`xvfb-run -a pliant view ... --screenshot out.png --frames 10`)"
            : fmt::format("display '{}'", display);
    throw Unsupported(fmt::format("viewer: {}: {}; {}", what,
                                  g_last_error.empty() ? "no reason given" : g_last_error, hint));
}

}  // namespace

Window::Window(const std::string& title, const WindowOptions& options) {
    if (options.width < 1 || options.height < 1 || options.width > 16384 ||
        options.height > 16384 || options.msaa_samples < WindowOptions::AUTO_MSAA ||
        options.msaa_samples > 16) {
        throw InvalidInput(fmt::format(
            "viewer: window {}x{} with {} samples, expected sizes in [1, 16384] and 0-16 samples "
            "(-1: automatic)",
            options.width, options.height, options.msaa_samples));
    }
    g_last_error.clear();
    glfwSetErrorCallback(on_glfw_error);
    if (glfwInit() != GLFW_TRUE) {
        fail("cannot initialise GLFW");
    }
    const bool automatic = options.msaa_samples == WindowOptions::AUTO_MSAA;
    open(title, options, automatic ? 4 : options.msaa_samples);
    if (automatic && is_software_renderer(gl_renderer())) {
        // Software rasterizers pay per sample: reopen without multisampling.
        glfwDestroyWindow(m_window);
        m_window = nullptr;
        open(title, options, 0);
    }
    glGetIntegerv(GL_SAMPLES, &m_samples);
    glfwSwapInterval(options.vsync ? 1 : 0);
    glfwSetWindowUserPointer(m_window, &m_scroll);
    glfwSetScrollCallback(m_window, on_scroll);
    if (options.show_ui) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
        ImGui::StyleColorsDark();
        ImGui::GetStyle().Alpha = 0.92f;
        // Installs ImGui's callbacks, which chain to the scroll callback above.
        ImGui_ImplGlfw_InitForOpenGL(m_window, true);
        ImGui_ImplOpenGL3_Init("#version 330 core");
        m_has_ui = true;
    }
}

void Window::open(const std::string& title, const WindowOptions& options, int samples) {
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, samples);
    m_window = glfwCreateWindow(options.width, options.height, title.c_str(), nullptr, nullptr);
    if (m_window == nullptr) {
        glfwTerminate();
        fail("cannot open an OpenGL 3.3 core window");
    }
    glfwMakeContextCurrent(m_window);
}

bool is_software_renderer(const std::string& renderer) {
    for (const char* name : {"llvmpipe", "softpipe", "swrast", "Software Rasterizer"}) {
        if (renderer.find(name) != std::string::npos) {
            return true;
        }
    }
    return false;
}

Window::~Window() {
    if (m_has_ui) {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    glfwDestroyWindow(m_window);
    glfwTerminate();
    glfwSetErrorCallback(nullptr);
}

bool Window::should_close() const {
    return glfwWindowShouldClose(m_window) != 0;
}

void Window::request_close() {
    glfwSetWindowShouldClose(m_window, GLFW_TRUE);
}

void Window::poll_events(double timeout_seconds) {
    if (timeout_seconds > 0.0) {
        glfwWaitEventsTimeout(timeout_seconds);
    } else {
        glfwPollEvents();
    }
}

void Window::framebuffer_size(int& width, int& height) const {
    glfwGetFramebufferSize(m_window, &width, &height);
}

double Window::pixel_scale() const {
    int fw = 0, fh = 0, ww = 0, wh = 0;
    glfwGetFramebufferSize(m_window, &fw, &fh);
    glfwGetWindowSize(m_window, &ww, &wh);
    return ww > 0 ? static_cast<double>(fw) / ww : 1.0;
}

void Window::swap_buffers() {
    glfwSwapBuffers(m_window);
}

void Window::begin_ui_frame() {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
}

void Window::end_ui_frame() {
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

bool Window::ui_wants_mouse() const {
    return m_has_ui && ImGui::GetIO().WantCaptureMouse;
}

bool Window::ui_is_active() const {
    return m_has_ui && ImGui::IsAnyItemActive();
}

bool Window::ui_wants_keyboard() const {
    return m_has_ui && ImGui::GetIO().WantCaptureKeyboard;
}

double Window::take_scroll() {
    const double s = m_scroll;
    m_scroll = 0.0;
    return s;
}

std::string Window::gl_renderer() const {
    const auto* text = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return text != nullptr ? text : "";
}

std::string Window::gl_version() const {
    const auto* text = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    return text != nullptr ? text : "";
}

}  // namespace pliant::viewer
