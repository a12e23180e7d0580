// libFuzzer target: the input lines of `umbra query` (tools/query_lines.cpp,
// the very parser and answering code the command runs), against a small
// fixed map.
//
// Input: byte 0 chooses the settings a user sets on the command line: bits
// 0-1 the kind (sphere, box, line, raycast), bit 2 --unknown free, bits 3-4
// --depth 0..3, bits 5-7 --radius from a list that includes what CLI11's
// NonNegativeNumber lets through (inf, nan, 1e300). The rest is the text
// of the input file, any number of lines, read one by one with
// QueryLineReader (the command's streaming reader). Not covered yet: `gain`
// lines (added to `umbra query` after this target).
//
// Crashes (the rule): any exception other than the std::invalid_argument /
// std::out_of_range the answering turns into a per-line problem, a failed
// UMBRA_ASSERT, a sanitizer report. Properties of what is accepted: a good
// line holds exactly the kind's count of finite numbers and a bad one holds
// none (a line over kMaxQueryLineBytes included); line numbers rise; the
// reader stops only at the end of the input; a NaN or infinite capsule
// radius is refused; a region free at a coarser depth is free at depth 0 (coarse answers are
// conservative); a raycast hit at depth 0 is the centre of an occupied
// voxel. The map (8 depth levels at 0.1 m, so +-12.8 m: easy to leave)
// holds free, occupied and unknown space: one scan of a half shell.
// Cost per input: one pass over the text, and at most two library queries
// per good line.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "query_lines.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using umbra::fuzz::require;
using namespace umbra;
using namespace umbra::cli;

const OccupancyMap& fixed_map() {
  static const OccupancyMap map = [] {
    MapConfig config;
    config.resolution = 0.1;
    config.depth_levels = 8;
    OccupancyMap m(config);
    const Vec3f origin{0.55f, 0.25f, 0.15f};
    std::vector<Vec3f> points;
    for (int a = 0; a < 60; ++a) {
      for (int b = 0; b < 15; ++b) {  // the upper half shell of radius 3: unknown below it and beyond
        const double azimuth = a * 6.283185307179586 / 60;
        const double elevation = b * 1.5707963267948966 / 15;
        points.push_back({origin.x + static_cast<float>(3 * std::cos(elevation) * std::cos(azimuth)),
                          origin.y + static_cast<float>(3 * std::cos(elevation) * std::sin(azimuth)),
                          origin.z + static_cast<float>(3 * std::sin(elevation))});
      }
    }
    m.insert_point_cloud(origin, points);
    return m;
  }();
  return map;
}

constexpr std::array<double, 8> kRadii = {0.0, 0.05, 0.3, 2.0, 1e300, std::numeric_limits<double>::infinity(),
                                          std::numeric_limits<double>::quiet_NaN(), 1e-300};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const OccupancyMap& map = fixed_map();
  const auto kind = static_cast<LineQuery>(data[0] & 3);
  LineQuerySettings settings;
  settings.collision = {(data[0] & 4) != 0, (data[0] >> 3) & 3};
  settings.radius = kRadii[data[0] >> 5];
  const CollisionOptions& collision = settings.collision;
  const double radius = settings.radius;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data) + 1, size - 1));
  QueryLineReader reader(in, kind);

  std::size_t last = 0;
  LineQuerySettings finest = settings;
  finest.collision.depth = 0;
  while (const QueryLine* line = reader.next()) {
    require(line->number > last, "lines come in order, numbered from 1");
    last = line->number;
    if (!line->good()) {
      require(line->values.empty(), "a bad line holds no values");
      continue;
    }
    require(line->values.size() == numbers_of(kind), "a good line holds exactly the kind's count of numbers");
    for (const double v : line->values) require(std::isfinite(v), "a good line holds only finite numbers");

    const QueryAnswer answer = answer_query_line(map, kind, line->values, settings);
    require(answer.ok != !answer.problem.empty(), "an answer or a problem, never both");
    if (kind == LineQuery::line && !(std::isfinite(radius) && radius >= 0.0)) {
      require(!answer.ok, "a NaN or infinite capsule radius is refused");
    }
    if (!answer.ok) continue;
    if (kind == LineQuery::raycast) {
      if (answer.yes && collision.depth == 0) {
        require(map.state(answer.point) == OccupancyState::occupied, "a raycast hits an occupied voxel's centre");
      }
    } else if (!answer.yes && collision.depth > 0) {
      const QueryAnswer fine = answer_query_line(map, kind, line->values, finest);
      require(fine.ok && !fine.yes, "free at a coarser depth is free at depth 0");
    }
  }
  require(in.eof(), "the reader stops only at the end of the input");
  return 0;
}
