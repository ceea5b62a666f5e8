// The built-in garment scene: an A-line skirt made of two flat-pattern panels (front and back,
// quads with UVs from the developed pattern, groups and materials), placed around a mannequin as
// garment tools arrange panels (each panel wrapped on a cone around the body, which a flat pattern
// of a cone's frustum fits without stretching), sewn together along both sides in the first
// 0.1 s, then resting on the hips of a body that turns left and right.
//
// write_skirt_scene(dir) writes dir/scene.json, dir/skirt.obj (+ skirt.mtl) and dir/body.obj and
// returns the scene's path; `pliant cloth` runs it like any scene. The body is a closed surface
// of revolution (waist 0.13 m at 1.02 m, hips 0.18 m at 0.80 m) moved rigidly by the scene's
// obstacle motion ("obstacles"[0]): an animated body replaces it with that one obstacle entry.
// Throws IoError when dir cannot be written.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

#include "pliant/pipeline/progress.hpp"

namespace pliant::pipeline {

// Quads per panel: around the body and down its length.
struct SkirtOptions {
    int quads_around = 24;
    int quads_down = 24;
    int frames = 96;  // 4 s at 24 fps: sewn, settled, turned left, right, back
};

std::filesystem::path write_skirt_scene(const std::filesystem::path& dir,
                                        const SkirtOptions& options = {});

// The demo's garment step: the skirt scene written to DIR (write_skirt_scene) and run there by
// run_cloth_scene (frames, preview, cloth.pc2, stats.json) for `frames` frames; returns
// stats.json's object.
nlohmann::ordered_json garment_demo(const std::filesystem::path& dir, int frames,
                                    const ProgressFn& progress);

}  // namespace pliant::pipeline
