// Quoting untrusted bytes for a message or a log line: what `umbra query`
// says about a bad input word and what `umbra view --serve` prints of a
// request line. A terminal must never receive the bytes themselves (an
// escape sequence could set its title, clear it or worse), so anything
// outside printable ASCII is written as \xNN. Cost: one pass over at most
// `max_shown` bytes. The quoting itself is umbra_io's (io/common/message_text.hpp),
// the one every error message of umbra's file code uses.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace umbra::cli {

/// `text` with bytes outside printable ASCII (0x20..0x7e), and ' and \, as \xNN, cut after
/// `max_shown` bytes with "... (N characters)" appended.
std::string printable(std::string_view text, std::size_t max_shown = 40);

}  // namespace umbra::cli
