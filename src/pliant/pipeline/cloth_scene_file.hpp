// Cloth scene files (JSON) → cloth::ClothScene. The format, every key, its type, unit and default
// are in docs/formats.md ("Cloth scenes"); scenes/*.json are examples.
//
//   const cloth::ClothScene scene = pipeline::read_cloth_scene("scenes/drape.json");
//
// Strict: an unknown key, a value of the wrong type or out of range, a missing required key or
// text that is not JSON throws IoError "<path>: <key path>: <what>, expected <x>, got <y>" (key
// paths like `material.stretch_compliance` or `obstacles[1].sphere.radius`). Nothing else
// (mesh files are not opened here; scene.mesh is made absolute against the scene's directory).
#pragma once

#include <filesystem>
#include <string_view>

#include "pliant/cloth/scene.hpp"

namespace pliant::pipeline {

// The largest magnitude of a scene vector's components (positions in m, velocities,
// accelerations, angles); nonzero ones are at least 1e-30. Mesh files a scene names are held to
// the same bound on their coordinates where they are read (cloth_setup.cpp).
inline constexpr double MAX_SCENE_COORDINATE = 1e6;

cloth::ClothScene read_cloth_scene(const std::filesystem::path& path);

// The same from JSON text; `name` (the file name) starts error messages and `base` resolves a
// relative mesh path.
cloth::ClothScene parse_cloth_scene(std::string_view text, std::string_view name,
                                    const std::filesystem::path& base);

}  // namespace pliant::pipeline
