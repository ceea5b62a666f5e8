#include "pliant/core/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace pliant {
namespace {

std::mutex& sink_mutex() {
    static std::mutex mutex;
    return mutex;
}
LogSink& sink() {
    static LogSink s;
    return s;
}
std::atomic<LogLevel>& level() {
    static std::atomic<LogLevel> l{LogLevel::info};
    return l;
}

}  // namespace

LogSink set_log_sink(LogSink new_sink) {
    std::lock_guard lock(sink_mutex());
    LogSink previous = std::move(sink());
    sink() = std::move(new_sink);
    return previous;
}

void set_log_level(LogLevel l) {
    level().store(l);
}
LogLevel log_level() {
    return level().load();
}

void log_message(LogLevel l, std::string_view message) {
    std::lock_guard lock(sink_mutex());
    if (sink()) {
        sink()(l, message);
        return;
    }
    std::fprintf(stderr, "pliant: %s: %.*s\n", level_name(l), static_cast<int>(message.size()),
                 message.data());
}

const char* level_name(LogLevel l) {
    switch (l) {
        case LogLevel::debug:
            return "debug";
        case LogLevel::info:
            return "info";
        case LogLevel::warning:
            return "warning";
        case LogLevel::error:
            return "error";
    }
    return "?";
}

}  // namespace pliant
