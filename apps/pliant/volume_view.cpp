#include "volume_view.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "pliant/io/transfer_function_json.hpp"

namespace pliant::cli {

std::array<int, 2> parse_size(const std::string& text, const std::string& option) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 1 ||
        h < 1 || w > 16384 || h > 16384) {
        throw CLI::ValidationError(
            option, fmt::format("expected WxH with 1 <= W, H <= 16384, got '{}'", text));
    }
    return {w, h};
}

render::Camera orbit_camera(const AABBd& box, double azimuth, double elevation, double distance,
                            int width, int height) {
    if (distance <= 0.0) {
        return render::frame_box(box, azimuth, elevation, width, height);
    }
    return orbit_camera_at(box.center(), azimuth, elevation, distance, width, height);
}

render::Camera orbit_camera_at(const Vec3d& target, double azimuth, double elevation,
                               double distance, int width, int height) {
    const double az = azimuth * std::numbers::pi / 180.0;
    const double el = elevation * std::numbers::pi / 180.0;
    const Vec3d dir{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
    const Vec3d up = std::fabs(std::sin(el)) > 0.999
                         ? Vec3d{-std::cos(az) * std::sin(el), -std::sin(az) * std::sin(el), 0.0}
                         : Vec3d{0.0, 0.0, 1.0};
    return render::Camera::perspective(target + distance * dir, target, up, ORBIT_FOV_DEGREES,
                                       width, height);
}

volume::TransferFunction load_transfer_function(const std::string& name_or_file,
                                                const volume::Volume& volume) {
    const auto& presets = volume::preset_names();
    return std::find(presets.begin(), presets.end(), name_or_file) != presets.end()
               ? volume::preset(name_or_file, volume)
               : io::read_transfer_function(name_or_file);
}

bool has_extension(const std::string& path, const char* ext) {
    std::string e = std::filesystem::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e == ext;
}

}  // namespace pliant::cli
