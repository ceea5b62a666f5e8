// pliant: fast deformable simulation and visualization — command-line entry point.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

#include "commands.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/version.hpp"
#include "progress_bar.hpp"

namespace {

// Edit distance between two words (insertions, deletions, substitutions, transpositions).
std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
    for (std::size_t i = 0; i <= a.size(); ++i) {
        d[i][0] = i;
    }
    for (std::size_t j = 0; j <= b.size(); ++j) {
        d[0][j] = j;
    }
    for (std::size_t i = 1; i <= a.size(); ++i) {
        for (std::size_t j = 1; j <= b.size(); ++j) {
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1,
                                d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        }
    }
    return d[a.size()][b.size()];
}

// The first word of the command line that is neither an option nor an option's value: what the
// user meant as the command ("" when there is none). Only --threads takes a value.
std::string command_word(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg == "--threads") {
            ++i;
        } else if (!arg.starts_with("-")) {
            return std::string(arg);
        }
    }
    return {};
}

// "unknown command 'colide' (did you mean 'collide'?); the commands are: ..." when `word` is not
// one of the app's commands; "" when it is (or is empty).
std::string unknown_command_message(const CLI::App& app, const std::string& word) {
    if (word.empty()) {
        return {};
    }
    std::string names;
    std::string nearest;
    std::size_t nearest_distance = 3;  // suggest at distance 2 at most
    for (const CLI::App* sub : app.get_subcommands({})) {
        if (sub->get_name() == word) {
            return {};
        }
        names += (names.empty() ? "" : ", ") + sub->get_name();
        const std::size_t distance = edit_distance(word, sub->get_name());
        if (distance < nearest_distance || sub->get_name().starts_with(word)) {
            nearest_distance = sub->get_name().starts_with(word) ? 0 : distance;
            nearest = sub->get_name();
        }
    }
    return fmt::format("unknown command '{}'{}; the commands are: {}", word,
                       nearest.empty() ? "" : fmt::format(" (did you mean '{}'?)", nearest), names);
}

}  // namespace

int main(int argc, char** argv) try {
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
        if (const std::string unknown = unknown_command_message(app, command_word(argc, argv));
            !unknown.empty()) {
            std::fprintf(stderr, "pliant: error: %s\nRun with --help for usage.\n",
                         unknown.c_str());
            return 2;
        }
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
} catch (const std::exception& e) {  // setting up the command line itself failed
    std::fprintf(stderr, "pliant: error: internal: %s\n", e.what());
    return 1;
}
