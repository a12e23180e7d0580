// FormatError: a file that is not what it claims to be.
//
// Every reader throws this for malformed input, with the file name and the
// position (line for text formats, byte offset for binary ones) in what().
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace umbra {

class FormatError : public std::runtime_error {
 public:
  /// "FILE: MESSAGE"
  FormatError(const std::string& file, const std::string& message)
      : std::runtime_error(file + ": " + message), file_(file) {}

  [[nodiscard]] const std::string& file() const { return file_; }

  /// "FILE:LINE: MESSAGE" (text formats).
  static FormatError at_line(const std::string& file, std::uint64_t line, const std::string& message) {
    return FormatError(file + ":" + std::to_string(line), message, file);
  }
  /// "FILE: byte OFFSET: MESSAGE" (binary formats).
  static FormatError at_byte(const std::string& file, std::uint64_t offset, const std::string& message) {
    return FormatError(file + ": byte " + std::to_string(offset), message, file);
  }

 private:
  FormatError(const std::string& where, const std::string& message, const std::string& file)
      : std::runtime_error(where + ": " + message), file_(file) {}
  std::string file_;
};

}  // namespace umbra
