#include "volume_panel.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "panel_widgets.hpp"
#include "pliant/core/error.hpp"
#include "pliant/volume/transfer_function.hpp"

namespace pliant::viewer {
namespace {

constexpr double TO_RADIANS = std::numbers::pi / 180.0;

Vec3d direction(double azimuth, double elevation) {
    const double az = azimuth * TO_RADIANS, el = elevation * TO_RADIANS;
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

// Half the box's extent along unit direction n.
double half_extent(const AABBd& box, const Vec3d& n) {
    const Vec3d e = box.extent();
    return 0.5 * (std::fabs(n.x) * e.x + std::fabs(n.y) * e.y + std::fabs(n.z) * e.z);
}

bool axis_combo(const char* label, pbd::Axis& axis) {
    int index = static_cast<int>(axis);
    const char* names[] = {"x", "y", "z"};
    if (ImGui::Combo(label, &index, names, 3)) {
        axis = static_cast<pbd::Axis>(index);
        return true;
    }
    return false;
}

bool slider(const char* label, double& value, double lo, double hi, const char* format = "%.3f") {
    auto f = static_cast<float>(value);
    if (ImGui::SliderFloat(label, &f, static_cast<float>(lo), static_cast<float>(hi), format)) {
        value = f;
        return true;
    }
    return false;
}

// The driver's parameters; returns whether any changed.
bool driver_controls(DriverSettings& d) {
    bool changed = false;
    switch (d.kind) {
        case DriverKind::wave:
            changed |= axis_combo("propagation", d.wave.direction);
            changed |= axis_combo("displacement", d.wave.displacement);
            changed |= slider("amplitude", d.wave.amplitude, 0.0, 0.2);
            changed |= slider("wavelength", d.wave.wavelength, 0.05, 2.0);
            changed |= slider("speed", d.wave.speed, -2.0, 2.0);
            if (d.wave.displacement == d.wave.direction) {
                ImGui::TextDisabled("displacement must differ from propagation");
            }
            break;
        case DriverKind::twist:
            changed |= axis_combo("axis", d.twist.axis);
            changed |= slider("angle", d.twist.angle, -360.0, 360.0, "%.0f deg");
            changed |= slider("grip", d.twist.grip, 0.0, 0.45);
            break;
        case DriverKind::bubble: {
            changed |= slider("radius", d.bubble.radius, 0.02, 0.6);
            changed |= slider("inflation", d.bubble.inflation, 0.2, 4.0);
            float centre[3] = {static_cast<float>(d.bubble.centre.x),
                               static_cast<float>(d.bubble.centre.y),
                               static_cast<float>(d.bubble.centre.z)};
            if (ImGui::SliderFloat3("centre", centre, 0.0f, 1.0f)) {
                d.bubble.centre = {centre[0], centre[1], centre[2]};
                changed = true;
            }
            break;
        }
        case DriverKind::none:
            break;
    }
    return changed;
}

}  // namespace

void clip_fields_from_plane(const render::ClipPlane& plane, const AABBd& box,
                            VolumeViewState& state) {
    const Vec3d n = plane.normal / norm(plane.normal);
    state.clip_enabled = true;
    state.clip_azimuth = static_cast<float>(std::atan2(n.y, n.x) / TO_RADIANS);
    state.clip_elevation = static_cast<float>(std::asin(std::clamp(n.z, -1.0, 1.0)) / TO_RADIANS);
    const double h = half_extent(box, n);
    state.clip_position = static_cast<float>(
        std::clamp(h > 0.0 ? dot(plane.point - box.center(), n) / h : 0.0, -1.0, 1.0));
}

render::ClipPlane plane_from_clip_fields(const VolumeViewState& state, const AABBd& box) {
    const Vec3d n = direction(state.clip_azimuth, state.clip_elevation);
    return {box.center() + n * (state.clip_position * half_extent(box, n)), n};
}

void draw_volume_panel(VolumeSession& session, VolumeViewState& state, const FrameClock& clock,
                       int height) {
    ImGui::SetNextWindowPos(ImVec2(0.0f, 0.0f), ImGuiCond_Always);
    ImGui::SetNextWindowSize(
        ImVec2(static_cast<float>(VOLUME_PANEL_WIDTH), static_cast<float>(height)),
        ImGuiCond_Always);
    ImGui::Begin("pliant view volume", nullptr,
                 ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
    ImGui::PushItemWidth(-120.0f);  // room for the labels
    const volume::Volume& source = session.source();
    ImGui::TextUnformatted(state.title.c_str());
    const std::string type(volume::name(source.type()));
    ImGui::Text("%lld x %lld x %lld, %s", static_cast<long long>(source.dims()[0]),
                static_cast<long long>(source.dims()[1]), static_cast<long long>(source.dims()[2]),
                type.c_str());
    ImGui::TextDisabled("%s", state.renderer.c_str());
    ImGui::Separator();
    ImGui::Text("%.1f fps (%.1f ms per frame)", clock.recent_fps(), clock.recent_ms());
    ImGui::Text("image %d x %d%s", state.image_width, state.image_height,
                state.preview ? " (preview while interacting)" : "");
    const VolumeFrameStats& stats = session.stats();
    if (ImGui::BeginTable("stages", 2, ImGuiTableFlags_SizingStretchProp)) {
        const auto row = stage_row;
        if (session.is_deformable()) {
            row("soft body step (XPBD)", stats.step_ms);
            row("resample", stats.resample_ms);
        }
        row("ray caster preparation", stats.prepare_ms);
        row("ray casting", stats.render_ms);
        ImGui::EndTable();
    }

    // Appearance.
    const VolumeSessionOptions& settings = session.settings();
    const auto apply = [&state](auto&& change) {
        try {
            change();
            state.error.clear();
        } catch (const Error& e) {
            state.error = e.what();
        }
    };
    if (ImGui::CollapsingHeader("Transfer function", ImGuiTreeNodeFlags_DefaultOpen)) {
        if (session.is_rgba()) {
            ImGui::TextDisabled("RGBA volume: its own colour and opacity");
        } else if (ImGui::BeginCombo("preset", settings.tf.c_str())) {
            for (const std::string& name : volume::preset_names()) {
                if (ImGui::Selectable(name.c_str(), name == settings.tf)) {
                    apply([&] { session.set_transfer_function(name); });
                }
            }
            ImGui::EndCombo();
        }
        auto scale = static_cast<float>(settings.opacity_scale);
        if (ImGui::SliderFloat("opacity scale", &scale, 0.05f, 20.0f, "%.2f",
                               ImGuiSliderFlags_Logarithmic)) {
            apply([&] { session.set_opacity_scale(scale); });
        }
        auto threshold = static_cast<float>(settings.threshold);
        if (ImGui::SliderFloat("threshold (0-255)", &threshold, 0.0f, 255.0f, "%.0f")) {
            apply([&] { session.set_threshold(threshold); });
        }
        bool shading = settings.shading;
        if (ImGui::Checkbox("gradient shading", &shading)) {
            session.set_shading(shading);
        }
    }
    if (ImGui::CollapsingHeader("Clipping plane", ImGuiTreeNodeFlags_DefaultOpen)) {
        bool changed = ImGui::Checkbox("clip", &state.clip_enabled);
        changed |=
            ImGui::SliderFloat("normal azimuth", &state.clip_azimuth, -180.0f, 180.0f, "%.0f deg");
        changed |= ImGui::SliderFloat("normal elevation", &state.clip_elevation, -90.0f, 90.0f,
                                      "%.0f deg");
        changed |= ImGui::SliderFloat("position", &state.clip_position, -1.0f, 1.0f, "%.2f");
        if (changed) {
            apply([&] {
                session.set_clip(state.clip_enabled ? std::optional(plane_from_clip_fields(
                                                          state, source.world_bounds()))
                                                    : std::nullopt);
            });
        }
    }
    if (session.is_deformable() &&
        ImGui::CollapsingHeader("Deformation", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Text("t = %.2f s, volume ratio %.4f, %lld inverted tets%s", session.time(),
                    stats.volume_ratio, static_cast<long long>(stats.inverted_tets),
                    state.paused ? " (paused)" : "");
        DriverSettings driver = settings.driver;
        int kind = static_cast<int>(driver.kind);
        const char* kinds[] = {"none", "wave", "twist", "bubble"};
        bool changed = ImGui::Combo("driver", &kind, kinds, 4);
        driver.kind = static_cast<DriverKind>(kind);
        changed |= driver_controls(driver);
        if (changed) {
            apply([&] { session.set_driver(driver); });
        }
        auto stiffness = static_cast<float>(settings.body.stiffness);
        if (ImGui::SliderFloat("stiffness", &stiffness, 0.5f, 1.0f, "%.2f")) {
            apply([&] { session.set_stiffness(stiffness); });
        }
        auto radius = static_cast<float>(settings.drag_radius);
        if (ImGui::SliderFloat("drag radius", &radius, 0.0f, 0.3f, "%.2f")) {
            apply([&] { session.set_drag_radius(radius); });
        }
        if (run_controls(state.paused, state.step_requested)) {
            apply([&] { session.reset_deformation(); });
        }
    }
    if (ImGui::Button("Reset camera")) {
        state.reset_camera = true;
    }
    if (!state.error.empty()) {
        ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", state.error.c_str());
    }
    if (ImGui::CollapsingHeader("Mouse and keys")) {
        ImGui::TextUnformatted(session.is_deformable()
                                   ? "left drag on the volume: drag it (XPBD drag)\n"
                                     "left drag elsewhere (or Shift+left): orbit\n"
                                     "right or middle drag: pan, wheel: zoom\n"
                                     "Space: pause, N: step, R: reset,\n"
                                     "C: reset camera, Esc: quit"
                                   : "left drag: orbit, right or middle drag: pan,\n"
                                     "wheel: zoom, C: reset camera, Esc: quit");
    }
    ImGui::PopItemWidth();
    ImGui::End();
}

}  // namespace pliant::viewer
