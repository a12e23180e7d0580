#include "core/assert.hpp"

namespace umbra {

void assertion_failed(const char* condition, const char* file, int line) {
  throw AssertionError(std::string("umbra internal error: assertion '") + condition + "' failed at " +
                       file + ":" + std::to_string(line));
}

}  // namespace umbra
