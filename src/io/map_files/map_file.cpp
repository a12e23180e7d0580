// The native map file (.umb): encoder, decoder and validator of format version 1.
//
// docs/map-format.md is the specification; this file follows it section by
// section: header fields (written and read byte by byte, little-endian),
// the two node streams (child masks, log-odds) produced and consumed in one
// depth-first walk of the tree, each streamed through its own zstd frame in
// 128 KiB chunks, and the two CRC-32s. Cost model: one pass over the tree on
// save and on load (plus refresh_all() to recompute the inner nodes), no
// per-node allocation, virtual call or system call; memory besides the map
// is the compressed file and two chunk buffers (with MapSaveOptions::threads
// above 1, zstd's own threads compress the values and color streams in
// 1 MiB jobs while the tree is walked: a few MiB more). Saving goes through
// write_file_atomically (temporary file, fsync, rename).
#include "umbra/io/map_file.hpp"

#include "umbra/io/file_saving.hpp"
#include "byte_input.hpp"
#include "message_text.hpp"
#include "core/memory_budget.hpp"
#include "map/map_access.hpp"

#include <zlib.h>
#include <zstd.h>
#include <zstd_errors.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>
#include <vector>

namespace umbra {
namespace {


// --- format constants (docs/map-format.md, "Header") -------------------------

constexpr std::array<std::uint8_t, 8> kMagic = {'U', 'M', 'B', 'R', 'A', 'M', 'A', 'P'};
constexpr std::size_t kHeaderBytes = 124;
constexpr std::size_t kChecksumBytes = 4;
/// Flag bit 0: saved with auto-pruning off; equal childless siblings may be present.
constexpr std::uint32_t kFlagUnpruned = 1u;
/// Flag bit 1: a colored map; a color frame follows the values frame.
constexpr std::uint32_t kFlagColor = 2u;
constexpr std::uint32_t kKnownFlags = kFlagUnpruned | kFlagColor;

/// Byte offsets of the header fields.
namespace at {
constexpr std::size_t magic = 0;
constexpr std::size_t version = 8;
constexpr std::size_t flags = 12;
constexpr std::size_t resolution = 16;
constexpr std::size_t depth_levels = 24;
constexpr std::size_t reserved = 28;
constexpr std::size_t thresholds = 32;  // occupied f64, free f64
constexpr std::size_t sensor = 48;      // p_hit, p_miss, clamp_min, clamp_max: f64 each
constexpr std::size_t inner_nodes = 80;
constexpr std::size_t childless_nodes = 88;
constexpr std::size_t structure_bytes = 96;
constexpr std::size_t structure_compressed = 104;
constexpr std::size_t values_compressed = 112;
constexpr std::size_t header_crc = 120;
}  // namespace at

/// No zstd block that produces output is shorter than 4 bytes (an RLE block:
/// 3-byte header + 1 byte) and none produces more than 128 KiB, so a frame
/// never expands more than 131072 / 4 times. A header declaring more is a lie.
constexpr std::uint64_t kMaxZstdExpansion = 32768;
constexpr int kZstdLevel = 3;            // level 9 is ~25% smaller on maps but ~4x slower to write
constexpr int kWriterWindowLog = 21;     // 2 MiB, level 3's own default for large inputs
constexpr int kReaderMaxWindowLog = 23;  // the spec's limit: a hostile frame cannot ask for more
constexpr std::size_t kChunkBytes = 128 * 1024;
/// With helper threads a stream is cut into jobs compressed apart: 1 MiB so
/// that the first job starts early and the last one, compressed after the
/// walk, is short. On the 3DTK map at 5 cm with 2 threads: 29 ms (65 ms with
/// zstd's default 8 MiB jobs, 41 ms with 512 KiB ones), file 19 bytes larger.
constexpr int kJobBytes = 1 << 20;

// --- little-endian fields ---------------------------------------------------

void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_u64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_f64(std::uint8_t* p, double v) { put_u64(p, std::bit_cast<std::uint64_t>(v)); }

std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
double get_f64(const std::uint8_t* p) { return std::bit_cast<double>(get_u64(p)); }

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(crc32_z(0, bytes.data(), bytes.size()));
}

// --- messages ---------------------------------------------------------------

std::string hex32(std::uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08x", v);
  return text;
}

std::string number(float v) {
  std::ostringstream out;
  out.precision(9);  // enough to tell any two floats apart
  out << v;
  return out.str();
}

using detail::float_text;
using detail::quote_bytes;

/// "node at depth D, key (x, y, z)", depth as the tree counts it (0: the leaves).
std::string node_text(int depth, std::uint64_t code) { return detail::node_text("depth", depth, code); }

// --- header -------------------------------------------------------------------

/// Largest number of inner nodes (nodes with children) at depths >= `lowest`
/// in a full tree of `depth_levels` levels: sum of 8^(D-d) for d in [lowest, D].
std::uint64_t max_inner_nodes(int depth_levels, int lowest) {
  std::uint64_t total = 0;
  std::uint64_t at_depth = 1;  // nodes at depth D, D-1, ...
  for (int d = depth_levels; d >= lowest; --d) {
    total += at_depth;
    at_depth *= 8;  // 8^21 = 2^63 is the largest value reached: no overflow
  }
  return total;
}

std::array<std::uint8_t, kHeaderBytes> encode_header(const MapFileInfo& info) {
  std::array<std::uint8_t, kHeaderBytes> h{};
  std::copy(kMagic.begin(), kMagic.end(), h.begin());
  put_u32(&h[at::version], info.version);
  put_u32(&h[at::flags], (info.auto_prune ? 0u : kFlagUnpruned) | (info.config.color ? kFlagColor : 0u));
  put_f64(&h[at::resolution], info.config.resolution);
  put_u32(&h[at::depth_levels], static_cast<std::uint32_t>(info.config.depth_levels));
  put_u32(&h[at::reserved], 0);
  put_f64(&h[at::thresholds], info.config.thresholds.occupied);
  put_f64(&h[at::thresholds + 8], info.config.thresholds.free);
  put_f64(&h[at::sensor], info.config.sensor.p_hit);
  put_f64(&h[at::sensor + 8], info.config.sensor.p_miss);
  put_f64(&h[at::sensor + 16], info.config.sensor.clamp_min);
  put_f64(&h[at::sensor + 24], info.config.sensor.clamp_max);
  put_u64(&h[at::inner_nodes], info.inner_nodes);
  put_u64(&h[at::childless_nodes], info.childless_nodes);
  put_u64(&h[at::structure_bytes], info.structure_bytes);
  put_u64(&h[at::structure_compressed], info.structure_compressed_bytes);
  put_u64(&h[at::values_compressed], info.values_compressed_bytes);
  put_u32(&h[at::header_crc], crc32_of(std::span(h).first(at::header_crc)));
  return h;
}

/// Validates the header in `head` (the file's first min(file_size, 124)
/// bytes) against the file size, in the order of docs/map-format.md, and
/// returns what it says.
MapFileInfo decode_header(const std::string& file, std::span<const std::uint8_t> head, std::uint64_t file_size) {
  auto fail = [&](std::size_t offset, const std::string& message) -> FormatError {
    return FormatError::at_byte(file, offset, message);
  };
  // Magic and version first: they are the part of the layout every version keeps.
  const std::size_t magic_seen = std::min(head.size(), kMagic.size());
  if (!std::equal(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(magic_seen), kMagic.begin())) {
    throw fail(at::magic, "bad magic: expected 'UMBRAMAP', found " + quote_bytes({reinterpret_cast<const char*>(head.data()), magic_seen}) +
                              " (not an umbra map file)");
  }
  if (head.size() >= at::version + 4) {
    const std::uint32_t version = get_u32(&head[at::version]);
    if (version != kMapFileVersion) {
      throw fail(at::version, "unsupported format version " + std::to_string(version) +
                                  " (this build reads version " + std::to_string(kMapFileVersion) + ")");
    }
  }
  if (head.size() < kHeaderBytes) {
    throw fail(head.size(), "truncated: header needs " + std::to_string(kHeaderBytes) + " bytes, file has " +
                                std::to_string(file_size));
  }
  const std::uint32_t stored_crc = get_u32(&head[at::header_crc]);
  const std::uint32_t computed_crc = crc32_of(head.first(at::header_crc));
  if (stored_crc != computed_crc) {
    throw fail(at::header_crc, "header checksum mismatch: stored " + hex32(stored_crc) + ", computed " +
                                   hex32(computed_crc) + " (the header is corrupt)");
  }

  MapFileInfo info;
  info.version = kMapFileVersion;
  const std::uint32_t flags = get_u32(&head[at::flags]);
  if ((flags & ~kKnownFlags) != 0) {
    throw fail(at::flags, "unsupported flags " + hex32(flags) + " (this build knows " + hex32(kKnownFlags) + ")");
  }
  info.auto_prune = (flags & kFlagUnpruned) == 0;
  info.config.color = (flags & kFlagColor) != 0;

  MapConfig& config = info.config;
  config.resolution = get_f64(&head[at::resolution]);
  try {
    Grid::validate_resolution(config.resolution);
  } catch (const std::invalid_argument& e) {
    throw fail(at::resolution, e.what());
  }
  const std::uint32_t depth_levels = get_u32(&head[at::depth_levels]);
  if (depth_levels < 1 || depth_levels > static_cast<std::uint32_t>(kMaxDepthLevels)) {
    throw fail(at::depth_levels, "depth levels must be in [1, " + std::to_string(kMaxDepthLevels) + "], found " +
                                     std::to_string(depth_levels));
  }
  config.depth_levels = static_cast<int>(depth_levels);
  if (const std::uint32_t reserved = get_u32(&head[at::reserved]); reserved != 0) {
    throw fail(at::reserved, "reserved field must be 0, found " + hex32(reserved));
  }
  config.thresholds.occupied = get_f64(&head[at::thresholds]);
  config.thresholds.free = get_f64(&head[at::thresholds + 8]);
  try {
    config.thresholds.validate();
  } catch (const std::invalid_argument& e) {
    throw fail(at::thresholds, std::string("invalid thresholds: ") + e.what());
  }
  config.sensor.p_hit = get_f64(&head[at::sensor]);
  config.sensor.p_miss = get_f64(&head[at::sensor + 8]);
  config.sensor.clamp_min = get_f64(&head[at::sensor + 16]);
  config.sensor.clamp_max = get_f64(&head[at::sensor + 24]);
  try {
    config.sensor.validate();
  } catch (const std::invalid_argument& e) {
    throw fail(at::sensor, std::string("invalid sensor model: ") + e.what());
  }

  // Node counts: a tree with I inner nodes has 8I + 1 nodes, 7I + 1 of them childless.
  const int depth = config.depth_levels;
  info.inner_nodes = get_u64(&head[at::inner_nodes]);
  info.childless_nodes = get_u64(&head[at::childless_nodes]);
  info.structure_bytes = get_u64(&head[at::structure_bytes]);
  info.structure_compressed_bytes = get_u64(&head[at::structure_compressed]);
  info.values_compressed_bytes = get_u64(&head[at::values_compressed]);
  const std::uint64_t max_inner = max_inner_nodes(depth, 1);
  if (info.inner_nodes > max_inner) {
    throw fail(at::inner_nodes, "inner node count " + std::to_string(info.inner_nodes) + " is more than a tree of " +
                                    std::to_string(depth) + " depth levels can hold (" + std::to_string(max_inner) +
                                    ")");
  }
  // max_inner <= 8^21 / 7, so 7 * inner_nodes + 1 cannot overflow.
  if (info.childless_nodes != 7 * info.inner_nodes + 1) {
    throw fail(at::childless_nodes, "childless node count " + std::to_string(info.childless_nodes) +
                                        " does not match the inner node count: a tree with " +
                                        std::to_string(info.inner_nodes) + " inner nodes has " +
                                        std::to_string(7 * info.inner_nodes + 1));
  }
  // One mask byte for the root plus one per inner node at depth >= 2; each of
  // those has at most 8 inner children at depth 1, so S - 1 <= I <= 9 (S - 1)
  // (and I <= 1, S = 1 when the root is at depth 1).
  const std::uint64_t s = info.structure_bytes;
  const std::uint64_t i = info.inner_nodes;
  const bool structure_fits =
      s >= 1 && (depth == 1 ? (s == 1 && i <= 1) : (s - 1 <= i && (s - 1 <= max_inner_nodes(depth, 2)) &&
                                                    i <= 9 * (s - 1)));
  if (!structure_fits) {
    throw fail(at::structure_bytes,
               "structure stream size " + std::to_string(s) + " is impossible for " + std::to_string(i) +
                   " inner nodes in a tree of " + std::to_string(depth) +
                   " depth levels (it must be 1 + the number of inner nodes at depth >= 2)");
  }
  // Compressed sizes: each below 2^56 so that the sums below cannot overflow.
  for (const auto& [offset, value] : {std::pair{at::structure_compressed, info.structure_compressed_bytes},
                                      std::pair{at::values_compressed, info.values_compressed_bytes}}) {
    if (value >= (std::uint64_t{1} << 56)) {
      throw fail(offset, "compressed stream size " + std::to_string(value) + " is impossibly large (file has " +
                             std::to_string(file_size) + " bytes)");
    }
  }
  if (s > kMaxZstdExpansion * info.structure_compressed_bytes) {
    throw fail(at::structure_bytes, "structure stream declares " + std::to_string(s) + " bytes, but its " +
                                        std::to_string(info.structure_compressed_bytes) +
                                        " compressed bytes can expand to at most " +
                                        std::to_string(kMaxZstdExpansion * info.structure_compressed_bytes));
  }
  // childless_nodes <= 7 * 8^21 / 7 + 1 < 2^63, and the bound below < 2^71: compare by division.
  if (info.childless_nodes > kMaxZstdExpansion * info.values_compressed_bytes / 4) {
    throw fail(at::childless_nodes, "values stream needs " + std::to_string(info.childless_nodes) +
                                        " x 4 bytes, but its " + std::to_string(info.values_compressed_bytes) +
                                        " compressed bytes can expand to at most " +
                                        std::to_string(kMaxZstdExpansion * info.values_compressed_bytes));
  }
  info.file_bytes = kHeaderBytes + info.structure_compressed_bytes + info.values_compressed_bytes + kChecksumBytes;
  if (info.config.color && file_size > info.file_bytes) {
    // The color frame is what lies between the values frame and the checksum.
    info.colors_compressed_bytes = file_size - info.file_bytes;
    if (info.childless_nodes > kMaxZstdExpansion * info.colors_compressed_bytes / 4) {
      throw fail(at::childless_nodes, "color stream needs " + std::to_string(info.childless_nodes) +
                                          " x 4 bytes, but its " + std::to_string(info.colors_compressed_bytes) +
                                          " compressed bytes can expand to at most " +
                                          std::to_string(kMaxZstdExpansion * info.colors_compressed_bytes));
    }
    info.file_bytes = file_size;
  } else if (info.config.color) {
    throw fail(file_size, "truncated: flag bit 1 says a color frame follows the values frame, but the file ends "
                          "with the values frame (" + std::to_string(file_size) + " bytes)");
  }
  if (file_size < info.file_bytes) {
    throw fail(file_size, "truncated: header declares " + std::to_string(info.file_bytes) + " bytes, file has " +
                              std::to_string(file_size));
  }
  if (file_size > info.file_bytes) {
    throw fail(info.file_bytes, std::to_string(file_size - info.file_bytes) +
                                    " trailing bytes: header declares " + std::to_string(info.file_bytes) +
                                    " bytes, file has " + std::to_string(file_size));
  }
  return info;
}


// --- streams ----------------------------------------------------------------------

/// One zstd frame written in chunks: bytes are gathered in a 128 KiB buffer
/// and compressed whenever it is full, so no whole raw stream is ever held.
class FrameWriter {
 public:
  /// `workers`: zstd threads compressing while the caller goes on filling
  /// chunks (0: the caller compresses each full chunk itself).
  FrameWriter(std::vector<std::uint8_t>& out, int workers)
      : out_(out), ctx_(ZSTD_createCCtx()), chunk_(kChunkBytes) {
    if (!ctx_) throw std::bad_alloc();
    check(ZSTD_CCtx_setParameter(ctx_.get(), ZSTD_c_compressionLevel, kZstdLevel));
    check(ZSTD_CCtx_setParameter(ctx_.get(), ZSTD_c_windowLog, kWriterWindowLog));
    // The file's CRC-32 covers the frame; zstd's own checksum would be redundant.
    check(ZSTD_CCtx_setParameter(ctx_.get(), ZSTD_c_checksumFlag, 0));
    // An error here means a libzstd built without threads: it then compresses on this thread.
    if (workers > 0 && !ZSTD_isError(ZSTD_CCtx_setParameter(ctx_.get(), ZSTD_c_nbWorkers, workers))) {
      check(ZSTD_CCtx_setParameter(ctx_.get(), ZSTD_c_jobSize, kJobBytes));
    }
  }

