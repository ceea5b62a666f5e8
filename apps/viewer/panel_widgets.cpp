#include "panel_widgets.hpp"

#include <imgui.h>

namespace pliant::viewer {

void stage_row(const char* name, double ms) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(name);
    ImGui::TableNextColumn();
    ImGui::Text("%8.2f ms", ms);
}

bool run_controls(bool& paused, bool& step_requested) {
    if (ImGui::Button(paused ? "Run" : "Pause")) {
        paused = !paused;
    }
    ImGui::SameLine();
    if (ImGui::Button("Step")) {
        step_requested = true;
    }
    ImGui::SameLine();
    return ImGui::Button("Reset");
}

}  // namespace pliant::viewer
