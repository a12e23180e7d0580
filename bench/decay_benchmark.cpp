// Decay toward unknown (docs/benchmarks.md, "Decay toward unknown"): the
// time of one decay step (OccupancyMap::advance_clock) on real maps, against
// the insertion of a scan into the same map and against the loop an OctoMap
// user writes for the same rule, side by side in one run:
//   - umbra: the map of all the dataset's scans (discrete integrator), then
//     `--steps` steps of `--dt` seconds at `--occupied` / `--free` log-odds
//     per second; also the same steps limited to a box (`--region` metres
//     around the first sensor position); memory_bytes() before and after;
//   - OctoMap: the OcTree of the same scans (insertPointCloud, discretize:
//     the same voxels), each step a loop over its leaves moving each value
//     toward 0 by the same float, then updateInnerOccupancy() (leaves that
//     reach 0 stay: see octomap_step);
//   - both maps' states compared after the steps, at the centres of each
//     one's leaves (they must agree, or the timing compares different work).
//   - the growth of a step with the map: the same steps on the map of the
//     first k scans, k = 1 .. all (one thread);
//   - the same steps on several threads (`--threads`, as a stamped scan
//     runs them: an empty stamped scan, whose tracing costs microseconds);
//   - a map that decays while it is built: every scan stamped `--dt` after
//     the last (its step, then the scan), against the plain inserts;
//   - the cost of reading: `state()` at a million random points of the
//     scans' extent, on the map without decay and on the decayed map.
// Datasets: 3dtk (5 cm), tum (2 cm); median of the steps.
//
//   umbra_decay_benchmark [--data ../shared/data] [--datasets 3dtk,tum] [--steps 10]
//                         [--dt 0.5] [--occupied 0.4] [--free 0.2] [--region 4] [--threads 2]
//                         [--stamped-only]   (only the plain and the stamped inserts: for a profiler)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>
#include <vector>

#include <random>

#include <octomap/OcTree.h>

#include "common/argument_cursor.hpp"
#include "bench_data.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// CPU time of the process (all threads), seconds: what a step costs even
/// while other programs share the cores (wall time then stretches).
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Options {
  std::string data_dir = "../shared/data";
  std::vector<std::string> datasets{"3dtk", "tum"};
  int steps = 10;
  double dt = 0.5;
  double occupied = 0.4;
  double free = 0.2;
  double region = 4.0;
  unsigned threads = 2;
  bool stamped_only = false;  // only the plain and the stamped inserts (for a profiler)
};

/// The amount a step from clock time `from` to `to` takes off at `rate`
/// (docs/design.md: the amounts accumulated since the clock started at 0,
/// rounded down to whole quanta of 2^-16, subtracted).
float quantized_step(double rate, double from, double to) {
  const double quantum = 1.0 / 65536.0;
  return static_cast<float>((std::floor(rate * to / quantum) - std::floor(rate * from / quantum)) * quantum);
}

/// The documented rule (docs/design.md), for OctoMap's values.
float decayed(float l, float occupied, float free) {
  if (l > 0.0f) return l > occupied ? l - occupied : 0.0f;
  if (l < 0.0f) return -l > free ? l + free : 0.0f;
  return 0.0f;
}

/// One decay step over an OcTree, as a user writes it: every leaf moved
/// toward 0, then inner nodes recomputed. Leaves that reach 0 stay as nodes
/// of log-odds 0 (OctoMap calls them free: 0 is not above its threshold):
/// deleting them (OcTree::deleteNode, OctoMap's only "unknown") aborts in
/// Debian's liboctomap 1.9 (an assertion in ~OcTreeDataNode when a deletion
/// empties a parent), so the comparison below counts l = 0 as unknown.
std::size_t octomap_step(octomap::OcTree& tree, float occupied, float free) {
  std::size_t zero = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const float next = decayed(it->getLogOdds(), occupied, free);
    it->setLogOdds(next);
    zero += next == 0.0f;
  }
  tree.updateInnerOccupancy();
  return zero;
}

/// Finest voxels on which the two maps' states differ (over umbra's known leaves and OctoMap's leaves).
std::size_t disagreements(const umbra::OccupancyMap& map, const octomap::OcTree& tree) {
  std::size_t differ = 0;
  map.for_each_leaf([&](const umbra::Node& node) {
    if (node.state == umbra::OccupancyState::unknown) return;
    const octomap::OcTreeNode* found = tree.search(node.center.x, node.center.y, node.center.z);
    const bool occupied = node.state == umbra::OccupancyState::occupied;
    if (found == nullptr || found->getLogOdds() == 0.0f || tree.isNodeOccupied(found) != occupied) ++differ;
  });
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (it->getLogOdds() != 0.0f && map.state(umbra::Vec3d{it.getX(), it.getY(), it.getZ()}) == umbra::OccupancyState::unknown) ++differ;
  }
  return differ;
}

