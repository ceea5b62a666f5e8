// PLIANT_CHECK(cond) / PLIANT_CHECK_EQ(a, b) / PLIANT_CHECK_LT …: always on, for invariants outside
// hot loops; a failure throws InternalError naming the expression, both values and the source
// location. PLIANT_DCHECK*: the same in debug builds, nothing in release builds (NDEBUG).
// All of them are single expressions (no dangling-else hazard). The _OP forms evaluate their
// arguments once more when the check fails (to print them): pass side-effect-free expressions.
#pragma once

#include <fmt/format.h>

#include <string>

#include "pliant/core/error.hpp"

namespace pliant::detail {

// Where a check sits. Not std::source_location: clang 14 with libstdc++ 12 (the fuzzing build)
// has no <source_location>.
struct SourceLocation {
    const char* file;
    int line;
    const char* function;
};

[[noreturn]] void check_failed(const char* expression, const std::string& values,
                               SourceLocation where);

template <typename A, typename B>
[[noreturn]] void check_op_failed(const char* expression, const A& a, const B& b,
                                  SourceLocation where) {
    check_failed(expression, fmt::format("({} vs {})", a, b), where);
}

}  // namespace pliant::detail

#define PLIANT_SOURCE_LOCATION_ (::pliant::detail::SourceLocation{__FILE__, __LINE__, __func__})

#define PLIANT_CHECK(cond)         \
    ((cond) ? static_cast<void>(0) \
            : ::pliant::detail::check_failed(#cond, std::string{}, PLIANT_SOURCE_LOCATION_))

#define PLIANT_CHECK_OP_(a, b, op)                                               \
    (((a)op(b)) ? static_cast<void>(0)                                           \
                : ::pliant::detail::check_op_failed(#a " " #op " " #b, (a), (b), \
                                                    PLIANT_SOURCE_LOCATION_))

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
