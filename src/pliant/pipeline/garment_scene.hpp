// The built-in garment scene: an A-line skirt made of two flat-pattern panels (front and back,
// quads with UVs from the developed pattern, groups and materials), placed around a mannequin as
// garment tools arrange panels, sewn together along both sides in the first 0.1 s, its
// waistband attached to the body (pins.attach), on a body that walks in place: legs swinging
// into the skirt, hips turning and the torso twisting (a deforming obstacle).
//
// write_skirt_scene(dir) writes dir/scene.json, dir/skirt.obj (+ skirt.mtl) and the body's walk
// cycle dir/body/frame_0000.obj .. frame_0011.obj (mannequin.hpp: scripts/make-body's mannequin
// at 10 segments, turn 25°, swing 20°; 12 frames at 8 fps, looped, interpolated between
// frames) and returns the scene's path; `pliant cloth` runs it like any scene. Throws IoError
// when dir cannot be written.
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