  void put_byte(std::uint8_t b) {
    if (used_ == chunk_.size()) compress(ZSTD_e_continue);
    chunk_[used_++] = b;
    ++raw_bytes_;
  }
  void put_float(float v) {
    if (chunk_.size() - used_ < 4) compress(ZSTD_e_continue);
    put_u32(&chunk_[used_], std::bit_cast<std::uint32_t>(v));
    used_ += 4;
    raw_bytes_ += 4;
  }
  /// Ends the frame.
  void finish() { compress(ZSTD_e_end); }
  [[nodiscard]] std::uint64_t raw_bytes() const { return raw_bytes_; }

 private:
  struct Free {
    void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
  };
  static std::size_t check(std::size_t result) {
    if (ZSTD_isError(result)) throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(result));
    return result;
  }

  void compress(ZSTD_EndDirective mode) {
    ZSTD_inBuffer in{chunk_.data(), used_, 0};
    for (;;) {
      const std::size_t old_size = out_.size();
      out_.resize(old_size + ZSTD_CStreamOutSize());
      ZSTD_outBuffer out{out_.data() + old_size, out_.size() - old_size, 0};
      const std::size_t left = check(ZSTD_compressStream2(ctx_.get(), &out, &in, mode));
      out_.resize(old_size + out.pos);
      // e_continue is done when the input is used; e_end when nothing is left to flush.
      if (mode == ZSTD_e_continue ? in.pos == in.size : left == 0) break;
    }
    used_ = 0;
  }

