#include "pliant/core/check.hpp"

#include <gtest/gtest.h>

#include <string>

#include "pliant/core/log.hpp"
#include "pliant/core/timer.hpp"

namespace pliant {
namespace {

TEST(Check, FailureNamesExpressionValuesAndLocation) {
    const int expected = 3;
    const int got = 4;
    try {
        PLIANT_CHECK_EQ(expected, got);
        FAIL() << "no throw";
    } catch (const InternalError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("expected == got"), std::string::npos) << message;
        EXPECT_NE(message.find("(3 vs 4)"), std::string::npos) << message;
        EXPECT_NE(message.find("check_test.cpp"), std::string::npos) << message;
    }
    EXPECT_NO_THROW(PLIANT_CHECK_LT(1, 2));
    EXPECT_THROW(PLIANT_CHECK(1 > 2), InternalError);
}

TEST(Check, IsAnExpressionSafeInIfElse) {
    int branch = 0;
    if (branch == 0)
        PLIANT_CHECK(true);
    else
        branch = 2;
    EXPECT_EQ(branch, 0);
}

TEST(Log, SinkReceivesMessagesAboveLevel) {
    std::vector<std::pair<LogLevel, std::string>> got;
    const LogSink previous = set_log_sink([&](LogLevel level, std::string_view message) {
        got.emplace_back(level, std::string(message));
    });
    set_log_level(LogLevel::info);
    log_debug("hidden {}", 1);
    log_info("shown {}", 2);
    log_warning("careful {}", 3);
    set_log_sink(previous);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].second, "shown 2");
    EXPECT_EQ(got[1].first, LogLevel::warning);
}

TEST(Timer, MedianOfSamples) {
    EXPECT_EQ(median({}), 0.0);
    EXPECT_EQ(median({3.0, 1.0, 2.0}), 2.0);
    EXPECT_EQ(median({4.0, 1.0, 2.0, 3.0}), 2.5);
    double total = 0.0;
    { ScopedTimer timer(total); }
    EXPECT_GE(total, 0.0);
}

}  // namespace
}  // namespace pliant
