// libFuzzer target for the OctoMap readers (.bt and .ot; built twice, as
// umbra_fuzz_octomap_bt and umbra_fuzz_octomap_ot, with their own seed
// corpora and dictionaries: the input is the whole file and the first line
// picks the format).
//
// Besides "no crash, only FormatError", a file that is read must give a map
// whose invariants hold, and writing it, reading that and writing again must
// give the same bytes (the writer's output is a fixed point). Cost per
// input: linear in its size (at most 17 levels of recursion).
#include <cstdint>
#include <span>

#include "fuzz_support.hpp"
#include "umbra/io/octomap_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  umbra::fuzz::expect_only_format_errors([&] {
    const umbra::OccupancyMap map = umbra::decode_octomap(std::span(data, size), "fuzz-input");
    umbra::fuzz::require(umbra::fuzz::invariants_hold(map), "a decoded map keeps the tree's invariants");
    for (const umbra::OctoMapFormat format : {umbra::OctoMapFormat::bt, umbra::OctoMapFormat::ot}) {
      const std::vector<std::uint8_t> written = umbra::encode_octomap(map, format);
      const umbra::OccupancyMap again = umbra::decode_octomap(written, "re-encoded");
      umbra::fuzz::require(umbra::encode_octomap(again, format) == written, "encode(decode(encode(m))) == encode(m)");
    }
  });
  return 0;
}
