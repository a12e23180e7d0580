#include "printable_text.hpp"

#include "message_text.hpp"

namespace umbra::cli {

std::string printable(std::string_view text, std::size_t max_shown) {
  return detail::escape(text, {.max_bytes = max_shown,
                                  .unprintable = detail::Unprintable::hex,
                                  .cut = detail::CutMark::dots_count});
}

}  // namespace umbra::cli
