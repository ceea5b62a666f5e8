// How a long pipeline run talks to its caller while it runs: the CLI draws a progress bar and
// stops on Ctrl-C, a viewer shows a status line, a script passes nothing. Pipeline runs never
// print and never install signal handlers.
#pragma once

#include <functional>

namespace pliant::pipeline {

// Called after each unit of work (a frame): units done, units in all, and the mean wall time per
// unit so far in milliseconds. Empty: no report.
using ProgressFn = std::function<void(int done, int total, double ms_per_unit)>;

// Asked before each unit of work: false stops the run cleanly after the unit in progress (what it
// wrote so far stays consistent). Empty: never stop.
using KeepGoingFn = std::function<bool()>;

}  // namespace pliant::pipeline
