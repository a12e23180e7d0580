// The navigation grid (umbra/query/navigation_grid.hpp) on the real maps:
// 3DTK at 5 cm, TUM at 2 cm, geb079.bt at 8 cm (bench/query/datasets.cpp
// builds them with the discrete integrator and reads them into liboctomap
// through a .bt file). In the same run, on the same maps:
//
//  - umbra: project_to_grid, rules all_known and any_free, cells of depth 0
//    (and depth 2, 4 voxels a cell);
//  - dense: the reference without the octree's help: every voxel of the
//    band over the grid's extent looked up one by one (OccupancyMap::node),
//    merged per cell by the rule. Its grid must equal umbra's, cell for
//    cell (the run stops otherwise): the answers are compared, not assumed;
//  - octomap_server: the algorithm of octomap_server's projected_map
//    (written here from its description, over liboctomap's leaf iterator):
//    every leaf whose centre z lies strictly inside (z_min, z_max) marks its
//    footprint's cells, occupied over everything, free over unknown only.
//    OctoMap has no such call of its own. It decides band membership by the
//    leaf's centre, so a coarse leaf straddling a bound counts whole or not
//    at all: its grid is compared with umbra's any_free grid and the share
//    of equal cells printed.
//
// Times are the calling thread's CPU time (the machine is shared), the
// median of --repeat runs (the dense reference runs once).
//
//   ./scripts/bench.sh navigation --datasets 3dtk-5cm,tum-2cm,geb079-8cm --z-min 0.1 --z-max 1.8 --repeat 7
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include <octomap/OcTree.h>

#include "query/datasets.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace {

using namespace umbra;
using umbra_bench::median;
using umbra_bench::thread_seconds;

struct Options {
  std::string data = "../shared/data";
  std::vector<std::string> datasets = {"3dtk-5cm", "tum-2cm", "geb079-8cm"};
  double z_min = 0.1;
  double z_max = 1.8;
  int repeat = 5;
};

/// The dense reference: every band voxel of the grid's extent, one lookup each.
NavigationGrid dense_projection(const OccupancyMap& map, const ProjectionOptions& o, const NavigationGrid& shape) {
  const Grid& grid = map.grid();
  const std::uint32_t lo = grid.axis_key(o.z_min).value_or(0);
  const std::uint32_t hi = grid.axis_key(o.z_max).value_or(grid.keys_per_axis() - 1);
  const std::uint32_t k = 1u << o.depth;
  const std::uint32_t x0 = *grid.axis_key(shape.origin_x + 0.5 * grid.resolution());
  const std::uint32_t y0 = *grid.axis_key(shape.origin_y + 0.5 * grid.resolution());
  NavigationGrid out = shape;
  for (std::uint32_t j = 0; j < shape.height; ++j) {
    for (std::uint32_t i = 0; i < shape.width; ++i) {
      bool occupied = false, some_free = false, all_free = true;
      for (std::uint32_t dy = 0; dy < k; ++dy) {
        for (std::uint32_t dx = 0; dx < k; ++dx) {
          for (std::uint32_t z = lo; z <= hi; ++z) {
            const OccupancyState s = map.node(Key{x0 + i * k + dx, y0 + j * k + dy, z}, 0).state;
            occupied |= s == OccupancyState::occupied;
            some_free |= s == OccupancyState::free;
            all_free &= s == OccupancyState::free;
          }
        }
      }
      const bool free = o.rule == ProjectionRule::all_known ? all_free : some_free;
      out.cells[std::size_t{j} * shape.width + i] =
          occupied ? GridCell::occupied : free ? GridCell::free : GridCell::unknown;
    }
  }
  return out;
}

/// octomap_server's projection over liboctomap's leaves, on umbra's grid extent (depth-0 cells).
std::vector<std::int8_t> octomap_server_projection(const octomap::OcTree& tree, double z_min, double z_max,
                                                   const NavigationGrid& shape) {
  std::vector<std::int8_t> cells(shape.cells.size(), -1);
  const double res = tree.getResolution();
  const octomap::OcTreeKey origin = tree.coordToKey(shape.origin_x + 0.5 * res, shape.origin_y + 0.5 * res, 0.0);
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const double z = it.getZ();
    if (!(z > z_min && z < z_max)) continue;
    const bool occupied = tree.isNodeOccupied(*it);
    const int size = 1 << (max_depth - static_cast<int>(it.getDepth()));
    const octomap::OcTreeKey low = it.getIndexKey();
    for (int dy = 0; dy < size; ++dy) {
      const long j = long(low[1]) + dy - long(origin[1]);
      if (j < 0 || j >= long(shape.height)) continue;
      for (int dx = 0; dx < size; ++dx) {
        const long i = long(low[0]) + dx - long(origin[0]);
        if (i < 0 || i >= long(shape.width)) continue;
        std::int8_t& cell = cells[std::size_t(j) * shape.width + std::size_t(i)];
        if (occupied) {
          cell = 100;
        } else if (cell == -1) {
          cell = 0;
        }
      }
    }
  }
  return cells;
}

