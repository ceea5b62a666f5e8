// FunctionRef<R(Args...)>: a non-owning, non-allocating reference to a callable, valid while the
// callable lives. Lets the parallel layer keep oneTBB out of headers without std::function's
// allocation.
#pragma once

#include <memory>
#include <type_traits>
#include <utility>

namespace pliant {

template <typename Signature>
class FunctionRef;

template <typename R, typename... Args>
class FunctionRef<R(Args...)> {
public:
    template <typename F>
    requires(!std::is_same_v<std::remove_cvref_t<F>, FunctionRef> &&
             std::is_invocable_r_v<R, F&, Args...>)
        // Implicit: used like a function parameter. The requires-clause keeps FunctionRef itself
        // out (clang-tidy 14 does not read requires-clauses).
        // NOLINTNEXTLINE(google-explicit-constructor, bugprone-forwarding-reference-overload)
        FunctionRef(F&& f)
        : m_object(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
          m_call([](void* object, Args... args) -> R {
              return (*static_cast<std::remove_reference_t<F>*>(object))(
                  std::forward<Args>(args)...);
          }) {}

    R operator()(Args... args) const { return m_call(m_object, std::forward<Args>(args)...); }

private:
    void* m_object;
    R (*m_call)(void*, Args...);
};

}  // namespace pliant