  std::vector<std::uint8_t>& out_;
  std::unique_ptr<ZSTD_CCtx, Free> ctx_;
  std::vector<std::uint8_t> chunk_;
  std::size_t used_ = 0;
  std::uint64_t raw_bytes_ = 0;
};

/// One zstd frame read in chunks. It never produces more than one byte past
/// the size the header declares (enough to notice a longer stream), so the
/// output the file really holds, not its claim, bounds what is allocated.
class FrameReader {
 public:
  FrameReader(const std::string& file, std::uint64_t offset, std::string name, std::span<const std::uint8_t> frame,
              std::uint64_t declared)
      : file_(file),
        offset_(offset),
        name_(std::move(name)),
        ctx_(ZSTD_createDCtx()),
        in_{frame.data(), frame.size(), 0},
        declared_(declared),
        chunk_(static_cast<std::size_t>(std::min<std::uint64_t>(kChunkBytes, declared + 1))) {
    if (!ctx_) throw std::bad_alloc();
    // Bounds the window a frame header can make zstd allocate.
    const std::size_t result = ZSTD_DCtx_setParameter(ctx_.get(), ZSTD_d_windowLogMax, kReaderMaxWindowLog);
    if (ZSTD_isError(result)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(result));
  }

  /// Next byte; false when the stream has no more.
  bool read_byte(std::uint8_t& b) {
    if (pos_ == end_ && !refill()) return false;
    b = chunk_[pos_++];
    return true;
  }
  /// Next `size` bytes; false when the stream ends first.
  bool read(std::uint8_t* out, std::size_t size) {
    while (size > 0) {
      if (pos_ == end_ && !refill()) return false;
      const std::size_t n = std::min(size, end_ - pos_);
      std::memcpy(out, &chunk_[pos_], n);
      pos_ += n;
      out += n;
      size -= n;
    }
    return true;
  }
  [[nodiscard]] std::uint64_t consumed() const { return produced_ - (end_ - pos_); }
  [[nodiscard]] std::uint64_t declared() const { return declared_; }

