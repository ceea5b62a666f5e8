// The parallel layer: the only place in pliant that talks to a threading library (oneTBB, in
// parallel.cpp). Every loop is split into *fixed chunks* — chunk c covers
// [c·grain, min(n, (c+1)·grain)) — whose boundaries depend only on n and grain, never on the number
// of threads. Reductions combine chunk results in chunk order and variable-length outputs are
// concatenated in chunk order, so every result is bitwise identical for 1 and N threads.
//
// Bodies may run concurrently on different chunks; they must not throw (kernels never do).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>

#include "pliant/core/function_ref.hpp"

namespace pliant {

// Limits every later parallel call in the process to n threads (n ≥ 1), or to all hardware
// threads (n = 0). Not to be called while a parallel loop runs.
void set_num_threads(int n);
// The threads a parallel call made here may use (≥ 1): the limit, or less inside a
// BackgroundTask of lower concurrency (core/parallel_task.hpp), whose work sees its own
// concurrency — 1 there means every parallel call runs inline on the calling thread.
int num_threads();
// Hardware threads available to this process.
int hardware_threads();

inline constexpr std::int64_t DEFAULT_GRAIN = 4096;

// Number of fixed chunks for n items (0 for n ≤ 0).
constexpr std::int64_t num_chunks(std::int64_t n, std::int64_t grain) {
    return n <= 0 ? 0 : (n + grain - 1) / grain;
}

namespace detail {
// Runs body(c) for c in [0, count), in parallel when the limit allows and count > 1.
void run_chunks(std::int64_t count, FunctionRef<void(std::int64_t)> body);
}  // namespace detail

// body(chunk, begin, end) for every fixed chunk of [0, n).
template <typename Body>
void parallel_for_chunks(std::int64_t n, std::int64_t grain, Body&& body) {
    const std::int64_t count = num_chunks(n, grain);
    detail::run_chunks(count, [&](std::int64_t c) {
        const std::int64_t begin = c * grain;
        const std::int64_t end = begin + grain < n ? begin + grain : n;
        body(c, begin, end);
    });
}

// body(i) for every i in [0, n).
template <typename Body>
void parallel_for(std::int64_t n, Body&& body, std::int64_t grain = DEFAULT_GRAIN) {
    parallel_for_chunks(n, grain, [&](std::int64_t, std::int64_t begin, std::int64_t end) {
        for (std::int64_t i = begin; i < end; ++i) {
            body(i);
        }
    });
}

// Deterministic reduction: partial = map(begin, end) per fixed chunk, then
// combine(…combine(combine(identity, p0), p1)…) in chunk order; the running result is moved
// into combine (a combine that appends is linear, not quadratic).
template <typename T, typename Map, typename Combine>
T parallel_reduce(std::int64_t n, T identity, Map&& map, Combine&& combine,
                  std::int64_t grain = DEFAULT_GRAIN) {
    // One slot per chunk in a plain array: std::vector<bool> would pack the slots into shared
    // words and make concurrent writes race.
    const std::int64_t count = num_chunks(n, grain);
    const auto partials = std::make_unique<T[]>(static_cast<std::size_t>(count));
    parallel_for_chunks(n, grain, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
        partials[static_cast<std::size_t>(c)] = map(begin, end);
    });
    T result = identity;
    for (std::int64_t c = 0; c < count; ++c) {
        result = combine(std::move(result), partials[static_cast<std::size_t>(c)]);
    }
    return result;
}

}  // namespace pliant
