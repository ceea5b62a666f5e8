// What every libFuzzer harness shares: the input written to a file (the readers take paths), and
// the contract under test — a reader either returns or throws a pliant::Error; anything else
// (another exception, a crash, a sanitizer report, a leak) is a finding.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::fuzz {

// One thread for every parallel loop: oneTBB splits a loop's range by work stealing, so with more
// threads its partitioner runs differently from run to run, and with it the coverage libFuzzer
// steers by. With one, a fixed seed and input count execute the same inputs on every machine.
inline const bool single_threaded = [] {
    pliant::set_num_threads(1);
    return true;
}();

// A scratch directory per process: $TMPDIR/pliant-fuzz-<pid, 10 digits>. The fixed width keeps
// the paths (and so the messages that name them, and the code that formats those) the same
// length in every run.
inline const std::filesystem::path& scratch() {
    static const std::filesystem::path dir = [] {
        std::string pid = std::to_string(::getpid());
        pid.insert(0, 10 - std::min<std::size_t>(pid.size(), 10), '0');
        std::filesystem::path d = std::filesystem::temp_directory_path() / ("pliant-fuzz-" + pid);
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

// Writes bytes to scratch()/name and returns the path.
inline std::filesystem::path write_input(const std::string& name, std::string_view bytes) {
    const std::filesystem::path path = scratch() / name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
        std::abort();
    }
    if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) {
        std::abort();
    }
    std::fclose(f);
    return path;
}

// The first part of `data` up to the first NUL byte, and the rest after it (for formats made of
// two files: TetGen .node + .ele, a JSON sidecar + its data).
inline std::pair<std::string_view, std::string_view> split_at_nul(std::string_view data) {
    const std::size_t nul = data.find('\0');
    if (nul == std::string_view::npos) {
        return {data, {}};
    }
    return {data.substr(0, nul), data.substr(nul + 1)};
}

// Runs read(); pliant::Error is the documented way to refuse input. Anything else aborts, so that
// libFuzzer records the input.
template <typename Read>
void expect_result_or_error(Read&& read) {
    try {
        read();
    } catch (const pliant::Error&) {
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fuzz: unexpected exception: %s\n", e.what());
        std::abort();
    }
}

// Readers refuse volumes above this many bytes (the harness must not run out of memory on a
// lying header that passes the other checks).
inline constexpr std::size_t MAX_BYTES = std::size_t{64} << 20;

}  // namespace pliant::fuzz
