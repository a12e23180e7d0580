#include "printable_text.hpp"

#include "message_text.hpp"

namespace umbra::cli {

std::string printable(std::string_view text, std::size_t max_shown) {
  return io_detail::escape(text, {.max_bytes = max_shown,
                                  .unprintable = io_detail::Unprintable::hex,
                                  .cut = io_detail::CutMark::dots_count});
}

}  // namespace umbra::cli
