// Decompression of bag chunks: see bag_chunk.hpp. Both decompressors are
// driven by one loop (inflate) through a small adapter that reports, per
// call, the bytes taken and given and whether the stream has ended.
#include "bag_chunk.hpp"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <memory>

#include "core/memory_budget.hpp"

namespace umbra::ros_io::bag_detail {
namespace {

/// What one call of a decompressor did.
struct Step {
  std::size_t taken = 0;  ///< input bytes consumed
  std::size_t given = 0;  ///< output bytes written
  bool ended = false;     ///< the compressed stream is complete
};

class Bz2Decoder {
 public:
  explicit Bz2Decoder(const RecordSite& site) : site_(site) {
    if (BZ2_bzDecompressInit(&stream_, 0, 0) != BZ_OK) throw site_.error("libbz2 could not start a decompressor");
  }
  Bz2Decoder(const Bz2Decoder&) = delete;
  Bz2Decoder& operator=(const Bz2Decoder&) = delete;
  ~Bz2Decoder() { BZ2_bzDecompressEnd(&stream_); }

  Step step(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out, std::size_t out_size) {
    // Pieces below 4 GiB each: libbz2 counts in unsigned int.
    const auto in_piece = static_cast<unsigned>(std::min<std::size_t>(in_size, 1u << 30));
    const auto out_piece = static_cast<unsigned>(std::min<std::size_t>(out_size, 1u << 30));
    stream_.next_in = const_cast<char*>(reinterpret_cast<const char*>(in));  // libbz2 does not write the input
    stream_.avail_in = in_piece;
    stream_.next_out = reinterpret_cast<char*>(out);
    stream_.avail_out = out_piece;
    const int result = BZ2_bzDecompress(&stream_);
    if (result != BZ_OK && result != BZ_STREAM_END) {
      throw site_.error("the bz2 chunk's data is corrupt (libbz2 error " + std::to_string(result) +
                        (result == BZ_DATA_ERROR_MAGIC ? ": not bz2 data" : result == BZ_DATA_ERROR ? ": bad data" : "") +
                        ")");
    }
    return {in_piece - stream_.avail_in, out_piece - stream_.avail_out, result == BZ_STREAM_END};
  }

 private:
  RecordSite site_;
  bz_stream stream_{};
};

class Lz4Decoder {
 public:
  explicit Lz4Decoder(const RecordSite& site) : site_(site) {
    if (LZ4F_isError(LZ4F_createDecompressionContext(&context_, LZ4F_VERSION))) {
      throw site_.error("liblz4 could not start a decompressor");
    }
  }
  Lz4Decoder(const Lz4Decoder&) = delete;
  Lz4Decoder& operator=(const Lz4Decoder&) = delete;
  ~Lz4Decoder() { LZ4F_freeDecompressionContext(context_); }

  Step step(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out, std::size_t out_size) {
    std::size_t taken = in_size;
    std::size_t given = out_size;
    const std::size_t hint = LZ4F_decompress(context_, out, &given, in, &taken, nullptr);
    if (LZ4F_isError(hint)) {
      throw site_.error(std::string("the lz4 chunk's data is corrupt (liblz4: ") + LZ4F_getErrorName(hint) + ")");
    }
    return {taken, given, hint == 0};
  }

 private:
  RecordSite site_;
  LZ4F_dctx* context_ = nullptr;
};

/// Runs `decoder` over `in` until its stream ends; `out` ends up exactly `size` bytes.
template <typename Decoder>
void inflate(Decoder& decoder, std::span<const std::uint8_t> in, std::uint32_t size, std::vector<std::uint8_t>& out,
             const RecordSite& site, const std::string& compression) {
  // Start near what the data can plausibly hold and double as output comes (never past `size`).
  const std::size_t first = std::min<std::size_t>(size, std::max<std::size_t>(std::size_t{64} << 10, 4 * in.size()));
  out.resize(first);
  std::size_t taken = 0;
  std::size_t given = 0;
  for (;;) {
    if (given == out.size()) {
      if (out.size() < size) {
        out.resize(std::min<std::size_t>(size, 2 * out.size()));
      } else {
        // Full at the declared size: the stream must end here without another byte.
        std::uint8_t extra = 0;
        const Step step = decoder.step(in.data() + taken, in.size() - taken, &extra, 1);
        taken += step.taken;
        if (step.given > 0) {
          throw site.error("the " + compression + " chunk decompresses to more than the " + std::to_string(size) +
                           " bytes its header declares");
        }
        if (step.ended) break;
        if (step.taken == 0) {
          throw site.error("the " + compression + " chunk's data ends before its compressed stream does");
        }
        continue;
      }
    }
    const Step step = decoder.step(in.data() + taken, in.size() - taken, out.data() + given, out.size() - given);
    taken += step.taken;
    given += step.given;
    if (step.ended) break;
    if (step.taken == 0 && step.given == 0) {
      throw site.error("the " + compression + " chunk's data ends before its compressed stream does (" +
                       std::to_string(given) + " of " + std::to_string(size) + " bytes decompressed)");
    }
  }
  if (given != size) {
    throw site.error("the " + compression + " chunk decompresses to " + std::to_string(given) + " bytes, but its header "
                     "declares " + std::to_string(size));
  }
  if (taken != in.size()) {
    throw site.error(std::to_string(in.size() - taken) + " bytes follow the end of the " + compression +
                     " chunk's compressed stream");
  }
}

}  // namespace

void decompress_chunk(const std::string& compression, std::span<const std::uint8_t> compressed, std::uint32_t size,
                      std::vector<std::uint8_t>& out, const RecordSite& site) {
  const std::string& file = site.file != nullptr ? *site.file : std::string();
  const std::string what = "decompressing the " + compression + " chunk at byte " + std::to_string(site.byte);
  detail::require_memory(file, what, std::uint64_t{size} + compressed.size());
  detail::naming_bad_alloc(file, what, size, [&] {
    if (compression == "bz2") {
      Bz2Decoder decoder(site);
      inflate(decoder, compressed, size, out, site, compression);
    } else if (compression == "lz4") {
      Lz4Decoder decoder(site);
      inflate(decoder, compressed, size, out, site, compression);
    } else {
      throw site.error("unknown chunk compression '" + compression + "'");
    }
  });
}

}  // namespace umbra::ros_io::bag_detail
