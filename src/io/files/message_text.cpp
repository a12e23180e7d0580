// The message helpers of message_text.hpp. Cost: one pass over at most
// max_bytes bytes of the quoted text; used on error paths only.
#include "message_text.hpp"

#include <bit>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "umbra/core/morton.hpp"

namespace umbra::detail {

std::string errno_text(int error) { return std::generic_category().message(error); }

void throw_io(std::string_view what, std::string_view file, int error) {
  throw std::runtime_error(std::string(what) + " " + std::string(file) + ": " + errno_text(error));
}

namespace {

void append_hex(std::string& out, unsigned char c) {
  static constexpr char kHex[] = "0123456789abcdef";
  out += "\\x";
  out += kHex[c >> 4];
  out += kHex[c & 15];
}

}  // namespace

std::string escape(std::string_view text, EscapeStyle style) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < style.max_bytes; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const bool printable = c >= 0x20 && c < 0x7f;
    switch (style.unprintable) {
      case Unprintable::hex:
        if (printable && c != '\'' && c != '\\') {
          out += static_cast<char>(c);
        } else {
          append_hex(out, c);
        }
        break;
      case Unprintable::question_mark:
        out += printable ? static_cast<char>(c) : '?';
        break;
      case Unprintable::question_mark_keep_utf8:
        out += printable || c >= 0x80 ? static_cast<char>(c) : '?';
        break;
    }
  }
  if (text.size() > style.max_bytes) {
    out += "...";
    if (style.cut == CutMark::dots_count) out += " (" + std::to_string(text.size()) + " characters)";
  }
  return out;
}

std::string quote(std::string_view text, EscapeStyle style) { return "'" + escape(text, style) + "'"; }

std::string quote_bytes(std::string_view text, std::size_t max_bytes) {
  return quote(text, {.max_bytes = max_bytes, .unprintable = Unprintable::hex});
}

std::string float_text(float value) {
  std::ostringstream out;
  out.precision(9);  // enough to tell any two floats apart
  char bits[16];
  std::snprintf(bits, sizeof bits, "0x%08x", static_cast<unsigned>(std::bit_cast<std::uint32_t>(value)));
  out << value << " (bits " << bits << ")";
  return out.str();
}

std::string node_text(std::string_view depth_name, int depth, std::uint64_t code) {
  const Key key = morton::decode(code);
  return "node at " + std::string(depth_name) + " " + std::to_string(depth) + ", key (" + std::to_string(key.x) +
         ", " + std::to_string(key.y) + ", " + std::to_string(key.z) + ")";
}

}  // namespace umbra::detail