  /// Why a read failed: the frame ended early, or the declared size is used up.
  [[nodiscard]] std::string why_ended() const {
    if (produced_ < declared_) {
      return "its zstd frame ends after " + std::to_string(produced_) + " of the " + std::to_string(declared_) +
             " bytes the header declares";
    }
    return "all " + std::to_string(declared_) + " bytes the header declares are used";
  }

  /// After the caller has consumed everything it needs: no unused output,
  /// the frame ends at its declared size, and no byte follows the frame.
  void finish(const std::string& unused_what) {
    if (consumed() < declared_) {
      fail(unused_what + ": " + std::to_string(declared_ - consumed()) + " of its " + std::to_string(declared_) +
           " declared bytes are unused");
    }
    if (refill()) fail("holds more than the " + std::to_string(declared_) + " bytes the header declares");
    if (in_.pos != in_.size) {
      fail(std::to_string(in_.size - in_.pos) + " bytes follow the end of its zstd frame");
    }
  }

  [[noreturn]] void fail(const std::string& message) const {
    throw FormatError::at_byte(file_, offset_, name_ + ": " + message);
  }

 private:
  struct Free {
    void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
  };

  bool refill() {
    if (done_) return false;
    const std::uint64_t remaining = declared_ - produced_;
    ZSTD_outBuffer out{chunk_.data(), static_cast<std::size_t>(std::min<std::uint64_t>(chunk_.size(), remaining + 1)), 0};
    while (out.pos == 0) {
      const std::size_t before = in_.pos;
      const std::size_t result = ZSTD_decompressStream(ctx_.get(), &out, &in_);
      if (ZSTD_isError(result)) {
        // Running out of memory is not a fault of the file: load_map names it as such.
        if (ZSTD_getErrorCode(result) == ZSTD_error_memory_allocation) throw std::bad_alloc();
        fail(std::string("zstd error: ") + ZSTD_getErrorName(result));
      }
      if (result == 0) {
        done_ = true;  // the frame is complete and flushed
        break;
      }
      if (out.pos == 0 && in_.pos == before) {
        fail("its zstd frame is truncated (it ends after " + std::to_string(produced_) + " bytes of output)");
      }
    }
    pos_ = 0;
    end_ = out.pos;
    produced_ += out.pos;
    if (produced_ > declared_) {
      fail("holds more than the " + std::to_string(declared_) + " bytes the header declares");
    }
    return end_ > 0;
  }

