#include "progress_bar.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace pliant::cli {

void print_progress(int done, int total, double ms_per_frame) {
    const int width = 40;
    const int filled = std::clamp(width * done / std::max(total, 1), 0, width);
    std::fprintf(stderr, "\r[%s%s] frame %d/%d  %.1f ms/frame", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), done, total, ms_per_frame);
    std::fflush(stderr);
}

void end_progress() {
    std::fputc('\n', stderr);
}

}  // namespace pliant::cli