/// A map that decays while it is built: each scan stamped `dt` after the
/// last (its step, then the scan), against the plain inserts (`plain`,
/// `plain_cpu`: seconds per scan). The step (advance_clock) and the scan
/// (insert_point_cloud with the same stamp: its clock is there already) are
/// also timed apart, to tell what the step costs from what decay adds to
/// the scan's own writes.
void stamped_scans(const umbra::bench::Dataset& data, double resolution, const umbra::InsertOptions& insert,
                   const Options& options, const std::vector<double>& plain, const std::vector<double>& plain_cpu) {
  umbra::OccupancyMap living(resolution);
  living.set_decay({options.occupied, options.free, std::nullopt});
  std::vector<double> living_insert, living_cpu, step_cpu, scan_cpu;
  umbra::InsertOptions living_options = insert;
  for (std::size_t i = 0; i < data.scans.size(); ++i) {
    living_options.stamp = static_cast<double>(i) * options.dt;
    const double cpu_start = cpu_seconds();
    const auto start = Clock::now();
    living.advance_clock(*living_options.stamp);
    const double cpu_stepped = cpu_seconds();
    living.insert_point_cloud(data.scans[i].origin, data.scans[i].points, living_options);
    living_insert.push_back(seconds_since(start));
    const double cpu_end = cpu_seconds();
    living_cpu.push_back(cpu_end - cpu_start);
    step_cpu.push_back(cpu_stepped - cpu_start);
    scan_cpu.push_back(cpu_end - cpu_stepped);
  }
  std::printf("  stamped scans (decay while building, %.2f s apart, 1 thread): median %.1f ms (CPU %.1f) per scan "
              "and its step, against %.1f ms plain; %zu nodes, %.1f MB\n",
              options.dt, umbra::bench::median(living_insert) * 1e3, umbra::bench::median(living_cpu) * 1e3,
              umbra::bench::median(plain) * 1e3, living.node_counts().total(), living.memory_bytes() / 1e6);
  double steps = 0.0, scans = 0.0, plains = 0.0;
  for (std::size_t i = 0; i < step_cpu.size(); ++i) {
    steps += step_cpu[i];
    scans += scan_cpu[i];
    plains += plain_cpu[i];
  }
  std::printf("  stamped scans apart, CPU: step median %.2f ms (all %.1f), scan with decay on median %.1f ms (all "
              "%.1f), plain scan median %.1f ms (all %.1f)\n",
              umbra::bench::median(step_cpu) * 1e3, steps * 1e3, umbra::bench::median(scan_cpu) * 1e3, scans * 1e3,
              umbra::bench::median(plain_cpu) * 1e3, plains * 1e3);
}

