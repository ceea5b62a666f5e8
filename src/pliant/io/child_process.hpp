// Running an external program (COLMAP, …) as a child process that the caller can stop.
//
// find_program(name): the first executable regular file `name` in a directory of $PATH (empty
// entries ignored; without $PATH, /usr/local/bin:/usr/bin:/bin); "" when absent. No shell.
//
// run_child_process(argv, log, poll): starts argv[0] (an absolute path or a name looked up by
// find_program) with the argument vector `argv` (posix_spawn, no shell), its standard input from
// /dev/null and its standard output and error appended to the file `log` (created if missing),
// in its own process group (so a Ctrl-C in the terminal reaches the caller, not the child).
// While the child runs, `poll` is called about every 50 ms (and once before it starts): false
// stops the child (SIGTERM, then SIGKILL after 2 s), reaps it and returns with `stopped` set.
// An exception thrown by `poll` also kills and reaps the child, then propagates.
// Returns the exit code (0–255), or the signal number that ended it (`signaled`).
// Throws InvalidInput for an empty argv, IoError "<program>: …" when the program is not found,
// the log cannot be opened or the child cannot be started.
// Not thread safe with respect to other code that reaps children (waitpid on this child only).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "pliant/core/function_ref.hpp"

namespace pliant::io {

std::filesystem::path find_program(const std::string& name);

struct ChildProcessResult {
    int exit_code = 0;      // valid when !signaled && !stopped
    bool signaled = false;  // ended by a signal not sent by run_child_process
    int signal = 0;
    bool stopped = false;  // poll returned false and the child was killed
    double seconds = 0.0;  // wall time from start to reaping
};

ChildProcessResult run_child_process(const std::vector<std::string>& argv,
                                     const std::filesystem::path& log, FunctionRef<bool()> poll);

}  // namespace pliant::io
