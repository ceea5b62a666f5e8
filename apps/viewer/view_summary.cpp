#include "view_summary.hpp"

namespace pliant::viewer {

nlohmann::ordered_json camera_json(const render::Camera& camera) {
    const auto vec = [](const Vec3d& v) {
        return nlohmann::ordered_json::array({v.x, v.y, v.z});
    };
    return {{"eye", vec(camera.eye())}, {"target", vec(camera.target())},
            {"up", vec(camera.up())},   {"fov_y_degrees", camera.fov_y_degrees()},
            {"width", camera.width()},  {"height", camera.height()}};
}

void add_run_summary(nlohmann::ordered_json& result, const FrameClock& clock,
                     const ViewRunOptions& run, const Window& window,
                     const std::optional<render::Camera>& camera) {
    result["frames"] = clock.frames();
    result["mean_frame_ms"] = clock.mean_ms();
    result["fps"] = clock.mean_ms() > 0.0 ? 1000.0 / clock.mean_ms() : 0.0;
    result["screenshot"] = run.screenshot.empty() ? nlohmann::ordered_json()
                                                  : nlohmann::ordered_json(run.screenshot.string());
    result["camera"] = camera ? camera_json(*camera) : nlohmann::ordered_json();
    result["gl_renderer"] = window.gl_renderer();
    result["gl_version"] = window.gl_version();
    result["msaa_samples"] = window.msaa_samples();
}

}  // namespace pliant::viewer
