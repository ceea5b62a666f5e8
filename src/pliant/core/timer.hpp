// Wall-clock timing: Stopwatch (monotonic, milliseconds), ScopedTimer, which adds the time of a
// scope to a caller's accumulator (per-stage timings in stats), and RunningMean.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace pliant {

class Stopwatch {
public:
    Stopwatch() : m_start(Clock::now()) {}
    void restart() { m_start = Clock::now(); }
    // Milliseconds since construction or the last restart.
    double elapsed_ms() const {
        return std::chrono::duration<double, std::milli>(Clock::now() - m_start).count();
    }

private:
    using Clock = std::chrono::steady_clock;
    Clock::time_point m_start;
};

class ScopedTimer {
public:
    explicit ScopedTimer(double& accumulator_ms) : m_accumulator(accumulator_ms) {}
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;
    ~ScopedTimer() { m_accumulator += m_watch.elapsed_ms(); }

private:
    double& m_accumulator;
    Stopwatch m_watch;
};

// A running sum and count of samples (per-frame timings of a run; saved in checkpoints).
struct RunningMean {
    double sum = 0.0;
    int count = 0;
    void add(double x) {
        sum += x;
        ++count;
    }
    double mean() const { return count > 0 ? sum / count : 0.0; }
};

// Median of a sample (by value; empty → 0). For reporting repeated timings.
inline double median(std::vector<double> samples) {
    if (samples.empty()) {
        return 0.0;
    }
    const auto mid = samples.begin() + static_cast<std::ptrdiff_t>(samples.size() / 2);
    std::nth_element(samples.begin(), mid, samples.end());
    if (samples.size() % 2 == 1) {
        return *mid;
    }
    const double upper = *mid;
    const double lower = *std::max_element(samples.begin(), mid);
    return 0.5 * (lower + upper);
}

}  // namespace pliant
