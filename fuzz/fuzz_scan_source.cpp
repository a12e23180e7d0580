// libFuzzer target for a point-cloud reader behind open_scan_source(): the
// format is fixed at build time (UMBRA_FUZZ_FORMAT, e.g. "graph", "xyz",
// "ply", "pcd", "kitti") and so is the name the input is held under
// (UMBRA_FUZZ_SUFFIX, e.g. ".xyz.bz2" to reach the bz2 path). Every scan is
// read to the end; a scan must have as many colors as points, or none, and
// the origin the source announced at open (origins()), if it did.
#include <cstdint>
#include <memory>
#include <vector>

#include "fuzz_support.hpp"
#include "umbra/io/scan_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static umbra::fuzz::InputFile file(UMBRA_FUZZ_SUFFIX);
  const auto& path = file.hold(data, size);
  umbra::fuzz::expect_only_format_errors([&] {
    umbra::ScanSourceOptions options;
    options.format = UMBRA_FUZZ_FORMAT;
    const std::unique_ptr<umbra::ScanSource> source = umbra::open_scan_source(path, options);
    const std::vector<umbra::Vec3f> origins = source->origins();
    umbra::fuzz::require(origins.empty() || origins.size() == source->scan_count(), "one origin per scan, or none");
    umbra::Scan scan;
    for (std::size_t index = 0; source->next(scan); ++index) {
      umbra::fuzz::require(scan.colors.empty() || scan.colors.size() == scan.points.size(),
                           "one color per point, or none");
      umbra::fuzz::require(origins.empty() || (index < origins.size() && origins[index] == scan.origin),
                           "the scan's origin is the one announced at open");
      const double progress = source->progress();
      umbra::fuzz::require(progress >= 0.0 && progress <= 1.0, "progress within 0..1");
    }
  });
  return 0;
}
