#include "progress_bar.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace pliant::cli {
namespace {

// Which bar's line is open on stderr (drawn, not yet ended by a newline).
enum class OpenLine { none, frames, training };
OpenLine g_line_open = OpenLine::none;

// "[####      ]": `filled` of `width` cells.
std::string bar(int width, int filled) {
    std::string text(static_cast<std::size_t>(width) + 2, ' ');
    text.front() = '[';
    text.back() = ']';
    std::fill_n(text.begin() + 1, filled, '#');
    return text;
}

}  // namespace

bool stderr_is_terminal() {
    return ::isatty(::fileno(stderr)) != 0;
}

pipeline::ProgressFn frame_progress(bool enabled) {
    if (!enabled) {
        return {};
    }
    return [](int done, int total, double ms_per_frame) {
        if (g_line_open == OpenLine::training) {
            end_progress();  // a frame bar after training (the demo) starts a line of its own
        }
        const int width = 40;
        const int filled = std::clamp(width * done / std::max(total, 1), 0, width);
        std::fprintf(stderr, "\r%s frame %d/%d  %.1f ms/frame", bar(width, filled).c_str(), done,
                     total, ms_per_frame);
        g_line_open = OpenLine::frames;
        if (done >= total) {
            end_progress();
        }
        std::fflush(stderr);
    };
}

std::function<void(const nerf::TrainProgress&)> train_progress(bool enabled) {
    if (!enabled) {
        return {};
    }
    return [last_print = -1e9](const nerf::TrainProgress& p) mutable {
        if (p.elapsed_ms - last_print <= 250.0) {
            return;
        }
        last_print = p.elapsed_ms;
        const int width = 30;
        const int filled = std::clamp(static_cast<int>(width * p.progress), 0, width);
        std::fprintf(stderr, "\r%s %3.0f%%  it %lld  grid %d  loss %.5f  PSNR %.2f dB  %.0f s ",
                     bar(width, filled).c_str(), 100.0 * p.progress,
                     static_cast<long long>(p.iteration), p.resolution, p.loss, p.psnr,
                     p.elapsed_ms / 1000.0);
        g_line_open = OpenLine::training;
        std::fflush(stderr);
    };
}

void end_progress() {
    if (g_line_open != OpenLine::none) {
        std::fputc('\n', stderr);
        g_line_open = OpenLine::none;
    }
}

}  // namespace pliant::cli
