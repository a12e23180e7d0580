// Decompression of a bag chunk's data (internal to bag_file.cpp): "bz2"
// with Debian's libbz2, "lz4" with liblz4's frame API (rosbag's roslz4
// writes standard LZ4 frames).
//
// The chunk header declares the decompressed size; the output must be
// exactly that long. The size is checked against the memory limit before
// anything is allocated (MemoryLimitError), and the output buffer grows as
// bytes actually come out (doubling, up to the declared size), so a header
// that declares more than its data holds costs no more than the data.
// Corrupt data, data that ends early, more output than declared and bytes
// after the end of the compressed stream are FormatErrors at the chunk's
// byte offset.
//
// Cost: one pass of the decompressor; the output buffer is reused between calls.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "bag_record.hpp"

namespace umbra::ros_io::bag_detail {

/// Decompresses `compressed` ("bz2" or "lz4", as `compression` says) into `out`, which ends up `size` bytes long.
/// `site` is the chunk record (errors name it).
void decompress_chunk(const std::string& compression, std::span<const std::uint8_t> compressed, std::uint32_t size,
                      std::vector<std::uint8_t>& out, const RecordSite& site);

}  // namespace umbra::ros_io::bag_detail
