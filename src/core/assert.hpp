// UMBRA_ASSERT: checks of internal invariants, with a switch of their own.
//
// Misuse and bad input are reported with exceptions; UMBRA_ASSERT is only for
// "this cannot happen unless umbra has a bug". It is compiled in when the
// library is built with UMBRA_ENABLE_ASSERTS (the test build does), and costs
// nothing otherwise. A failed assertion throws umbra::AssertionError rather
// than aborting, so a host program is never killed by the library.
#pragma once

#include <stdexcept>
#include <string>

namespace umbra {

struct AssertionError : std::logic_error {
  using std::logic_error::logic_error;
};

[[noreturn]] void assertion_failed(const char* condition, const char* file, int line);

}  // namespace umbra

#if defined(UMBRA_ENABLE_ASSERTS)
#define UMBRA_ASSERT(condition)                                            \
  do {                                                                     \
    if (!(condition)) ::umbra::assertion_failed(#condition, __FILE__, __LINE__); \
  } while (false)
#else
#define UMBRA_ASSERT(condition) \
  do {                          \
  } while (false)
#endif
