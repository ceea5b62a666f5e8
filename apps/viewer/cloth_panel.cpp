#include "cloth_panel.hpp"

#include <imgui.h>

#include "panel_widgets.hpp"

namespace pliant::viewer {

void draw_cloth_panel(ClothSession& session, ClothViewState& state, const FrameClock& clock) {
    ImGui::SetNextWindowPos(ImVec2(10.0f, 10.0f), ImGuiCond_FirstUseEver);
    ImGui::Begin("pliant view cloth", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::TextUnformatted(state.title.c_str());
    ImGui::Text("%zu triangles, %zu vertices", session.triangles().size(),
                session.positions().size());
    ImGui::TextDisabled("%s", state.renderer.c_str());
    ImGui::Separator();
    const double frame_ms = clock.recent_ms();
    ImGui::Text("display %.1f fps (%.1f ms per frame)", clock.recent_fps(), frame_ms);
    const double simulated_per_frame = session.substeps_per_frame() * session.substep();
    ImGui::Text("t = %.3f s, frame %lld%s", session.time(), static_cast<long long>(session.frame()),
                state.paused ? " (paused)" : "");
    if (!state.paused) {
        ImGui::Text("simulation %.1f frames/s, %.2fx real time", state.simulation_fps,
                    state.simulation_fps * simulated_per_frame);
    }
    const ClothFrameStats& stats = session.stats();
    const cloth::ClothStepStats& step = stats.step;
    if (ImGui::BeginTable("stages", 2, ImGuiTableFlags_SizingStretchProp)) {
        const auto row = stage_row;
        row("step (whole)", step.ms);
        row("  solve (XPBD, obstacles)", step.solve_ms);
        if (step.has_self_collision) {
            row("  refit (BVH)", step.self.refit_ms);
            row("  traverse", step.self.traverse_ms);
            row("  narrow (proximity, CCD)", step.self.narrow_ms);
            row("  response", step.self.response_ms);
        }
        row("draw (upload + GL calls)", state.draw_ms);
        ImGui::EndTable();
    }
    if (step.has_self_collision) {
        ImGui::Text("contacts: %lld self, %lld obstacle",
                    static_cast<long long>(step.self.contacts),
                    static_cast<long long>(step.obstacle_contacts));
    } else {
        ImGui::Text("contacts: %lld obstacle (self-collision off)",
                    static_cast<long long>(step.obstacle_contacts));
    }
    if (stats.intersecting_pairs >= 0) {
        ImGui::Text("intersecting pairs: %lld", static_cast<long long>(stats.intersecting_pairs));
        ImGui::TextDisabled("(exact; counted every few frames: frame %lld, %.1f ms)",
                            static_cast<long long>(stats.checked_frame), stats.check_ms);
    }
    ImGui::Separator();
    if (run_controls(state.paused, state.step_requested)) {
        state.reset_requested = true;
    }
    ImGui::SameLine();
    if (ImGui::Button("Reset camera")) {
        state.reset_camera = true;
    }
    int substeps = session.substeps_per_frame();
    if (ImGui::SliderInt("substeps/frame", &substeps, 1, 4 * session.scene().substeps)) {
        session.set_substeps_per_frame(substeps);
    }
    ImGui::TextDisabled("(the scene: %d substeps per 1/%g s)", session.scene().substeps,
                        session.scene().frames_per_second);
    if (ImGui::CollapsingHeader("Mouse and keys")) {
        ImGui::TextUnformatted(
            "left drag on the cloth: grab a vertex\n"
            "left drag elsewhere (or Shift+left): orbit\n"
            "right or middle drag: pan, wheel: zoom\n"
            "Space: pause, N: step, R: reset,\n"
            "C: reset camera, Esc: quit");
    }
    ImGui::End();
}

}  // namespace pliant::viewer
