// The overlay of `pliant view volume` (Dear ImGui): frame rate and stage times (soft body step,
// resampling, ray-caster preparation, ray casting) with the resolution of the last image, the
// transfer function presets, opacity scale and threshold sliders, shading, the clipping plane
// (normal by azimuth and elevation, position across the box), and with --deform the driver
// (wave, twist, bubble and their parameters), stiffness, drag radius, pause, step and reset.
// Settings are applied to the session as they change; an error (a transfer function file that
// cannot be read) is shown in the panel, not thrown.
#pragma once

#include <string>

#include "frame_clock.hpp"
#include "volume_session.hpp"

namespace pliant::viewer {

struct VolumeViewState {
    bool paused = false;
    bool step_requested = false;
    bool reset_camera = false;
    int image_width = 0, image_height = 0;  // of the last rendered image
    bool preview = false;                   // the last image is a reduced-resolution preview
    std::string title;
    std::string renderer;
    std::string error;  // last settings error, shown until the next change
    // The clipping plane as edited: normal azimuth, elevation (degrees) and the plane's position
    // along it in [−1, 1] (fractions of the box's half extent along the normal, 0 = centre).
    bool clip_enabled = false;
    float clip_azimuth = 0.0f, clip_elevation = 0.0f, clip_position = 0.0f;
};

// Fills the plane fields of `state` from a plane (the initial --clip), and builds the plane the
// fields describe, for the volume's box.
void clip_fields_from_plane(const render::ClipPlane& plane, const AABBd& box,
                            VolumeViewState& state);
render::ClipPlane plane_from_clip_fields(const VolumeViewState& state, const AABBd& box);

// The panel's width in pixels: it is docked at the window's left, over the full height, beside
// the image.
inline constexpr int VOLUME_PANEL_WIDTH = 330;

void draw_volume_panel(VolumeSession& session, VolumeViewState& state, const FrameClock& clock,
                       int height);

}  // namespace pliant::viewer
