// How cloth scenes look, wherever they are drawn: the MP4 preview of `pliant cloth`
// (cloth_preview.hpp, through render::MeshRasterizer) and the OpenGL viewer (`pliant view
// cloth`), so that a viewer screenshot can be compared with the offline rasterizer. The cloth is
// warm red on the front and tinted on the back so folds read; obstacles are grey-blue; the
// default camera looks from azimuth −60°, elevation 25° (render::frame_box's convention).
#pragma once

#include "pliant/render/image.hpp"
#include "pliant/render/mesh_rasterizer.hpp"

namespace pliant::pipeline {

inline constexpr render::Color CLOTH_COLOR{0.82f, 0.30f, 0.22f};
inline constexpr render::Color OBSTACLE_COLOR{0.62f, 0.68f, 0.76f};
inline constexpr double CLOTH_AZIMUTH_DEGREES = -60.0;
inline constexpr double CLOTH_ELEVATION_DEGREES = 25.0;

// The rasterizer's options for cloth scenes: a light grey-blue background and a yellow back
// tint (the key light, headlight and ambient are the rasterizer's defaults, which the viewer's
// shader reproduces).
inline render::RasterOptions cloth_raster_options() {
    render::RasterOptions options;
    options.background = {0.93f, 0.94f, 0.96f};
    options.back_tint = {0.95f, 0.80f, 0.35f};
    return options;
}

}  // namespace pliant::pipeline
