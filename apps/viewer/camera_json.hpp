// The camera of a view as JSON (eye, target, up, vertical field of view, size), so that a
// screenshot can be reproduced by the offline renderers with render::Camera::perspective.
#pragma once

#include <nlohmann/json.hpp>

#include "pliant/render/camera.hpp"

namespace pliant::viewer {

inline nlohmann::ordered_json camera_json(const render::Camera& camera) {
    const auto vec = [](const Vec3d& v) {
        return nlohmann::ordered_json::array({v.x, v.y, v.z});
    };
    return {{"eye", vec(camera.eye())}, {"target", vec(camera.target())},
            {"up", vec(camera.up())},   {"fov_y_degrees", camera.fov_y_degrees()},
            {"width", camera.width()},  {"height", camera.height()}};
}

}  // namespace pliant::viewer
