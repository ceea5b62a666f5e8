// A one-line progress bar on stderr for the long commands (cloth, deform).
#pragma once

namespace pliant::cli {

// Redraws "\r[#####     ] frame 12/48  35.2 ms/frame" on stderr (done of total frames).
void print_progress(int done, int total, double ms_per_frame);
// Ends the bar's line.
void end_progress();

}  // namespace pliant::cli
