// How umbra's file code names things in its error messages: a system error,
// untrusted bytes (quoted so that a terminal never receives them raw), a
// float with its bits, a node of a tree file. Every reader, every map-file
// format and the umbra program use these, so that a byte or a node is shown
// the same way wherever a message mentions one. Not installed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace umbra::detail {

/// The system's text for an errno value, e.g. "No such file or directory".
std::string errno_text(int error);

/// Throws std::runtime_error("WHAT FILE: reason"), e.g. "cannot read a.bt: Input/output error".
[[noreturn]] void throw_io(std::string_view what, std::string_view file, int error);

/// How escape() shows a byte outside printable ASCII (0x20 to 0x7e).
enum class Unprintable : std::uint8_t {
  /// As \xNN, and so are ' and \ (binary headers, words typed by a user:
  /// every byte can be told apart).
  hex,
  /// As '?' (lines of text files: a stray control byte keeps the line readable).
  question_mark,
  /// As '?', except bytes from 0x80 on, kept (parts of UTF-8 characters in text files).
  question_mark_keep_utf8,
};

/// What escape() shows after the first `max_bytes` bytes of a longer text.
enum class CutMark : std::uint8_t {
  dots,        ///< "..."
  dots_count,  ///< "... (N characters)", N the whole text's length
};

struct EscapeStyle {
  std::size_t max_bytes = 80;
  Unprintable unprintable = Unprintable::question_mark;
  CutMark cut = CutMark::dots;
};

/// `text` made safe for a message or a log line as `style` says, unquoted.
std::string escape(std::string_view text, EscapeStyle style);

/// escape(text, style) between single quotes.
std::string quote(std::string_view text, EscapeStyle style = {});

/// quote() in the style of binary files: unprintable bytes as \xNN, cut after `max_bytes`.
std::string quote_bytes(std::string_view text, std::size_t max_bytes = 64);

/// A float with enough digits to tell it apart from any other, and its bits:
/// "3.5999999 (bits 0x40666666)".
std::string float_text(float value);

/// "node at DEPTH_NAME D, key (x, y, z)": a tree node named by its depth, as
/// the file format counts depths (`depth_name`: "depth", "OctoMap depth"),
/// and the key of its first voxel (`code`, the Morton code of the node).
std::string node_text(std::string_view depth_name, int depth, std::uint64_t code);

}  // namespace umbra::detail
