// Frame timing for the overlay and the --json summary: the wall time between consecutive frames,
// a running mean over the last WINDOW frames (what the overlay shows as fps) and the mean over a
// whole run after its first frame (what `--frames N --json` reports: the first frame also
// compiles shaders and builds caches). Per-stage times are averaged with Mean.
#pragma once

#include <array>
#include <cstdint>

#include "pliant/core/timer.hpp"

namespace pliant::viewer {

// A plain mean of added samples.
struct Mean {
    double sum = 0.0;
    std::int64_t count = 0;
    void add(double x) {
        sum += x;
        ++count;
    }
    double value() const { return count > 0 ? sum / static_cast<double>(count) : 0.0; }
};

class FrameClock {
public:
    static constexpr int WINDOW = 30;

    // Marks the end of a frame: its time is the wall time since the previous mark (or since
    // construction for the first frame).
    void tick() {
        const double ms = m_watch.elapsed_ms();
        m_watch.restart();
        m_recent[static_cast<std::size_t>(m_frames % WINDOW)] = ms;
        if (m_frames > 0) {
            m_after_first.add(ms);
        }
        m_last_ms = ms;
        ++m_frames;
    }
    std::int64_t frames() const { return m_frames; }
    double last_ms() const { return m_last_ms; }
    // Mean of the last min(frames, WINDOW) frames.
    double recent_ms() const {
        const std::int64_t n = m_frames < WINDOW ? m_frames : WINDOW;
        double sum = 0.0;
        for (std::int64_t i = 0; i < n; ++i) {
            sum += m_recent[static_cast<std::size_t>(i)];
        }
        return n > 0 ? sum / static_cast<double>(n) : 0.0;
    }
    double recent_fps() const {
        const double ms = recent_ms();
        return ms > 0.0 ? 1000.0 / ms : 0.0;
    }
    // Mean over every frame but the first (the first frame's alone when there is one frame).
    double mean_ms() const { return m_after_first.count > 0 ? m_after_first.value() : m_last_ms; }

private:
    Stopwatch m_watch;
    std::array<double, WINDOW> m_recent{};
    Mean m_after_first;
    double m_last_ms = 0.0;
    std::int64_t m_frames = 0;
};

}  // namespace pliant::viewer
