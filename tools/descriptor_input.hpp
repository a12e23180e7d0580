// Reading `umbra query --input` (a file, or standard input for "-") through
// a std::streambuf over a POSIX file descriptor, for one thing std::cin and
// std::ifstream do not promise: in_avail() says whether a read would wait.
// std::cin shares stdio's unbuffered reads and reports nothing available, so
// the command would have to flush its answers after every line; here a pipe
// or terminal with no line ready reports 0 (poll), and the command flushes
// exactly when it is about to wait for its writer, which keeps a program
// that writes a query and waits for its answer going, at full speed for a
// file. Cost: one read(2) per 64 KiB, one poll(2) per emptied buffer.
#pragma once

#include <array>
#include <streambuf>
#include <string>

namespace umbra::cli {

class DescriptorInput : public std::streambuf {
 public:
  /// Reads `fd`, which stays open (standard input).
  explicit DescriptorInput(int fd);
  /// Opens `path` for reading; throws std::runtime_error with the system's
  /// reason when it cannot.
  explicit DescriptorInput(const std::string& path);
  ~DescriptorInput() override;
  DescriptorInput(const DescriptorInput&) = delete;
  DescriptorInput& operator=(const DescriptorInput&) = delete;

  /// The system's reason for the last failed read ("Is a directory"), or "".
  [[nodiscard]] const std::string& read_error() const { return read_error_; }

 protected:
  int_type underflow() override;
  /// 1 when a read would not wait (data, or the end of the input), else 0.
  std::streamsize showmanyc() override;

 private:
  int fd_;
  bool owned_;
  std::string read_error_;
  std::array<char, 65536> buffer_{};
};

}  // namespace umbra::cli
