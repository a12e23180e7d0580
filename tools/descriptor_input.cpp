#include "descriptor_input.hpp"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace umbra::cli {

DescriptorInput::DescriptorInput(int fd) : fd_(fd), owned_(false) {}

DescriptorInput::DescriptorInput(const std::string& path)
    : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)), owned_(true) {
  if (fd_ < 0) throw std::runtime_error(std::string("cannot be opened for reading: ") + std::strerror(errno));
}

DescriptorInput::~DescriptorInput() {
  if (owned_) ::close(fd_);
}

DescriptorInput::int_type DescriptorInput::underflow() {
  if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
  for (;;) {
    const ssize_t n = ::read(fd_, buffer_.data(), buffer_.size());
    if (n > 0) {
      setg(buffer_.data(), buffer_.data(), buffer_.data() + n);
      return traits_type::to_int_type(buffer_[0]);
    }
    if (n == 0) return traits_type::eof();
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) {  // a non-blocking descriptor (set so by the writer's side)
      pollfd ready{fd_, POLLIN, 0};
      ::poll(&ready, 1, -1);
      continue;
    }
    read_error_ = std::strerror(errno);
    // The istream turns an exception from its buffer into badbit, which
    // the reader reports; returning eof would end the input silently.
    throw std::runtime_error(read_error_);
  }
}

std::streamsize DescriptorInput::showmanyc() {
  pollfd ready{fd_, POLLIN, 0};
  return ::poll(&ready, 1, 0) == 1 ? 1 : 0;  // POLLIN, POLLHUP (end) or POLLERR: a read returns at once
}

}  // namespace umbra::cli