void run(const std::string& name, const Options& options) {
  umbra::bench::DatasetOptions data_options;
  data_options.data_dir = options.data_dir;
  const umbra::bench::Dataset data = umbra::bench::load_dataset(name, data_options);
  const double resolution = name == "tum" ? 0.02 : 0.05;
  umbra::OccupancyMap map(resolution);
  octomap::OcTree tree(resolution);
  umbra::InsertOptions insert;
  insert.integrator = umbra::IntegratorKind::discrete;
  insert.max_range = data.max_range;
  insert.threads = 1;
  std::vector<double> umbra_insert, umbra_insert_cpu, octomap_insert;
  // Wall times of the steps; with `cpu`, also their CPU times.
  const auto decay_steps = [&](umbra::OccupancyMap& m, std::vector<double>* cpu = nullptr) {
    std::vector<double> times;
    double clock = 0.0;
    m.advance_clock(clock);
    for (int i = 0; i < options.steps; ++i) {
      clock += options.dt;
      const double cpu_start = cpu_seconds();
      const auto start = Clock::now();
      m.advance_clock(clock);
      times.push_back(seconds_since(start));
      if (cpu != nullptr) cpu->push_back(cpu_seconds() - cpu_start);
    }
    return times;
  };
  std::vector<std::string> growth;  // one line per prefix of the scans
  for (const umbra::Scan& scan : data.scans) {
    const double insert_cpu = cpu_seconds();
    auto start = Clock::now();
    map.insert_point_cloud(scan.origin, scan.points, insert);
    umbra_insert.push_back(seconds_since(start));
    umbra_insert_cpu.push_back(cpu_seconds() - insert_cpu);
    if (options.stamped_only) continue;
    octomap::Pointcloud cloud;
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    start = Clock::now();
    tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), data.max_range, false,
                          true);
    octomap_insert.push_back(seconds_since(start));
    umbra::OccupancyMap prefix = map;
    prefix.set_decay({options.occupied, options.free, std::nullopt});
    std::vector<double> cpu;
    const std::vector<double> times = decay_steps(prefix, &cpu);
    char line[200];
    double total = 0.0;
    for (const double c : cpu) total += c;
    std::snprintf(line, sizeof line,
                  "    %zu scans: %zu nodes, step median %.2f ms wall, %.2f ms CPU (first %.2f, max %.2f, all %zu steps %.2f CPU)",
                  umbra_insert.size(), map.node_counts().total(), umbra::bench::median(times) * 1e3,
                  umbra::bench::median(cpu) * 1e3, cpu.front() * 1e3, *std::max_element(cpu.begin(), cpu.end()) * 1e3,
                  cpu.size(), total * 1e3);
    growth.emplace_back(line);
  }
  const umbra::NodeCounts counts = map.node_counts();
  if (options.stamped_only) {
    stamped_scans(data, resolution, insert, options, umbra_insert, umbra_insert_cpu);
    return;
  }
  std::printf("%s %.2f cm: %zu scans; umbra %zu nodes (%zu leaves, %zu inner leaves), %.1f MB; OctoMap %zu nodes, %.1f MB\n",
              name.c_str(), resolution * 100, data.scans.size(), counts.total(), counts.leaf, counts.inner_leaf,
              map.memory_bytes() / 1e6, tree.size(), tree.memoryUsage() / 1e6);
  std::printf("  insert per scan (median, 1 thread): umbra %.1f ms (CPU %.1f), OctoMap %.1f ms\n",
              umbra::bench::median(umbra_insert) * 1e3, umbra::bench::median(umbra_insert_cpu) * 1e3,
              umbra::bench::median(octomap_insert) * 1e3);

  std::printf("  decay step against the map's size (1 thread, %d steps each):\n", options.steps);
  for (const std::string& line : growth) std::printf("%s\n", line.c_str());

  // Whole map.
  umbra::OccupancyMap whole = map;
  whole.set_decay({options.occupied, options.free, std::nullopt});
  const std::size_t bytes_before = whole.memory_bytes();
  std::vector<double> umbra_cpu;
  const std::vector<double> umbra_times = decay_steps(whole, &umbra_cpu);
  std::vector<double> octomap_times;
  std::size_t octomap_zero = 0;
  for (int i = 0; i < options.steps; ++i) {
    // The amounts of umbra's step i (clock from i dt to (i + 1) dt).
    const double from = i * options.dt;
    const double to = (i + 1) * options.dt;
    const float occupied_step = quantized_step(options.occupied, from, to);
    const float free_step = quantized_step(options.free, from, to);
    const auto start = Clock::now();
    octomap_zero = octomap_step(tree, occupied_step, free_step);
    octomap_times.push_back(seconds_since(start));
  }
  double umbra_cpu_total = 0.0;
  for (const double c : umbra_cpu) umbra_cpu_total += c;
  std::printf("  decay step, whole map (%d steps of %.2f s at %.2f / %.2f per s): umbra median %.2f ms (first %.2f, "
              "last %.2f; CPU median %.2f, max %.2f, all steps %.2f), OctoMap loop median %.2f ms (first %.2f, last %.2f)\n",
              options.steps, options.dt, options.occupied, options.free, umbra::bench::median(umbra_times) * 1e3,
              umbra_times.front() * 1e3, umbra_times.back() * 1e3, umbra::bench::median(umbra_cpu) * 1e3,
              *std::max_element(umbra_cpu.begin(), umbra_cpu.end()) * 1e3, umbra_cpu_total * 1e3,
              umbra::bench::median(octomap_times) * 1e3,
              octomap_times.front() * 1e3, octomap_times.back() * 1e3);
  const umbra::NodeCounts after = whole.node_counts();
  std::printf("  after: umbra %zu nodes, memory_bytes %.1f MB -> %.1f MB; OctoMap "
              "%zu nodes (%zu leaves at 0); leaves whose states differ: %zu\n",
              after.total(), bytes_before / 1e6, whole.memory_bytes() / 1e6,
              tree.size(), octomap_zero, disagreements(whole, tree));

  // The same steps on several threads, as a stamped scan runs them.
  umbra::OccupancyMap threaded = map;
  threaded.set_decay({options.occupied, options.free, std::nullopt});
  std::vector<double> threaded_times, threaded_cpu;
  umbra::InsertOptions stamped;
  stamped.threads = options.threads;
  for (int i = 0; i <= options.steps; ++i) {
    stamped.stamp = i * options.dt;
    const double cpu_start = cpu_seconds();
    const auto start = Clock::now();
    threaded.insert_point_cloud(data.scans.front().origin, std::vector<umbra::Vec3f>{}, stamped);
    if (i == 0) continue;  // the first stamp only starts the clock
    threaded_times.push_back(seconds_since(start));
    threaded_cpu.push_back(cpu_seconds() - cpu_start);
  }
  std::printf("  decay step, whole map, %u threads (an empty stamped scan): umbra median %.2f ms (first %.2f, last "
              "%.2f; CPU median %.2f, all threads)%s\n",
              options.threads, umbra::bench::median(threaded_times) * 1e3, threaded_times.front() * 1e3,
              threaded_times.back() * 1e3, umbra::bench::median(threaded_cpu) * 1e3, threaded.node_counts().total() == whole.node_counts().total() ? "" : " DIFFERENT MAP");

  // A region around the first sensor position.
  umbra::OccupancyMap boxed = map;
  const umbra::Vec3d o(data.scans.front().origin);
  const umbra::Vec3d half{options.region / 2, options.region / 2, options.region / 2};
  boxed.set_decay({options.occupied, options.free, umbra::Aabb{o - half, o + half}});
  std::vector<double> boxed_cpu;
  const std::vector<double> boxed_times = decay_steps(boxed, &boxed_cpu);
  std::printf("  decay step, %.1f m box: umbra median %.2f ms (first %.2f, last %.2f; CPU median %.2f)\n",
              options.region, umbra::bench::median(boxed_times) * 1e3, boxed_times.front() * 1e3,
              boxed_times.back() * 1e3, umbra::bench::median(boxed_cpu) * 1e3);

  stamped_scans(data, resolution, insert, options, umbra_insert, umbra_insert_cpu);

  // Reading: state() at random points of the scans' extent.
  umbra::Vec3d lo{1e30, 1e30, 1e30};
  umbra::Vec3d hi{-1e30, -1e30, -1e30};
  for (const umbra::Scan& scan : data.scans) {
    for (std::size_t i = 0; i < scan.points.size(); i += 97) {
      const umbra::Vec3f& p = scan.points[i];
      lo = {std::min(lo.x, double{p.x}), std::min(lo.y, double{p.y}), std::min(lo.z, double{p.z})};
      hi = {std::max(hi.x, double{p.x}), std::max(hi.y, double{p.y}), std::max(hi.z, double{p.z})};
    }
  }
  const auto query_ns = [&](const umbra::OccupancyMap& m) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(lo.x, hi.x), uy(lo.y, hi.y), uz(lo.z, hi.z);
    std::vector<umbra::Vec3d> points(1000000);
    for (umbra::Vec3d& p : points) p = {ux(rng), uy(rng), uz(rng)};
    std::vector<double> runs;
    std::size_t occupied = 0;
    for (int run = 0; run < 3; ++run) {
      const double cpu_start = cpu_seconds();
      for (const umbra::Vec3d& p : points) occupied += m.state(p) == umbra::OccupancyState::occupied;
      runs.push_back((cpu_seconds() - cpu_start) * 1e9 / static_cast<double>(points.size()));
    }
    return std::pair{umbra::bench::median(runs), occupied / 3};
  };
  const auto [plain_ns, plain_occupied] = query_ns(map);
  const auto [decayed_ns, decayed_occupied] = query_ns(whole);
  std::printf("  state() at 1 M random points, CPU median of 3: %.1f ns on the map without decay (%zu occupied), "
              "%.1f ns on the decayed map (%zu occupied)\n",
              plain_ns, plain_occupied, decayed_ns, decayed_occupied);
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    if (umbra::bench::take_dataset_flag(args, arg, options.data_dir, options.datasets)) continue;
    if (arg == "--steps") {
      options.steps = std::stoi(args.value());
    } else if (arg == "--dt") {
      options.dt = std::stod(args.value());
    } else if (arg == "--occupied") {
      options.occupied = std::stod(args.value());
    } else if (arg == "--free") {
      options.free = std::stod(args.value());
    } else if (arg == "--region") {
      options.region = std::stod(args.value());
    } else if (arg == "--stamped-only") {
      options.stamped_only = true;
    } else if (arg == "--threads") {
      options.threads = static_cast<unsigned>(std::stoul(args.value()));
    } else {
      std::cerr << "usage: umbra_decay_benchmark [--data DIR] [--datasets 3dtk,tum] [--steps N] [--dt S] "
                   "[--occupied R] [--free R] [--region M] [--threads N] [--stamped-only]\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  try {
    for (const std::string& name : options.datasets) run(name, options);
  } catch (const std::exception& e) {
    std::cerr << "umbra_decay_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
