// Parallel exclusive prefix sum over fixed chunks (deterministic for 1 and N threads; exact for
// integers). out[i] = in[0] + … + in[i-1]; returns the total. `in` and `out` may be the same span.
// Complexity O(n), two passes.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {

template <typename T>
T exclusive_scan(std::span<const T> in, std::span<T> out, std::int64_t grain = 1 << 15) {
    PLIANT_CHECK_EQ(in.size(), out.size());
    const auto n = static_cast<std::int64_t>(in.size());
    const std::int64_t count = num_chunks(n, grain);
    if (count <= 1) {
        T sum{};
        for (std::int64_t i = 0; i < n; ++i) {
            const T v = in[static_cast<std::size_t>(i)];
            out[static_cast<std::size_t>(i)] = sum;
            sum += v;
        }
        return sum;
    }
    // Step 1: chunk sums. Step 2: scan of chunk sums. Step 3: scan inside chunks with offsets.
    std::vector<T> offsets(static_cast<std::size_t>(count) + 1, T{});
    parallel_for_chunks(n, grain, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
        T sum{};
        for (std::int64_t i = begin; i < end; ++i) {
            sum += in[static_cast<std::size_t>(i)];
        }
        offsets[static_cast<std::size_t>(c) + 1] = sum;
    });
    for (std::size_t c = 1; c < offsets.size(); ++c) {
        offsets[c] += offsets[c - 1];
    }
    parallel_for_chunks(n, grain, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
        T sum = offsets[static_cast<std::size_t>(c)];
        for (std::int64_t i = begin; i < end; ++i) {
            const T v = in[static_cast<std::size_t>(i)];
            out[static_cast<std::size_t>(i)] = sum;
            sum += v;
        }
    });
    return offsets.back();
}

template <typename T>
T exclusive_scan(std::span<T> values, std::int64_t grain = 1 << 15) {
    return exclusive_scan(std::span<const T>(values), values, grain);
}

}  // namespace pliant
