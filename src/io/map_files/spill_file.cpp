// Spill files (umbra/io/spill_file.hpp): pieces of .umb bytes behind a
// magic and a length, appended with one write each and synced to disk
// before the append returns, read back one by one.
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

/// Cuts `file` back to `end` bytes after a failed append and throws `what`.
/// When the cut fails too, the piece may be whole on disk while the caller
/// keeps its voxels and spills them again: its magic is overwritten, so that
/// a reader stops there with an error instead of adding the voxels twice.
[[noreturn]] void cut_back_and_throw(int file, off_t end, const std::string& name, const std::string& what) {
  if (::ftruncate(file, end) == 0) {
    throw std::runtime_error("cannot append to spill file '" + name + "': " + what +
                             (end == 0 ? " (the new file is left empty)" : " (the file is as before)"));
  }
  const std::string cut_reason = system_reason();
  const std::array<char, 8> spoiled{};
  const bool marked = ::pwrite(file, spoiled.data(), spoiled.size(), end) == static_cast<ssize_t>(spoiled.size());
  throw std::runtime_error("cannot append to spill file '" + name + "': " + what + "; cutting it back to " +
                           std::to_string(end) + " bytes failed too (" + cut_reason + "): " +
                           (marked ? "the piece's magic at byte " + std::to_string(end) +
                                         " was zeroed, so readers stop there; cut the file to " +
                                         std::to_string(end) + " bytes"
                                   : "its bytes from " + std::to_string(end) + " on may hold the piece: cut the file to " +
                                         std::to_string(end) + " bytes before reading it"));
}

/// Syncs the folder holding `path`, so that a new file's name survives a
/// crash too. A folder that cannot be opened for reading (no read
/// permission) or synced (EINVAL, EROFS: some network and FUSE file
/// systems) is not an error: the piece itself is synced, and refusing would
/// make spilling impossible there. Other errors (EIO) are.
bool sync_folder_of(const std::filesystem::path& path) {
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  const Descriptor directory(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (directory.get() < 0) return true;
  return ::fsync(directory.get()) == 0 || errno == EINVAL || errno == EROFS;
}

/// What a reader of a file whose last piece is cut short can do: the whole
/// pieces before it stay readable once the file is cut there.
std::string keep_the_whole_pieces(std::uint64_t offset, std::size_t whole) {
  return "; the " + std::to_string(whole) + " whole piece(s) before it end at byte " + std::to_string(offset) +
         ": cut the file to " + std::to_string(offset) + " bytes to keep them";
}

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
    if (n <= 0) cut_back_and_throw(file.get(), end, name, n < 0 ? system_reason() : "nothing written");
    written += static_cast<std::size_t>(n);
  }
  // On disk before the append returns: the window forgets the piece's
  // voxels right after, so a piece lost in a crash would be lost for good.
  // A crash during the write or the sync can leave part of this piece at
  // the end (never a damaged earlier one: pieces are only appended); the
  // reader names where the whole pieces end. One sync per move of the box.
  if (::fdatasync(file.get()) != 0) cut_back_and_throw(file.get(), end, name, "sync failed: " + system_reason());
  if (end == 0 && !sync_folder_of(path)) {
    cut_back_and_throw(file.get(), end, name, "syncing its folder failed: " + system_reason());
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
                                                   std::to_string(got) + " bytes left" +
                                                   keep_the_whole_pieces(offset, count));
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
                                                       " follow (truncated: was the run cut off while spilling?)" +
                                                       keep_the_whole_pieces(offset, count));
    }
    bytes.resize(static_cast<std::size_t>(size));
    const std::uint64_t map_at = offset + kPieceHeaderBytes;
    if (file.read_at(map_at, bytes.data(), bytes.size()) != bytes.size()) {
      throw FormatError::at_byte(name, map_at, piece + ": truncated while reading (is the file being written?)" +
                                                   keep_the_whole_pieces(offset, count));
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