  const std::string& file_;
  std::uint64_t offset_;
  std::string name_;
  std::unique_ptr<ZSTD_DCtx, Free> ctx_;
  ZSTD_inBuffer in_;
  std::uint64_t declared_;
  std::uint64_t produced_ = 0;
  bool done_ = false;
  std::vector<std::uint8_t> chunk_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
};

// --- saving -------------------------------------------------------------------

/// Writes the two node streams of a tree in depth-first order (see the spec).
class TreeEncoder {
 public:
  /// `colors` is null for a map without color.
  TreeEncoder(const OccupancyTree& tree, LogOddsRange range, bool pruned, FrameWriter& structure, FrameWriter& values,
              FrameWriter* colors)
      : tree_(tree), range_(range), pruned_(pruned), structure_(structure), values_(values), colors_(colors) {}

  void run() {
    const NodeRef root = tree_.root();
    structure_.put_byte(tree_.has_children(root) ? 1 : 0);
    encode(root, 0);
  }
  [[nodiscard]] std::uint64_t inner_nodes() const { return inner_nodes_; }
  [[nodiscard]] std::uint64_t childless_nodes() const { return childless_nodes_; }

 private:
  void encode(NodeRef node, std::uint64_t code) {
    if (!tree_.has_children(node)) {
      put_childless(node, code);
      return;
    }
    ++inner_nodes_;
    const int child_depth = node.depth - 1;
    if (child_depth == 0) {
      for (unsigned slot = 0; slot < 8; ++slot) put_childless(tree_.child(node, slot), code | std::uint64_t{slot});
      check_not_prunable(node, code);
      return;
    }
    std::uint8_t mask = 0;
    for (unsigned slot = 0; slot < 8; ++slot) {
      if (tree_.has_children(tree_.child(node, slot))) mask = static_cast<std::uint8_t>(mask | (1u << slot));
    }
    structure_.put_byte(mask);
    for (unsigned slot = 0; slot < 8; ++slot) {
      encode(tree_.child(node, slot), code | (std::uint64_t{slot} << (3 * child_depth)));
    }
    if (mask == 0) check_not_prunable(node, code);
  }

  void put_childless(NodeRef node, std::uint64_t code) {
    const float value = tree_.log_odds(node);
    // Written so that NaN fails too. Such a file could not be loaded: refuse it now.
    if (!(value >= range_.min && value <= range_.max)) {
      throw std::invalid_argument("save_map: log-odds value " + float_text(value) + " at the " +
                                  node_text(node.depth, code) + " is outside the sensor model's clamping range [" +
                                  number(range_.min) + ", " + number(range_.max) +
                                  "] (was the sensor model changed after the value was stored?)");
    }
    values_.put_float(value);
    if (colors_ != nullptr) {
      const Rgb rgb = tree_.color(node).value_or(Rgb{});
      colors_->put_byte(rgb.r);
      colors_->put_byte(rgb.g);
      colors_->put_byte(rgb.b);
      colors_->put_byte(tree_.color_weight(node));
    }
    ++childless_nodes_;
  }

  /// A file marked pruned must not hold eight equal childless siblings; the
  /// tree's invariant guarantees it while auto-pruning is on.
  void check_not_prunable(NodeRef node, std::uint64_t code) const {
    if (!pruned_ || !tree_.all_children_same(node)) return;
    throw std::logic_error("save_map: the " + node_text(node.depth, code) +
                           " has eight equal childless children although auto-pruning is on (broken tree invariant)");
  }

  const OccupancyTree& tree_;
  LogOddsRange range_;
  bool pruned_;
  FrameWriter& structure_;
  FrameWriter& values_;
  FrameWriter* colors_;
  std::uint64_t inner_nodes_ = 0;
  std::uint64_t childless_nodes_ = 0;
};

// --- loading ------------------------------------------------------------------

/// Rebuilds a tree from the two node streams, checking every mask and value.
class TreeDecoder {
 public:
  /// `colors` is null for a map without color.
  TreeDecoder(detail::TreeBuilder& tree, const MapFileInfo& info, FrameReader& structure, FrameReader& values,
              FrameReader* colors)
      : tree_(tree),
        range_(LogOddsRange::from(info.config.sensor)),
        pruned_(info.auto_prune),
        declared_inner_(info.inner_nodes),
        structure_(structure),
        values_(values),
        colors_(colors) {}

