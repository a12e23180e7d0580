// libFuzzer target for a point-cloud reader behind open_scan_source(): the
// format is fixed at build time (UMBRA_FUZZ_FORMAT, e.g. "graph", "xyz",
// "ply", "pcd", "kitti") and so is the name the input is held under
// (UMBRA_FUZZ_SUFFIX, e.g. ".xyz.bz2" to reach the bz2 path). Every scan is
// read to the end; a scan must have as many colours as points, or none.
#include <cstdint>
#include <memory>

#include "fuzz_support.hpp"
#include "umbra/io/scan_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static umbra::fuzz::InputFile file(UMBRA_FUZZ_SUFFIX);
  const auto& path = file.hold(data, size);
  umbra::fuzz::expect_only_format_errors([&] {
    umbra::ScanSourceOptions options;
    options.format = UMBRA_FUZZ_FORMAT;
    const std::unique_ptr<umbra::ScanSource> source = umbra::open_scan_source(path, options);
    umbra::Scan scan;
    while (source->next(scan)) {
      umbra::fuzz::require(scan.colors.empty() || scan.colors.size() == scan.points.size(),
                           "one colour per point, or none");
      const double progress = source->progress();
      umbra::fuzz::require(progress >= 0.0 && progress <= 1.0, "progress within 0..1");
    }
  });
  return 0;
}
