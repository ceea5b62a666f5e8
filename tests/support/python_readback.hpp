// Runs a Python script of the repository's tests on a file with Debian's /usr/bin/python3 and
// parses the JSON it prints: readers independent of pliant (OpenVDB's pyopenvdb, the xml module)
// checking what pliant wrote. A non-zero exit status is a test failure naming the command.
#pragma once

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stdio.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace pliant::test {

inline constexpr const char* SYSTEM_PYTHON = "/usr/bin/python3";

// `script`: a path relative to the source tree (PLIANT_SOURCE_DIR), e.g. "tests/io/x.py".
inline nlohmann::json run_python_readback(const std::string& script,
                                          const std::filesystem::path& path) {
    const std::string command = std::string(SYSTEM_PYTHON) + " " + PLIANT_SOURCE_DIR + "/" +
                                script + " '" + path.string() + "'";
    FILE* pipe = ::popen(command.c_str(), "r");
    EXPECT_NE(pipe, nullptr) << command;
    std::string text;
    char buffer[4096];
    std::size_t n = 0;
    while (pipe != nullptr && (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) {
        text.append(buffer, n);
    }
    EXPECT_EQ(pipe != nullptr ? ::pclose(pipe) : -1, 0) << command;
    return nlohmann::json::parse(text);
}

}  // namespace pliant::test