  void run() {
    std::uint8_t root = 0;
    if (!structure_.read_byte(root)) structure_.fail("node structure ends early: no root byte; " + structure_.why_ended());
    if (root > 1) {
      structure_.fail("node structure: the root byte must be 0 (childless root) or 1 (root has children), found " +
                      hex32(root));
    }
    decode(tree_.root(), 0, root == 1);
    if (inner_seen_ != declared_inner_) {
      structure_.fail("node structure describes " + std::to_string(inner_seen_) +
                      " inner nodes, the header declares " + std::to_string(declared_inner_));
    }
    structure_.finish("node structure has unused bytes after the tree ends");
    values_.finish("unused values after the tree ends");
    if (colors_ != nullptr) colors_->finish("unused colors after the tree ends");
  }

 private:
  void decode(NodeRef node, std::uint64_t code, bool has_children) {
    if (!has_children) {
      tree_.set_childless_value(node, next_value(node.depth, code));
      read_color(node, code);
      return;
    }
    if (++inner_seen_ > declared_inner_) {
      structure_.fail("node structure describes more than the " + std::to_string(declared_inner_) +
                      " inner nodes the header declares (at the " + node_text(node.depth, code) + ")");
    }
    tree_.subdivide(node);
    const int child_depth = node.depth - 1;
    if (child_depth == 0) {
      decode_leaf_group(node, code);
      return;
    }
    std::uint8_t mask = 0;
    if (!structure_.read_byte(mask)) {
      structure_.fail("node structure ends early: the " + node_text(node.depth, code) +
                      " has children and needs a child mask, but " + structure_.why_ended());
    }
    for (unsigned slot = 0; slot < 8; ++slot) {
      decode(tree_.child(node, slot), code | (std::uint64_t{slot} << (3 * child_depth)), (mask >> slot & 1u) != 0);
    }
    if (mask == 0 && pruned_) check_not_prunable(node, code);
  }

  /// A file marked pruned must not hold eight childless children that are
  /// equal (in value, and in color when it has color).
  void check_not_prunable(NodeRef node, std::uint64_t code) const {
    const NodeRef first = tree_.child(node, 0);
    for (unsigned slot = 1; slot < 8; ++slot) {
      const NodeRef other = tree_.child(node, slot);
      if (tree_.log_odds(other) != tree_.log_odds(first) || tree_.color(other) != tree_.color(first) ||
          tree_.color_weight(other) != tree_.color_weight(first)) {
        return;
      }
    }
    fail_prunable(node, code, tree_.log_odds(first));
  }

  void read_color(NodeRef node, std::uint64_t code) {
    if (colors_ == nullptr) return;
    std::array<std::uint8_t, 4> bytes;
    if (!colors_->read(bytes.data(), bytes.size())) {
      colors_->fail("ends early at the " + node_text(node.depth, code) + ": " + colors_->why_ended());
    }
    const Rgb rgb{bytes[0], bytes[1], bytes[2]};
    const std::uint8_t weight = bytes[3];
    if (weight == 0 && rgb != Rgb{}) {
      colors_->fail("the " + node_text(node.depth, code) + " has weight 0 (no color) but color (" +
                    std::to_string(rgb.r) + ", " + std::to_string(rgb.g) + ", " + std::to_string(rgb.b) +
                    "); an uncolored node is stored as 0 0 0 0");
    }
    tree_.set_childless_color(node, rgb, weight);
  }

  void decode_leaf_group(NodeRef node, std::uint64_t code) {
    std::array<std::uint8_t, 32> bytes;
    if (!values_.read(bytes.data(), bytes.size())) {
      values_.fail("ends early at the children of the " + node_text(node.depth, code) + ": " + values_.why_ended());
    }
    const std::uint32_t group = tree_.child(node, 0).group;
    for (unsigned slot = 0; slot < 8; ++slot) {
      const float value = std::bit_cast<float>(get_u32(&bytes[4 * slot]));
      check_value(value, 0, code | std::uint64_t{slot});
      tree_.set_childless_value(NodeRef{group, static_cast<std::uint8_t>(slot), 0}, value);
      read_color(NodeRef{group, static_cast<std::uint8_t>(slot), 0}, code | std::uint64_t{slot});
    }
    if (pruned_) check_not_prunable(node, code);
  }

  float next_value(int depth, std::uint64_t code) {
    std::array<std::uint8_t, 4> bytes;
    if (!values_.read(bytes.data(), bytes.size())) {
      values_.fail("ends early at the " + node_text(depth, code) + ": " + values_.why_ended());
    }
    const float value = std::bit_cast<float>(get_u32(bytes.data()));
    check_value(value, depth, code);
    return value;
  }

  void check_value(float value, int depth, std::uint64_t code) const {
    if (value >= range_.min && value <= range_.max) return;  // NaN fails this
    if (!std::isfinite(value)) {
      std::string text = std::isnan(value) ? "nan" : (value > 0 ? "inf" : "-inf");
      values_.fail("log-odds value " + text + " at the " + node_text(depth, code));
    }
    values_.fail("log-odds value " + float_text(value) + " at the " + node_text(depth, code) +
                 " is outside the sensor model's clamping range [" + number(range_.min) + ", " +
                 number(range_.max) + "]");
  }

  [[noreturn]] void fail_prunable(NodeRef node, std::uint64_t code, float value) const {
    values_.fail("the " + node_text(node.depth, code) + " has eight equal childless children (value " +
                 float_text(value) + "), but the file is marked pruned (flag bit 0 clear), so they would have been "
                 "merged");
  }

