#include "pliant/core/check.hpp"

namespace pliant::detail {

void check_failed(const char* expression, const std::string& values, SourceLocation where) {
    throw InternalError(fmt::format("check failed: {} {}at {}:{} in {}", expression,
                                    values.empty() ? std::string{} : values + " ", where.file,
                                    where.line, where.function));
}

}  // namespace pliant::detail
