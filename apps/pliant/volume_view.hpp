// What the volume commands (render, deform, demo) share: image sizes, the orbit camera and the
// transfer-function choice.
#pragma once

#include <array>
#include <string>

#include "pliant/core/aabb.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::cli {

// "WxH" → {W, H}, each in [1, 16384]; CLI::ValidationError naming `option` (exit 2) otherwise.
std::array<int, 2> parse_size(const std::string& text, const std::string& option = "--size");

// A perspective camera at azimuth, elevation (degrees, render::frame_box's convention) and
// `distance` world units from the box's centre, looking at it; distance ≤ 0 frames the box.
render::Camera orbit_camera(const AABBd& box, double azimuth, double elevation, double distance,
                            int width, int height);

// The same around any point: eye = target + distance · (cos el cos az, cos el sin az, sin el),
// vertical field of view ORBIT_FOV_DEGREES, up hint +z (at elevation ±90° the horizontal
// direction away from the azimuth). distance > 0.
inline constexpr double ORBIT_FOV_DEGREES = 30.0;
render::Camera orbit_camera_at(const Vec3d& target, double azimuth, double elevation,
                               double distance, int width, int height);

// `name_or_file`: a preset (volume::preset_names) computed for `volume`, else a transfer
// function JSON file (io::read_transfer_function; IoError when missing or broken).
volume::TransferFunction load_transfer_function(const std::string& name_or_file,
                                                const volume::Volume& volume);

// True when `path` ends in `ext` (".png"; case-insensitive).
bool has_extension(const std::string& path, const char* ext);

}  // namespace pliant::cli
