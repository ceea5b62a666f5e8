// ImGui pieces both overlays use: a row of the stage-time table and the run controls.
#pragma once

namespace pliant::viewer {

// One row of a two-column table (between ImGui::BeginTable and EndTable): name, "12.34 ms".
void stage_row(const char* name, double ms);

// Pause/Run, Step and Reset buttons on one line: toggles `paused`, sets `step_requested`;
// returns whether Reset was clicked.
bool run_controls(bool& paused, bool& step_requested);

}  // namespace pliant::viewer
