// One-line progress bars on stderr for the long commands (cloth, deform, nerf train, demo): the
// pipeline runs report through callbacks (pipeline/progress.hpp) and these draw them.
#pragma once

#include <functional>

#include "pliant/nerf/trainer.hpp"
#include "pliant/pipeline/progress.hpp"

namespace pliant::cli {

// True when stderr is a terminal (progress bars are drawn only then).
bool stderr_is_terminal();

// "\r[#####     ] frame 12/48  35.2 ms/frame" after every frame; the line ends at the last frame.
// Empty when !enabled.
pipeline::ProgressFn frame_progress(bool enabled);

// "\r[####   ]  40%  it 1200  grid 96  loss 0.00123  PSNR 29.10 dB  48 s" at most every 250 ms
// of training. Empty when !enabled.
std::function<void(const nerf::TrainProgress&)> train_progress(bool enabled);

// Ends a bar's line left open (a run that stopped or failed before its last unit, or training),
// so that what is printed next starts on a line of its own.
void end_progress();

}  // namespace pliant::cli
