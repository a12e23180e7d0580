// libFuzzer target for umbra's own map files (.umb): load_map and
// read_map_info on the input, which is held in a tmpfs file because both
// read from a path. A map that loads must keep the tree's invariants.
//
// Built twice: umbra_fuzz_umb takes the input as it is (so it mostly meets
// the two CRC-32s), umbra_fuzz_umb_body (UMBRA_FUZZ_FIX_CRC) first rewrites
// both checksums to match, so mutations reach the header fields, the zstd
// frames and the tree decoder behind them. Cost per input: one CRC pass and
// the load.
#include <zlib.h>

#include <cstdint>
#include <vector>

#include "fuzz_support.hpp"
#include "umbra/io/map_file.hpp"

#if defined(UMBRA_FUZZ_FIX_CRC)
namespace {

void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

/// The header CRC (bytes 120..123, over bytes 0..119) and the file CRC (the
/// last 4 bytes, over everything before them), as docs/map-format.md defines them.
void fix_checksums(std::vector<std::uint8_t>& bytes) {
  constexpr std::size_t kHeaderCrcAt = 120;
  if (bytes.size() < kHeaderCrcAt + 8) return;
  put_u32(&bytes[kHeaderCrcAt], static_cast<std::uint32_t>(crc32_z(0, bytes.data(), kHeaderCrcAt)));
  const std::size_t body = bytes.size() - 4;
  put_u32(&bytes[body], static_cast<std::uint32_t>(crc32_z(0, bytes.data(), body)));
}

}  // namespace
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static umbra::fuzz::InputFile file(".umb");
  std::vector<std::uint8_t> bytes(data, data + size);
#if defined(UMBRA_FUZZ_FIX_CRC)
  fix_checksums(bytes);
#endif
  const auto& path = file.hold(bytes.data(), bytes.size());
  umbra::fuzz::expect_only_format_errors([&] { (void)umbra::read_map_info(path); });
  umbra::fuzz::expect_only_format_errors([&] {
    const umbra::OccupancyMap map = umbra::load_map(path);
    umbra::fuzz::require(umbra::fuzz::invariants_hold(map), "a loaded map keeps the tree's invariants");
  });
  return 0;
}
