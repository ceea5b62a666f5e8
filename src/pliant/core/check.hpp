// PLIANT_CHECK(cond) / PLIANT_CHECK_EQ(a, b) / PLIANT_CHECK_LT …: always on, for invariants outside
// hot loops; a failure throws InternalError naming the expression, both values and the source
// location. PLIANT_DCHECK*: the same in debug builds, nothing in release builds (NDEBUG).
// All of them are single expressions (no dangling-else hazard). The _OP forms evaluate their
// arguments once more when the check fails (to print them): pass side-effect-free expressions.
#pragma once

#include <fmt/format.h>

#include <source_location>
#include <string>

#include "pliant/core/error.hpp"

namespace pliant::detail {

[[noreturn]] void check_failed(const char* expression, const std::string& values,
                               std::source_location where);

template <typename A, typename B>
[[noreturn]] void check_op_failed(const char* expression, const A& a, const B& b,
                                  std::source_location where) {
    check_failed(expression, fmt::format("({} vs {})", a, b), where);
}

}  // namespace pliant::detail

#define PLIANT_CHECK(cond)      \
    ((cond)                     \
         ? static_cast<void>(0) \
         : ::pliant::detail::check_failed(#cond, std::string{}, std::source_location::current()))

#define PLIANT_CHECK_OP_(a, b, op)                                               \
    (((a)op(b)) ? static_cast<void>(0)                                           \
                : ::pliant::detail::check_op_failed(#a " " #op " " #b, (a), (b), \
                                                    std::source_location::current()))

#define PLIANT_CHECK_EQ(a, b) PLIANT_CHECK_OP_(a, b, ==)
#define PLIANT_CHECK_NE(a, b) PLIANT_CHECK_OP_(a, b, !=)
#define PLIANT_CHECK_LT(a, b) PLIANT_CHECK_OP_(a, b, <)
#define PLIANT_CHECK_LE(a, b) PLIANT_CHECK_OP_(a, b, <=)
#define PLIANT_CHECK_GT(a, b) PLIANT_CHECK_OP_(a, b, >)
#define PLIANT_CHECK_GE(a, b) PLIANT_CHECK_OP_(a, b, >=)

#ifdef NDEBUG
#define PLIANT_DCHECK(cond) static_cast<void>(0)
#define PLIANT_DCHECK_EQ(a, b) static_cast<void>(0)
#define PLIANT_DCHECK_LT(a, b) static_cast<void>(0)
#define PLIANT_DCHECK_LE(a, b) static_cast<void>(0)
#else
#define PLIANT_DCHECK(cond) PLIANT_CHECK(cond)
#define PLIANT_DCHECK_EQ(a, b) PLIANT_CHECK_EQ(a, b)
#define PLIANT_DCHECK_LT(a, b) PLIANT_CHECK_LT(a, b)
#define PLIANT_DCHECK_LE(a, b) PLIANT_CHECK_LE(a, b)
#endif
