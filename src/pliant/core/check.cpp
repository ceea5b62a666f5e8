#include "pliant/core/check.hpp"

namespace pliant::detail {

void check_failed(const char* expression, const std::string& values, std::source_location where) {
    throw InternalError(fmt::format("check failed: {} {}at {}:{} in {}", expression,
                                    values.empty() ? std::string{} : values + " ",
                                    where.file_name(), where.line(), where.function_name()));
}

}  // namespace pliant::detail
