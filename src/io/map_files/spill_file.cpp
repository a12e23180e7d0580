// Spill files (umbra/io/spill_file.hpp): pieces of .umb bytes behind a
// magic and a length, appended with one write each, read back one by one.
#include "umbra/io/spill_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "byte_input.hpp"
#include "map_file_bytes.hpp"

namespace umbra {
namespace {

constexpr std::array<char, 8> kSpillMagic = {'U', 'M', 'B', 'S', 'P', 'I', 'L', 'L'};
constexpr std::size_t kPieceHeaderBytes = 16;

std::string system_reason() { return std::strerror(errno); }

/// Closes a descriptor at the end of its scope.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

void append_spill_piece(const std::filesystem::path& path, const OccupancyMap& piece) {
  const std::vector<std::uint8_t> map_file = detail::encode_map_file(piece);
  std::vector<std::uint8_t> bytes(kPieceHeaderBytes);
  std::memcpy(bytes.data(), kSpillMagic.data(), kSpillMagic.size());
  const std::uint64_t size = map_file.size();
  for (int i = 0; i < 8; ++i) bytes[8 + i] = static_cast<std::uint8_t>(size >> (8 * i));
  bytes.insert(bytes.end(), map_file.begin(), map_file.end());

  const std::string name = path.string();
  const Descriptor file(::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644));
  if (file.get() < 0) throw std::runtime_error("cannot open spill file '" + name + "': " + system_reason());
  // The piece goes at the end as the file is now; on an error the file is
  // cut back there, so no part of the piece stays.
  const off_t end = ::lseek(file.get(), 0, SEEK_END);
  if (end < 0) throw std::runtime_error("cannot append to spill file '" + name + "': " + system_reason());
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(file.get(), bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string reason = n < 0 ? system_reason() : "nothing written";
      if (::ftruncate(file.get(), end) != 0) {
        throw std::runtime_error("cannot append to spill file '" + name + "': " + reason +
                                 "; cutting it back to " + std::to_string(end) + " bytes failed too: " +
                                 system_reason());
      }
      throw std::runtime_error("cannot append to spill file '" + name + "': " + reason + " (the file is as before)");
    }
    written += static_cast<std::size_t>(n);
  }
}

std::function<void(const OccupancyMap&)> spill_to_file(const std::filesystem::path& path) {
  return [path](const OccupancyMap& piece) { append_spill_piece(path, piece); };
}

std::size_t for_each_spill_piece(const std::filesystem::path& path, FunctionRef<void(OccupancyMap&& piece)> visit) {
  const detail::InputFile file(path, {}, "spill file");
  const std::string name = path.string();
  std::uint64_t offset = 0;
  std::size_t count = 0;
  std::vector<std::uint8_t> bytes;
  while (offset < file.size()) {
    std::array<std::uint8_t, kPieceHeaderBytes> head{};
    const std::size_t got = file.read_at(offset, head.data(), head.size());
    const std::string piece = "piece " + std::to_string(count + 1);
    if (got < head.size()) {
      throw FormatError::at_byte(name, offset, piece + ": truncated: a 16-byte piece header expected, " +
                                                   std::to_string(got) + " bytes left");
    }
    if (std::memcmp(head.data(), kSpillMagic.data(), kSpillMagic.size()) != 0) {
      throw FormatError::at_byte(name, offset, piece + ": magic \"UMBSPILL\" expected (not a spill file, or corrupt)");
    }
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) size |= std::uint64_t{head[8 + i]} << (8 * i);
    const std::uint64_t left = file.size() - offset - kPieceHeaderBytes;
    if (size > left) {
      throw FormatError::at_byte(name, offset + 8, piece + ": declares " + std::to_string(size) + " bytes, only " +
                                                       std::to_string(left) +
                                                       " follow (truncated: was the run cut off while spilling?)");
    }
    bytes.resize(static_cast<std::size_t>(size));
    const std::uint64_t map_at = offset + kPieceHeaderBytes;
    if (file.read_at(map_at, bytes.data(), bytes.size()) != bytes.size()) {
      throw FormatError::at_byte(name, map_at, piece + ": truncated while reading (is the file being written?)");
    }
    visit(detail::decode_map_file(name + " (" + piece + ", its map file starting at byte " + std::to_string(map_at) + ")",
                                  bytes));
    ++count;
    offset = map_at + size;
  }
  return count;
}

OccupancyMap load_spill(const std::filesystem::path& path) {
  std::optional<OccupancyMap> whole;
  std::size_t index = 0;
  const std::size_t pieces = for_each_spill_piece(path, [&](OccupancyMap&& piece) {
    ++index;
    if (!whole) {
      whole.emplace(std::move(piece));
      return;
    }
    try {
      whole->merge(piece);
    } catch (const std::exception& error) {
      throw std::invalid_argument(path.string() + ": piece " + std::to_string(index) +
                                  " cannot be merged with the first: " + error.what());
    }
  });
  if (pieces == 0) throw FormatError::at_byte(path.string(), 0, "the spill file holds no pieces");
  return std::move(*whole);
}

}  // namespace umbra