  detail::TreeBuilder& tree_;
  LogOddsRange range_;
  bool pruned_;
  std::uint64_t declared_inner_;
  std::uint64_t inner_seen_ = 0;
  FrameReader& structure_;
  FrameReader& values_;
  FrameReader* colors_;
};

/// a * b, or UINT64_MAX when that overflows.
std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b) {
  return b != 0 && a > UINT64_MAX / b ? UINT64_MAX : a * b;
}

/// What load_map allocates for a file, from its validated header: the whole
/// file, and one group of eight children per inner node (an InnerGroup above
/// the finest depth, a LeafGroup at it, and a ColorGroup each with color).
/// The structure stream holds one byte per inner node at depth >= 2, plus
/// the root's, so that many inner nodes have InnerGroup children.
std::uint64_t bytes_to_load(const MapFileInfo& info) {
  const std::uint64_t above_finest = info.structure_bytes - 1;
  const std::uint64_t at_finest = info.inner_nodes - std::min(above_finest, info.inner_nodes);
  const std::uint64_t color = info.config.color ? sizeof(OccupancyTree::ColorGroup) : 0;
  const std::uint64_t upper = saturating_product(above_finest, sizeof(OccupancyTree::InnerGroup) + color);
  const std::uint64_t lower = saturating_product(at_finest, sizeof(OccupancyTree::LeafGroup) + color);
  const std::uint64_t groups = upper > UINT64_MAX - lower ? UINT64_MAX : upper + lower;
  return groups > UINT64_MAX - info.file_bytes ? UINT64_MAX : groups + info.file_bytes;
}

OccupancyMap load_body(const detail::InputFile& file, const std::filesystem::path& path, const MapFileInfo& info);
/// The map from a whole file's bytes (their size checked against the header).
OccupancyMap decode_body(const std::string& name, std::span<const std::uint8_t> bytes, const MapFileInfo& info);

}  // namespace

// --- public functions ---------------------------------------------------------

void MapSaveOptions::validate() const {
  if (threads > max_threads()) {
    throw std::invalid_argument("MapSaveOptions::threads must be at most " + std::to_string(max_threads()) +
                                " (4 per hardware thread, " + std::to_string(hardware_threads()) +
                                " here; at least 16), got " + std::to_string(threads));
  }
}

namespace {

/// A map file's bytes in its parts, as save_map writes them one after another.
struct EncodedMap {
  std::array<std::uint8_t, kHeaderBytes> header;
  std::vector<std::uint8_t> structure_frame;
  std::vector<std::uint8_t> values_frame;
  std::vector<std::uint8_t> colors_frame;
  std::array<std::uint8_t, kChecksumBytes> trailer;
};

EncodedMap encode_map(const OccupancyMap& map, const MapSaveOptions& options) {
  // Every thread but the caller's (which walks the tree) compresses the
  // values and color streams, which are nearly all the bytes; the small
  // structure stream stays on the caller's thread. At most 2 each: the walk
  // feeds ~450 MB/s and one worker compresses ~500 MB/s at level 3 (a
  // second one brought nothing measurable on the 3DTK map), so more would idle.
  // At least 1 even with one thread: zstd's multi-threaded framing gives the
  // same bytes for any number of workers, its single-threaded one other
  // bytes, and a file must not change with the thread count.
  const unsigned threads = options.threads == 0 ? hardware_threads() : options.threads;
  const int workers = std::max(1, static_cast<int>(std::min(threads, 3u)) - 1);
  // Encode first: a map that cannot be saved throws before any file exists.
  std::vector<std::uint8_t> structure_frame;
  std::vector<std::uint8_t> values_frame;
  std::vector<std::uint8_t> colors_frame;
  FrameWriter structure(structure_frame, 0);
  FrameWriter values(values_frame, workers);
  std::optional<FrameWriter> colors;
  if (map.has_color()) colors.emplace(colors_frame, workers);
  // Encoded under one read of the map, so a concurrent insert cannot tear it.
  const auto [inner_nodes, childless_nodes, config, auto_prune] =
      detail::MapAccess::read(map, [&](const OccupancyTree& tree) {
        const MapConfig map_config = map.config();
        const bool pruned = map.auto_prune();
        TreeEncoder encoder(tree, LogOddsRange::from(map_config.sensor), pruned, structure, values,
                            colors ? &*colors : nullptr);
        encoder.run();
        return std::tuple(encoder.inner_nodes(), encoder.childless_nodes(), map_config, pruned);
      });
  structure.finish();
  values.finish();
  if (colors) colors->finish();

  MapFileInfo info;
  info.config = config;
  info.auto_prune = auto_prune;
  info.inner_nodes = inner_nodes;
  info.childless_nodes = childless_nodes;
  info.structure_bytes = structure.raw_bytes();
  info.structure_compressed_bytes = structure_frame.size();
  info.values_compressed_bytes = values_frame.size();
  const auto header = encode_header(info);
  std::uint32_t crc = crc32_of(header);
  crc = static_cast<std::uint32_t>(crc32_z(crc, structure_frame.data(), structure_frame.size()));
  crc = static_cast<std::uint32_t>(crc32_z(crc, values_frame.data(), values_frame.size()));
  // (zlib returns the initial value for a null buffer, so an empty frame must be skipped.)
  if (!colors_frame.empty()) crc = static_cast<std::uint32_t>(crc32_z(crc, colors_frame.data(), colors_frame.size()));
  std::array<std::uint8_t, kChecksumBytes> trailer{};
  put_u32(trailer.data(), crc);

  return EncodedMap{header, std::move(structure_frame), std::move(values_frame), std::move(colors_frame), trailer};
}


}  // namespace