template <typename Run>
double median_ms(int repeat, Run&& run) {
  std::vector<double> times;
  for (int r = 0; r < repeat; ++r) {
    const double start = thread_seconds();
    run();
    times.push_back(1e3 * (thread_seconds() - start));
  }
  return median(times);
}

std::string counts_text(const NavigationGrid& g) {
  std::size_t o = 0, f = 0;
  for (const GridCell c : g.cells) {
    o += c == GridCell::occupied;
    f += c == GridCell::free;
  }
  char text[96];
  std::snprintf(text, sizeof text, "%zu / %zu / %zu", o, f, g.cells.size() - o - f);
  return text;
}

int run(const Options& options) {
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() / ("umbra-navigation-grid-benchmark-" + std::to_string(::getpid()));
  std::filesystem::create_directories(scratch);
  std::printf("band z %g .. %g m; times: thread CPU ms, median of %d (dense: one run)\n\n", options.z_min,
              options.z_max, options.repeat);
  std::printf("| map | depth | cells (w x h) | band voxels | occupied / free / unknown (all_known) | umbra all_known | "
              "umbra any_free | dense per-voxel | umbra vs dense | octomap_server over liboctomap leaves | cells "
              "equal to umbra any_free |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& name : options.datasets) {
    const auto spec = std::find_if(umbra_bench::kDatasets.begin(), umbra_bench::kDatasets.end(),
                                   [&](const umbra_bench::DatasetSpec& s) { return s.name == name; });
    if (spec == umbra_bench::kDatasets.end()) throw std::invalid_argument("unknown dataset '" + name + "'");
    const umbra_bench::Dataset data = umbra_bench::load_dataset(*spec, options.data, scratch);
    const OccupancyMap& map = *data.map;
    for (const int depth : {0, 2}) {
      ProjectionOptions all_known{options.z_min, options.z_max, depth, ProjectionRule::all_known};
      ProjectionOptions any_free = all_known;
      any_free.rule = ProjectionRule::any_free;
      NavigationGrid grid_all, grid_any;
      const double t_all = median_ms(options.repeat, [&] { grid_all = project_to_grid(map, all_known); });
      const double t_any = median_ms(options.repeat, [&] { grid_any = project_to_grid(map, any_free); });
      if (grid_all.empty()) throw std::runtime_error(name + ": nothing known in the band");
      NavigationGrid dense;
      const double t_dense = median_ms(1, [&] { dense = dense_projection(map, all_known, grid_all); });
      if (!(dense == grid_all)) throw std::runtime_error(name + ": umbra's grid differs from the dense reference");
      const NavigationGrid dense_any = dense_projection(map, any_free, grid_any);
      if (!(dense_any == grid_any)) throw std::runtime_error(name + ": any_free differs from the dense reference");
      const std::size_t rows = grid_all.cells.size() * (std::size_t{1} << (2 * depth)) *
                               (*map.grid().axis_key(options.z_max) - *map.grid().axis_key(options.z_min) + 1);
      std::string octo_time = "-", octo_equal = "-";
      if (depth == 0) {
        std::vector<std::int8_t> octo;
        const double t_octo = median_ms(options.repeat, [&] {
          octo = octomap_server_projection(*data.octree, options.z_min, options.z_max, grid_any);
        });
        std::size_t equal = 0;
        for (std::size_t c = 0; c < octo.size(); ++c) equal += octo[c] == static_cast<std::int8_t>(grid_any.cells[c]);
        char text[64];
        std::snprintf(text, sizeof text, "%.2f ms", t_octo);
        octo_time = text;
        std::snprintf(text, sizeof text, "%.2f%%", 100.0 * double(equal) / double(octo.size()));
        octo_equal = text;
      }
      std::printf("| %s | %d | %u x %u | %zu | %s | %.2f ms | %.2f ms | %.1f ms | %s | %s | %s |\n", name.c_str(),
                  depth, grid_all.width, grid_all.height, rows, counts_text(grid_all).c_str(), t_all, t_any, t_dense,
                  umbra_bench::ratio(t_dense, t_all).c_str(), octo_time.c_str(), octo_equal.c_str());
      std::fflush(stdout);
    }
  }
  std::filesystem::remove_all(scratch);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
      return argv[++i];
    };
    try {
      if (arg == "--data") {
        options.data = value();
      } else if (arg == "--datasets") {
        options.datasets = umbra_bench::split(value());
      } else if (arg == "--z-min") {
        options.z_min = std::stod(value());
      } else if (arg == "--z-max") {
        options.z_max = std::stod(value());
      } else if (arg == "--repeat") {
        options.repeat = std::max(1, std::stoi(value()));
      } else {
        std::fprintf(stderr,
                     "usage: %s [--data DIR] [--datasets 3dtk-5cm,tum-2cm,geb079-8cm] [--z-min M] [--z-max M] "
                     "[--repeat N]\nunknown option '%s'\n",
                     argv[0], arg.c_str());
        return 2;
      }
    } catch (const std::logic_error& e) {
      std::fprintf(stderr, "%s: bad %s: %s\n", argv[0], arg.c_str(), e.what());
      return 2;
    }
  }
  try {
    return run(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
}
