// The pliant command line: one register_<command> per subcommand, each in cmd_<command>.cpp.
// A command's callback throws pliant::Error on bad input; main turns it into
// `pliant: error: <what>` and exit code 1. Usage errors (CLI11) exit with 2.
#pragma once

#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>

namespace pliant::cli {

// Options every command shares, filled by main before the subcommand runs.
struct GlobalOptions {
    int threads = 0;    // 0: all hardware threads
    bool json = false;  // machine-readable result on stdout
};

void register_collide(CLI::App& app, const GlobalOptions& global);
void register_ccd(CLI::App& app, const GlobalOptions& global);
void register_bench(CLI::App& app, const GlobalOptions& global);
void register_demo(CLI::App& app, const GlobalOptions& global);
void register_cloth(CLI::App& app, const GlobalOptions& global);
void register_volume(CLI::App& app, const GlobalOptions& global);
void register_render(CLI::App& app, const GlobalOptions& global);
void register_deform(CLI::App& app, const GlobalOptions& global);
void register_dataset(CLI::App& app, const GlobalOptions& global);
void register_nerf(CLI::App& app, const GlobalOptions& global);
void register_view(CLI::App& app, const GlobalOptions& global);

}  // namespace pliant::cli
