// pliant: fast deformable simulation and visualization — command-line entry point.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/version.hpp"
#include "progress_bar.hpp"

int main(int argc, char** argv) {
    using namespace pliant;
    cli::GlobalOptions global;
    CLI::App app{
        "pliant: fast deformable simulation (cloth with self-collision) and deformable volumes"};
    app.set_version_flag("--version", fmt::format("pliant {}", PLIANT_VERSION));
    app.option_defaults()->always_capture_default();
    app.add_option("--threads", global.threads, "Worker threads (0 = all hardware threads)")
        ->check(CLI::Range(0, 1024));
    app.add_flag("--json", global.json, "Print the result as one JSON object on stdout");
    app.fallthrough();
    app.require_subcommand(1);
    app.parse_complete_callback([&] { set_num_threads(global.threads); });

    cli::register_collide(app, global);
    cli::register_ccd(app, global);
    cli::register_bench(app, global);
    cli::register_demo(app, global);
    cli::register_cloth(app, global);
    cli::register_volume(app, global);
    cli::register_render(app, global);
    cli::register_deform(app, global);
    cli::register_dataset(app, global);
    cli::register_nerf(app, global);
    cli::register_view(app, global);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        cli::end_progress();
        std::fprintf(stderr, "pliant: error: %s\nRun with --help for usage.\n", e.what());
        return 2;
    } catch (const Error& e) {
        cli::end_progress();
        std::fprintf(stderr, "pliant: error: %s\n", e.what());
        return 1;
    } catch (const Interrupted& e) {
        cli::end_progress();
        std::fprintf(stderr, "pliant: interrupted: %s\n", e.what());
        return 130;
    } catch (const std::bad_alloc&) {
        cli::end_progress();
        std::fprintf(stderr, "pliant: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        cli::end_progress();
        std::fprintf(stderr, "pliant: error: internal: %s\n", e.what());
        return 1;
    }
    return 0;
}
