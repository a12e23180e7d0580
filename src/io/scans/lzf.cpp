// LZF decompression for PCD "binary_compressed" data; the format is
// described in lzf.hpp. One pass, no allocation, every length checked
// against both buffers before it is used.
#include "lzf.hpp"

#include <cstring>

namespace umbra::io_detail {

void lzf_decompress(std::span<const unsigned char> input, std::span<unsigned char> output) {
  constexpr unsigned kLiteralLimit = 32;  // control bytes below this start a literal run
  constexpr unsigned kExtendedLength = 7;  // length field value that takes an extra byte
  std::size_t in = 0;
  std::size_t out = 0;
  while (in < input.size()) {
    const std::size_t chunk_start = in;
    const unsigned control = input[in++];
    if (control < kLiteralLimit) {
      const std::size_t length = control + 1;
      if (length > input.size() - in) {
        throw LzfError(chunk_start, "a literal run of " + std::to_string(length) + " bytes, but only " +
                                        std::to_string(input.size() - in) + " bytes of input remain");
      }
      if (length > output.size() - out) {
        throw LzfError(chunk_start, "a literal run of " + std::to_string(length) + " bytes overflows the output (" +
                                        std::to_string(output.size()) + " bytes expected)");
      }
      std::memcpy(output.data() + out, input.data() + in, length);
      in += length;
      out += length;
      continue;
    }
    std::size_t length = control >> 5;
    if (length == kExtendedLength) {
      if (in == input.size()) throw LzfError(chunk_start, "a back reference whose length byte is missing");
      length += input[in++];
    }
    length += 2;
    if (in == input.size()) throw LzfError(chunk_start, "a back reference whose distance byte is missing");
    const std::size_t distance = ((static_cast<std::size_t>(control & 31U) << 8) | input[in++]) + 1;
    if (distance > out) {
      throw LzfError(chunk_start, "a back reference " + std::to_string(distance) + " bytes back, but only " +
                                      std::to_string(out) + " bytes have been produced");
    }
    if (length > output.size() - out) {
      throw LzfError(chunk_start, "a back reference of " + std::to_string(length) + " bytes overflows the output (" +
                                      std::to_string(output.size()) + " bytes expected)");
    }
    unsigned char* destination = output.data() + out;
    const unsigned char* source = destination - distance;
    if (distance >= length) {
      std::memcpy(destination, source, length);
    } else {
      for (std::size_t i = 0; i < length; ++i) destination[i] = source[i];  // overlapping: repeats
    }
    out += length;
  }
  if (out != output.size()) {
    throw LzfError(input.size(), "the data ends after " + std::to_string(out) + " of the expected " +
                                     std::to_string(output.size()) + " bytes");
  }
}

}  // namespace umbra::io_detail
