// Fidelity benchmark: how the discrete and fast integrators' maps agree with
// the simple integrator's (OctoMap's insertPointCloud without
// discretisation), voxel by voxel, on the benchmark inputs.
//
// For every dataset and resolution each method builds a map from all scans
// (one thread: the map is the same for every thread count), then the
// finished map is compared with the simple integrator's
// (umbra::compare_maps, include/umbra/map/map_agreement.hpp: the comparison
// the tests and `umbra compare` use): occupied
// and free voxels, recall and precision of the occupied voxels, the share of
// the simple map's free voxels left unknown, and the simple map's occupied
// voxels made free, and the voxels it frees where the simple map has none known
// (between rays). Methods: discrete, fast-n2, fast-n0 (fast integrator,
// fine_steps 2 / 0, clear depth at 16 cm unless --clear-depth says).
//
// Usage: umbra_fidelity_benchmark [--data DIR] [--datasets tum,3dtk,sim-camera]
//          [--res 0.04,0.02] [--methods discrete,fast-n2,fast-n0] [--clear-depth -1]
//          [--max-range 30] [--tum-max-range 5] [--markdown FILE]
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "common/argument_cursor.hpp"
#include "umbra/map/map_agreement.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using namespace umbra;

struct Method {
  std::string name;
  IntegratorKind kind;
  int fine_steps;
};

const std::vector<Method> kMethods = {
    {"simple", IntegratorKind::simple, 0},
    {"discrete", IntegratorKind::discrete, 0},
    {"fast-n2", IntegratorKind::fast, 2},
    {"fast-n0", IntegratorKind::fast, 0},
    {"projective", IntegratorKind::projective, 0},
};

OccupancyMap build(const bench::Dataset& data, double resolution, const Method& method, int clear_depth,
                   double& seconds) {
  OccupancyMap map(resolution);
  InsertOptions options;
  options.integrator = method.kind;
  options.fine_steps = method.fine_steps;
  options.clear_depth = clear_depth;
  options.max_range = data.max_range;
  options.threads = 1;
  const auto start = std::chrono::steady_clock::now();
  for (const Scan& scan : data.scans) {
    if (method.kind == IntegratorKind::projective && scan.image) {
      map.insert_depth_image(scan.image->view(), scan.image->camera, scan.image->pose, {}, options);
    } else {
      map.insert_point_cloud(scan.origin, scan.points, options);
    }
  }
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return map;
}

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f%%", 100.0 * fraction);
  return text;
}

std::string thousands(std::uint64_t n) {
  std::string digits = std::to_string(n);
  for (int i = static_cast<int>(digits.size()) - 3; i > 0; i -= 3) digits.insert(static_cast<std::size_t>(i), ",");
  return digits;
}

}  // namespace

int main(int argc, char** argv) {
  bench::DatasetOptions data_options;
  std::string datasets = "tum,3dtk,sim-camera";
  std::string resolutions = "0.04,0.02";
  std::string method_names = "discrete,fast-n2,fast-n0";
  std::string markdown_path;
  int clear_depth = -1;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    auto value = [&] { return args.value(); };
    if (arg == "--data") data_options.data_dir = value();
    else if (arg == "--datasets") datasets = value();
    else if (arg == "--res") resolutions = value();
    else if (arg == "--methods") method_names = value();
    else if (arg == "--clear-depth") clear_depth = std::stoi(value());
    else if (arg == "--max-range") data_options.max_range = std::stod(value());
    else if (arg == "--tum-max-range") data_options.tum_max_range = std::stod(value());
    else if (arg == "--markdown") markdown_path = value();
    else if (arg == "--help" || arg == "-h") {
      std::printf("usage: umbra_fidelity_benchmark [--data DIR] [--datasets tum,3dtk,sim-camera] [--res 0.04,0.02]\n"
                  "         [--methods discrete,fast-n2,fast-n0,projective] [--clear-depth -1] [--max-range 30]\n"
                  "         [--tum-max-range 5] [--markdown FILE]\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/fidelity_benchmark.cpp)\n",
                   arg.c_str());
      return 2;
    }
  }
  std::vector<Method> methods;
  for (const std::string& name : bench::split_list(method_names)) {
    bool found = false;
    for (const Method& m : kMethods) {
      if (m.name == name && m.name != "simple") {
        methods.push_back(m);
        found = true;
      }
    }
    if (!found) {
      std::fprintf(stderr, "unknown method %s (discrete, fast-n2, fast-n0, projective)\n", name.c_str());
      return 2;
    }
  }

  std::ostringstream table;
  table << "| dataset | res (m) | method | occupied voxels | recall vs simple | precision vs simple | free voxels | "
           "simple's free left unknown | simple's occupied made free | free where simple has unknown | "
           "s (1 thread) |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& name : bench::split_list(datasets)) {
    bench::Dataset data;
    try {
      data = bench::load_dataset(name, data_options);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cannot load %s: %s\n", name.c_str(), e.what());
      return 1;
    }
    for (const std::string& res_text : bench::split_list(resolutions)) {
      const double resolution = std::stod(res_text);
      double seconds = 0.0;
      const OccupancyMap simple = build(data, resolution, kMethods[0], clear_depth, seconds);
      const umbra::MapAgreement self = umbra::compare_maps(simple, simple);
      char row[512];
      std::snprintf(row, sizeof row, "| %s | %.3g | simple | %s | - | - | %s | - | - | - | %.2f |\n", name.c_str(),
                    resolution, thousands(self.reference_count(OccupancyState::occupied)).c_str(),
                    thousands(self.reference_count(OccupancyState::free)).c_str(), seconds);
      table << row;
      std::fputs(row, stderr);
      for (const Method& method : methods) {
        const OccupancyMap map = build(data, resolution, method, clear_depth, seconds);
        const umbra::MapAgreement a = umbra::compare_maps(simple, map);
        std::snprintf(row, sizeof row, "| %s | %.3g | %s | %s | %s | %s | %s | %s | %s | %s | %.2f |\n", name.c_str(),
                      resolution, method.name.c_str(), thousands(a.other_count(OccupancyState::occupied)).c_str(),
                      percent(a.recall()).c_str(), percent(a.precision()).c_str(),
                      thousands(a.other_count(OccupancyState::free)).c_str(), percent(a.free_left_unknown()).c_str(),
                      thousands(a.count(OccupancyState::occupied, OccupancyState::free)).c_str(),
                      thousands(a.count(OccupancyState::unknown, OccupancyState::free)).c_str(), seconds);
        table << row;
        std::fputs(row, stderr);
      }
    }
  }
  std::printf("%s", table.str().c_str());
  if (!markdown_path.empty()) std::ofstream(markdown_path) << table.str();
  return 0;
}
