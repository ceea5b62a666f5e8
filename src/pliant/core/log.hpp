// The log sink. Kernels never print; apps and io report progress and warnings through log_*,
// which go to one process-wide sink (default: stderr, "pliant: warning: …"). Tests and embedding
// applications replace the sink. Thread safe.
#pragma once

#include <fmt/format.h>

#include <functional>
#include <string_view>

namespace pliant {

enum class LogLevel { debug, info, warning, error };

using LogSink = std::function<void(LogLevel, std::string_view)>;

// Replaces the sink; an empty function restores the default. Returns the previous sink.
LogSink set_log_sink(LogSink sink);
// Messages below this level are dropped (default: info).
void set_log_level(LogLevel level);
LogLevel log_level();

void log_message(LogLevel level, std::string_view message);

// "debug", "info", "warning" or "error": the word the default sink prints.
const char* level_name(LogLevel level);

template <typename... Args>
void log_info(fmt::format_string<Args...> format, Args&&... args) {
    if (log_level() <= LogLevel::info) {
        log_message(LogLevel::info, fmt::format(format, std::forward<Args>(args)...));
    }
}
template <typename... Args>
void log_warning(fmt::format_string<Args...> format, Args&&... args) {
    if (log_level() <= LogLevel::warning) {
        log_message(LogLevel::warning, fmt::format(format, std::forward<Args>(args)...));
    }
}
template <typename... Args>
void log_debug(fmt::format_string<Args...> format, Args&&... args) {
    if (log_level() <= LogLevel::debug) {
        log_message(LogLevel::debug, fmt::format(format, std::forward<Args>(args)...));
    }
}

}  // namespace pliant
