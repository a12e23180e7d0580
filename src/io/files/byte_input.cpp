// InputFile, ByteReader and LineReader (byte_input.hpp).
//
// Cost model: every read goes through one buffer per reader (1 MiB by
// default for bytes, growing only for records or lines longer than the
// buffer, up to the file size or a line limit), so a reader's memory is
// independent of the file size; nothing allocates per record or per line.
#include "byte_input.hpp"

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "message_text.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra::detail {

namespace {
constexpr std::size_t kLineChunkBytes = 256 * 1024;
/// How much of an overlong line its message shows.
constexpr std::size_t kLineStartShown = 80;

bool is_blank(std::string_view line) {
  return std::all_of(line.begin(), line.end(),
                     [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; });
}
}  // namespace

void reject_directory(const std::filesystem::path& path) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw std::runtime_error("cannot open " + path.string() + ": it is a directory");
  }
}

// --- InputFile ---------------------------------------------------------------

InputFile::InputFile(const std::filesystem::path& path, std::string_view format, std::string_view kind)
    : name_(path.string()), named_(kind.empty() ? name_ : std::string(kind) + " '" + name_ + "'") {
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor_ < 0) throw_io("cannot open", named_, errno);
  struct stat info {};
  if (::fstat(descriptor_, &info) != 0) {
    const int error = errno;
    ::close(descriptor_);
    throw_io("cannot open", named_, error);
  }
  if (S_ISDIR(info.st_mode)) {
    ::close(descriptor_);
    throw std::runtime_error("cannot open " + named_ + ": it is a directory");
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(descriptor_);
    std::string reason = "not a regular file";
    if (!format.empty()) reason += " (" + std::string(format) + " files are read with seeks)";
    throw std::runtime_error("cannot open " + named_ + ": " + reason);
  }
  size_ = static_cast<std::uint64_t>(info.st_size);
}

InputFile::~InputFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

std::size_t InputFile::read_at(std::uint64_t offset, void* out, std::size_t capacity) const {
  auto* bytes = static_cast<unsigned char*>(out);
  std::size_t done = 0;
  while (done < capacity) {
    const ::ssize_t got = ::pread(descriptor_, bytes + done, capacity - done, static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw_io("cannot read", named_, errno);
    }
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  return done;
}

// --- ByteReader --------------------------------------------------------------

ByteReader::ByteReader(const InputFile& file, std::uint64_t offset, std::size_t buffer_bytes)
    : file_(&file),
      buffer_bytes_(std::max<std::size_t>(buffer_bytes, 64)),
      buffer_end_offset_(offset),
      size_(file.size()) {}

ByteReader::ByteReader(std::span<const std::uint8_t> bytes)
    : data_(bytes.data()), end_(bytes.size()), buffer_end_offset_(bytes.size()), size_(bytes.size()) {}

ByteReader::ByteReader(const ByteReader& source, std::uint64_t offset) : size_(source.size_) {
  if (source.file_ != nullptr) {
    file_ = source.file_;
    buffer_bytes_ = source.buffer_bytes_;
    buffer_end_offset_ = offset;
    return;
  }
  // Memory: the bytes from the start, positioned at `offset`.
  const std::uint64_t source_start = source.buffer_end_offset_ - source.end_;  // 0 for memory
  data_ = source.data_;
  end_ = source.end_;
  buffer_end_offset_ = source.buffer_end_offset_;
  begin_ = static_cast<std::size_t>(std::min(std::max(offset, source_start) - source_start, std::uint64_t{end_}));
}

bool ByteReader::fill(std::size_t count) {
  if (file_ == nullptr) return false;  // memory: every byte is already in data_
  const std::size_t have = end_ - begin_;
  // Never past the size the file had when it was opened.
  const std::uint64_t left = size_ - std::min(size_, buffer_end_offset_);
  if (count - have > left) return false;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, have);
    begin_ = 0;
    end_ = have;
  }
  const auto wanted = static_cast<std::size_t>(std::max<std::uint64_t>(count, std::min<std::uint64_t>(buffer_bytes_, have + left)));
  if (buffer_.size() < wanted) buffer_.resize(wanted);  // bounded by the file size (checked above)
  data_ = buffer_.data();
  while (end_ < count) {
    const auto capacity =
        static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size() - end_, size_ - buffer_end_offset_));
    const std::size_t got = file_->read_at(buffer_end_offset_, buffer_.data() + end_, capacity);
    if (got == 0) return false;  // the file shrank after it was opened
    end_ += got;
    buffer_end_offset_ += got;
  }
  return true;
}

bool ByteReader::skip(std::uint64_t count) {
  const std::uint64_t have = end_ - begin_;
  if (count <= have) {
    begin_ += static_cast<std::size_t>(count);
    return true;
  }
  if (count > remaining()) return false;
  buffer_end_offset_ += count - have;
  begin_ = end_ = 0;
  return true;
}

// --- LineReader --------------------------------------------------------------

LineReader::LineReader(const InputFile& file, std::uint64_t offset, std::uint64_t first_line,
                       std::size_t max_line_bytes)
    : file_(file),
      max_line_bytes_(max_line_bytes),
      buffer_(std::min(kLineChunkBytes, max_line_bytes + 1)),
      buffer_end_offset_(offset),
      line_number_(first_line - 1) {}

bool LineReader::next(std::string_view& line) {
  std::size_t searched = begin_;  // bytes before this have no '\n'
  while (true) {
    const auto* newline = static_cast<const char*>(std::memchr(buffer_.data() + searched, '\n', end_ - searched));
    if (newline != nullptr || (at_end_ && end_ > begin_)) {
      const std::size_t line_end = newline != nullptr ? static_cast<std::size_t>(newline - buffer_.data()) : end_;
      if (line_end - begin_ > max_line_bytes_) break;  // reported below
      line = std::string_view(buffer_.data() + begin_, line_end - begin_);
      while (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ = newline != nullptr ? line_end + 1 : line_end;
      ++line_number_;
      return true;
    }
    if (at_end_) return false;
    searched = end_;
    if (end_ - begin_ > max_line_bytes_) break;
    // Keep the unfinished line, make room, read more.
    if (begin_ > 0) {
      std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
      end_ -= begin_;
      searched -= begin_;
      begin_ = 0;
    }
    if (end_ == buffer_.size()) buffer_.resize(std::min(buffer_.size() * 2, max_line_bytes_ + 2));
    const std::size_t got = file_.read_at(buffer_end_offset_, buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) at_end_ = true;
    end_ += got;
    buffer_end_offset_ += got;
  }
  throw FormatError::at_line(file_.name(), line_number_ + 1,
                             "line longer than " + std::to_string(max_line_bytes_) +
                                 " bytes; is this really a text file? It starts " +
                                 quote({buffer_.data() + begin_, std::min<std::size_t>(end_ - begin_, kLineStartShown)}));
}

bool LineReader::next_non_blank(std::string_view& line) {
  while (next(line)) {
    if (!is_blank(line)) return true;
  }
  return false;
}

}  // namespace umbra::detail