void save_map(const OccupancyMap& map, const std::filesystem::path& path, const MapSaveOptions& options) {
  options.validate();
  const EncodedMap file = encode_map(map, options);
  write_file_atomically(path, {file.header, file.structure_frame, file.values_frame, file.colors_frame, file.trailer},
                        "map");
}

namespace detail {

std::vector<std::uint8_t> encode_map_file(const OccupancyMap& map) {
  MapSaveOptions one_thread;
  one_thread.threads = 1;
  const EncodedMap file = encode_map(map, one_thread);
  std::vector<std::uint8_t> bytes;
  bytes.reserve(file.header.size() + file.structure_frame.size() + file.values_frame.size() +
                file.colors_frame.size() + file.trailer.size());
  for (const std::span<const std::uint8_t> part :
       {std::span<const std::uint8_t>(file.header), std::span<const std::uint8_t>(file.structure_frame),
        std::span<const std::uint8_t>(file.values_frame), std::span<const std::uint8_t>(file.colors_frame),
        std::span<const std::uint8_t>(file.trailer)}) {
    bytes.insert(bytes.end(), part.begin(), part.end());
  }
  return bytes;
}

OccupancyMap decode_map_file(const std::string& name, std::span<const std::uint8_t> bytes) {
  const MapFileInfo info = decode_header(name, bytes.first(std::min(bytes.size(), kHeaderBytes)), bytes.size());
  const std::uint64_t need = bytes_to_load(info);
  require_memory(name, "loading this map (" + std::to_string(info.inner_nodes) + " nodes with children)", need);
  return naming_bad_alloc(name, "loading the map", need, [&] { return decode_body(name, bytes, info); });
}

}  // namespace detail

MapFileInfo read_map_info(const std::filesystem::path& path) {
  const detail::InputFile file(path, {}, "map file");
  std::array<std::uint8_t, kHeaderBytes> head{};
  const std::size_t n = file.read_at(0, head.data(), head.size());
  return decode_header(path.string(), std::span(head).first(n), file.size());
}

OccupancyMap load_map(const std::filesystem::path& path) {
  const std::string name = path.string();
  const detail::InputFile file(path, {}, "map file");

  // 1. The header, checked against the real file size before anything is allocated.
  std::array<std::uint8_t, kHeaderBytes> head{};
  const std::size_t head_size = file.read_at(0, head.data(), head.size());
  const MapFileInfo info = decode_header(name, std::span(head).first(head_size), file.size());
  const std::uint64_t need = bytes_to_load(info);
  detail::require_memory(name, "loading this map (" + std::to_string(info.inner_nodes) + " nodes with children)", need);
  return detail::naming_bad_alloc(name, "loading the map", need, [&] { return load_body(file, path, info); });
}

namespace {

OccupancyMap load_body(const detail::InputFile& file, const std::filesystem::path& path, const MapFileInfo& info) {
  const std::string name = path.string();

  // 2. The whole file (its size is now known to be what the header declares), and its checksum.
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(info.file_bytes));
  const std::size_t got = file.read_at(0, bytes.data(), bytes.size());
  if (got != bytes.size()) {
    throw FormatError::at_byte(name, got, "truncated while reading: header declares " + std::to_string(bytes.size()) +
                                              " bytes, read " + std::to_string(got) + " (is the file being written?)");
  }
  return decode_body(name, bytes, info);
}

OccupancyMap decode_body(const std::string& name, std::span<const std::uint8_t> bytes, const MapFileInfo& info) {
  const std::size_t crc_at = bytes.size() - kChecksumBytes;
  const std::uint32_t stored = get_u32(&bytes[crc_at]);
  const std::uint32_t computed = crc32_of(bytes.first(crc_at));
  if (stored != computed) {
    throw FormatError::at_byte(name, crc_at, "checksum mismatch: stored " + hex32(stored) + ", computed " +
                                                 hex32(computed) + " (the file is corrupt)");
  }

  // 3. The tree, rebuilt from both streams in one walk; inner nodes recomputed at the end.
  OccupancyMap map(info.config);  // subdivide(), set_childless_value() and refresh_all() never prune
  const std::span<const std::uint8_t> all = bytes;
  const std::uint64_t values_at = kHeaderBytes + info.structure_compressed_bytes;
  FrameReader structure(name, kHeaderBytes, "structure stream",
                        all.subspan(kHeaderBytes, static_cast<std::size_t>(info.structure_compressed_bytes)),
                        info.structure_bytes);
  FrameReader values(name, values_at, "values stream",
                     all.subspan(static_cast<std::size_t>(values_at), static_cast<std::size_t>(info.values_compressed_bytes)),
                     4 * info.childless_nodes);
  std::optional<FrameReader> colors;
  if (info.config.color) {
    const std::uint64_t colors_at = values_at + info.values_compressed_bytes;
    colors.emplace(name, colors_at, "color stream",
                   all.subspan(static_cast<std::size_t>(colors_at), static_cast<std::size_t>(info.colors_compressed_bytes)),
                   4 * info.childless_nodes);
  }
  detail::MapAccess::build(map, [&](detail::TreeBuilder& builder) {
    TreeDecoder(builder, info, structure, values, colors ? &*colors : nullptr).run();
  });
  // Switching it off only sets the flag; a pruned file was checked to hold no equal childless siblings.
  if (!info.auto_prune) map.set_auto_prune(false);
  return map;
}

}  // namespace
}  // namespace umbra
