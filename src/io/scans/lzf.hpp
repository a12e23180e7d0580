// LZF decompression (internal): the compression PCL uses for PCD files
// written as "DATA binary_compressed".
//
// LZF is a byte-oriented LZ77 variant. The stream is a sequence of chunks,
// each starting with a control byte c. c < 32: a literal run, the next c + 1
// bytes are copied to the output. c >= 32: a back reference of length
// (c >> 5) + 2, where a length field of 7 is extended by the next byte
// (length = 7 + that byte + 2, so up to 264); the distance is
// ((c & 31) << 8) + the following byte + 1, counted back from the current
// output position (up to 8192). The copy runs byte by byte, so a distance
// shorter than the length repeats the last bytes (run-length encoding).
// Decompression is one pass over the input, linear in the output size, and
// writes only into the caller's buffer; any inconsistency (a run or
// reference that leaves the input or output, a distance reaching before the
// start of the output, an output shorter than expected) is an LzfError with
// the input offset where it was found.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

namespace umbra::io_detail {

class LzfError : public std::runtime_error {
 public:
  LzfError(std::size_t input_offset, const std::string& message)
      : std::runtime_error("corrupt LZF data at compressed byte " + std::to_string(input_offset) + ": " + message),
        input_offset_(input_offset) {}
  /// Offset into the compressed input of the chunk that is wrong.
  [[nodiscard]] std::size_t input_offset() const { return input_offset_; }

 private:
  std::size_t input_offset_;
};

/// The largest output a valid LZF stream of `input_bytes` bytes can produce
/// (88 times the input: a 3-byte reference yields at most 264 bytes). Lets
/// callers reject claimed sizes before allocating.
constexpr std::uint64_t lzf_max_output_bytes(std::uint64_t input_bytes) { return input_bytes * 88; }

/// Decompresses all of `input` into exactly `output.size()` bytes; throws
/// LzfError when the data is corrupt or does not produce exactly that size.
void lzf_decompress(std::span<const unsigned char> input, std::span<unsigned char> output);

}  // namespace umbra::io_detail
