// FunctionRef: a non-owning reference to a callable, for visitors.
//
// Calls cost one indirect call and nothing is allocated (std::function may
// allocate for a lambda with captures). The callable must outlive the call
// that receives the FunctionRef, which is always so for a visitor passed to a
// function.
#pragma once

#include <memory>
#include <type_traits>
#include <utility>

namespace umbra {

template <typename Signature>
class FunctionRef;

template <typename R, typename... Args>
class FunctionRef<R(Args...)> {
 public:
  template <typename F>
    requires(!std::is_same_v<std::remove_cvref_t<F>, FunctionRef> && std::is_invocable_r_v<R, F&, Args...>)
  FunctionRef(F&& f) noexcept  // NOLINT(google-explicit-constructor): converts like std::function
      : object_(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
        call_([](void* object, Args... args) -> R {
          return (*static_cast<std::remove_reference_t<F>*>(object))(std::forward<Args>(args)...);
        }) {}

  R operator()(Args... args) const { return call_(object_, std::forward<Args>(args)...); }

 private:
  void* object_;
  R (*call_)(void*, Args...);
};

}  // namespace umbra
