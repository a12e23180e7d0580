// umbra's DistanceField against OctoMap's DynamicEDTOctomap (Debian
// libdynamicedt3d-dev) on the same maps, over the same box, side by side in
// one run (docs/benchmarks.md, "Distance field"):
//   - build: the field of the map after the first scan (dynamicEDT3D: its
//     constructor and first update());
//   - per-scan update: each further scan inserted into both maps, then
//     DistanceField::update() against DynamicEDTOctomap::update();
//   - queries: uniform random points in the box, umbra's batch
//     distance_and_gradient and single distance() calls (also cycling over
//     1,000 points, in cache) against getDistance() in a loop, one thread,
//     in thread CPU time;
//   - memory: DistanceField::memory_bytes() against dynamicEDT3D's arrays
//     (24-byte dataCell and a bool per cell), and the resident-set growth of
//     each;
//   - answers: on sample points, each library against a brute force of its
//     own metric over its own map (umbra: voxel centre to the nearest
//     blocking cube; dynamicEDT3D: centre to centre), and umbra's against
//     dynamicEDT3D's, with unknown as occupied (umbra's blocking distance)
//     and as free (umbra's occupied distance).
// Datasets: 3dtk (5 cm), tum (2 cm), geb079 (the .bt map, 8 cm, no scans).
//
//   umbra_field_benchmark [--data-dir ../shared/data] [--datasets 3dtk,tum,geb079]
//                         [--max-distance 1.0] [--queries 1000000] [--samples 2000]
//                         [--updates-only] [--threads N] [--fingerprint]
// --updates-only: umbra alone (no OctoMap tree, no dynamicEDT3D, no
// queries), each update's thread CPU time (and the process' CPU time and
// the wall time: with --threads N the serial share), so that two builds can be
// compared on a loaded machine; --threads sets DistanceFieldOptions::threads
// there; --fingerprint adds, after each update, a hash of the whole field
// (every cell of the box queried, the answers' bytes hashed): equal
// fingerprints, bit-identical fields.
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <octomap/OcTree.h>

#include "common/argument_cursor.hpp"
#include "bench_data.hpp"
#include "field_datasets.hpp"
#include "umbra/io/octomap_files.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/field/distance_field.hpp"

namespace {

using umbra::bench::field_dataset_box;
using umbra::bench::thread_cpu_seconds;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// CPU seconds of all the process' threads (an update's workers included).
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::size_t rss_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

struct Options {
  std::string data_dir = "../shared/data";
  std::vector<std::string> datasets{"3dtk", "tum", "geb079"};
  double max_distance = 1.0;
  std::size_t queries = 1000000;
  std::size_t samples = 2000;
  bool updates_only = false;
  bool fingerprint = false;
  unsigned threads = 1;
};

/// Cell states of the box for the brute forces (one byte per voxel).
struct DenseStates {
  umbra::Key min;
  int nx = 0, ny = 0, nz = 0;
  std::vector<std::uint8_t> umbra_state;   // 0 free, 1 occupied, 2 unknown
  std::vector<std::uint8_t> octomap_state;
  [[nodiscard]] std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * std::size_t(ny) + std::size_t(y)) * std::size_t(nx) + std::size_t(x);
  }
};

DenseStates dense_states(const umbra::OccupancyMap& map, const octomap::OcTree& tree, const umbra::Aabb& box) {
  DenseStates d;
  d.min = map.key(box.min);
  const umbra::Key max = map.key(box.max);
  d.nx = int(max.x - d.min.x) + 1;
  d.ny = int(max.y - d.min.y) + 1;
  d.nz = int(max.z - d.min.z) + 1;
  const std::size_t cells = std::size_t(d.nx) * std::size_t(d.ny) * std::size_t(d.nz);
  d.umbra_state.assign(cells, 2);
  d.octomap_state.assign(cells, 2);
  map.for_each_leaf([&](const umbra::Node& n) {
    if (n.state == umbra::OccupancyState::unknown) return;
    const std::uint8_t s = n.state == umbra::OccupancyState::occupied ? 1 : 0;
    const std::uint32_t size = 1u << n.depth;
    for (std::uint32_t z = n.key.z; z < n.key.z + size; ++z) {
      if (z < d.min.z || z > max.z) continue;
      for (std::uint32_t y = n.key.y; y < n.key.y + size; ++y) {
        if (y < d.min.y || y > max.y) continue;
        for (std::uint32_t x = n.key.x; x < n.key.x + size; ++x) {
          if (x < d.min.x || x > max.x) continue;
          d.umbra_state[d.index(int(x - d.min.x), int(y - d.min.y), int(z - d.min.z))] = s;
        }
      }
    }
  });
  // OctoMap keys equal umbra's for 16 depth levels (both offset by 2^15).
  for (auto it = tree.begin_leafs_bbx(octomap::point3d(float(box.min.x), float(box.min.y), float(box.min.z)),
                                      octomap::point3d(float(box.max.x), float(box.max.y), float(box.max.z)));
       it != tree.end_leafs_bbx(); ++it) {
    const std::uint8_t s = tree.isNodeOccupied(*it) ? 1 : 0;
    const octomap::OcTreeKey k = it.getKey();
    const int size = 1 << (16 - int(it.getDepth()));
    const std::uint32_t first[3] = {std::uint32_t(k[0]) & ~std::uint32_t(size - 1),
                                    std::uint32_t(k[1]) & ~std::uint32_t(size - 1),
                                    std::uint32_t(k[2]) & ~std::uint32_t(size - 1)};
    for (std::uint32_t z = first[2]; z < first[2] + std::uint32_t(size); ++z) {
      if (z < d.min.z || z > max.z) continue;
      for (std::uint32_t y = first[1]; y < first[1] + std::uint32_t(size); ++y) {
        if (y < d.min.y || y > max.y) continue;
        for (std::uint32_t x = first[0]; x < first[0] + std::uint32_t(size); ++x) {
          if (x < d.min.x || x > max.x) continue;
          d.octomap_state[d.index(int(x - d.min.x), int(y - d.min.y), int(z - d.min.z))] = s;
        }
      }
    }
  }
  return d;
}

/// Brute force of both metrics at one voxel: nearest site within `reach`
/// voxels, unknown counted as occupied or not, capped.
double brute_force(const DenseStates& d, const std::vector<std::uint8_t>& states, umbra::Key voxel, int reach,
                   bool unknown_blocks, bool centre_to_centre, double resolution, double cap) {
  const int cx = int(voxel.x - d.min.x), cy = int(voxel.y - d.min.y), cz = int(voxel.z - d.min.z);
  double best = cap * cap / (resolution * resolution);
  for (int z = std::max(0, cz - reach); z <= std::min(d.nz - 1, cz + reach); ++z) {
    for (int y = std::max(0, cy - reach); y <= std::min(d.ny - 1, cy + reach); ++y) {
      for (int x = std::max(0, cx - reach); x <= std::min(d.nx - 1, cx + reach); ++x) {
        const std::uint8_t s = states[d.index(x, y, z)];
        if (!(s == 1 || (s == 2 && unknown_blocks))) continue;
        const int off[3] = {x - cx, y - cy, z - cz};
        double sum = 0;
        for (int a : off) {
          const double g = centre_to_centre ? double(a) : std::max(0.0, std::abs(double(a)) - 0.5);
          sum += g * g;
        }
        best = std::min(best, sum);
      }
    }
  }
  return std::min(cap, std::sqrt(best) * resolution);
}

struct Row {
  std::string dataset;
  double resolution = 0;
  long long box_cells = 0;
  double umbra_build = 0, edt_build = 0;
  std::vector<double> umbra_updates, edt_updates, umbra_parallel_updates;
  // dynamicEDT3D with unknown as free: umbra's one update keeps both
  // distances, dynamicEDT3D needs a second field for the occupied one.
  std::vector<double> edt_free_updates;
  std::vector<double> umbra_update_cpu, edt_update_cpu, edt_free_update_cpu;  // thread CPU seconds
  double umbra_parallel_build = 0;
  unsigned threads = 1;
  double umbra_query_ns = 0, umbra_query_single_ns = 0, umbra_query_hot_ns = 0, edt_query_ns = 0;
  std::size_t umbra_bytes = 0, umbra_rss = 0, edt_bytes = 0, edt_rss = 0;
  std::size_t umbra_known_bytes = 0;
  double umbra_known_build = 0;
  std::size_t bricks_lowered = 0, bricks_transformed = 0;  // by all updates
};

void print_answers(const char* label, std::size_t n, std::size_t umbra_exact, double umbra_worst, std::size_t edt_exact,
                   double edt_worst, std::size_t agree, double worst_gap) {
  std::printf("  answers (%s), %zu points: umbra = its brute force %zu (max error %.2e m); dynamicEDT3D = its brute "
              "force %zu (max error %.3f m); umbra = dynamicEDT3D %zu, max |difference| %.3f m\n",
              label, n, umbra_exact, umbra_worst, edt_exact, edt_worst, agree, worst_gap);
}

Row run(const std::string& name, const Options& options) {
  Row row;
  row.dataset = name;
  std::vector<umbra::Scan> scans;
  double max_range = 30.0;
  std::unique_ptr<umbra::OccupancyMap> map;
  std::unique_ptr<octomap::OcTree> tree;
  // The same map again for dynamicEDT3D with unknown as free: its update()
  // consumes the tree's change set, so two fields cannot share one tree.
  std::unique_ptr<octomap::OcTree> tree_free;
  umbra::Aabb box;
  if (name == "geb079") {
    const std::string path = options.data_dir + "/octomap/geb079.bt";
    map = std::make_unique<umbra::OccupancyMap>(umbra::load_octomap(path));
    tree = std::make_unique<octomap::OcTree>(path);
    tree_free = std::make_unique<octomap::OcTree>(path);
    double x0, y0, z0, x1, y1, z1;
    tree->getMetricMin(x0, y0, z0);
    tree->getMetricMax(x1, y1, z1);
    box = {{x0 + 1e-3, y0 + 1e-3, z0 + 1e-3}, {x1 - 1e-3, y1 - 1e-3, z1 - 1e-3}};
  } else {
    umbra::bench::DatasetOptions data_options;
    data_options.data_dir = options.data_dir;
    umbra::bench::Dataset data = umbra::bench::load_dataset(name, data_options);
    scans = std::move(data.scans);
    max_range = data.max_range;
    const double resolution = name == "tum" ? 0.02 : 0.05;
    map = std::make_unique<umbra::OccupancyMap>(resolution);
    tree = std::make_unique<octomap::OcTree>(resolution);
    tree_free = std::make_unique<octomap::OcTree>(resolution);
    const umbra::Vec3d o(scans[0].origin);
    // A box around the first sensor position both fields can hold (dynamicEDT3D: dense).
    box = field_dataset_box(name, o);
  }
  row.resolution = map->resolution();
  umbra::InsertOptions insert;
  insert.max_range = max_range;
  const auto insert_scan = [&](const umbra::Scan& scan) {
    map->insert_point_cloud(scan.origin, scan.points, insert);
    octomap::Pointcloud cloud;
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    tree->insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), max_range, false,
                           false);
    tree_free->insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), max_range,
                                false, false);
  };
  if (!scans.empty()) insert_scan(scans[0]);

  const umbra::Key kmin = map->key(box.min), kmax = map->key(box.max);
  row.box_cells = static_cast<long long>(kmax.x - kmin.x + 1) * (kmax.y - kmin.y + 1) * (kmax.z - kmin.z + 1);
  const octomap::point3d bmin(float(box.min.x), float(box.min.y), float(box.min.z));
  const octomap::point3d bmax(float(box.max.x), float(box.max.y), float(box.max.z));

  // Build both (unknown as occupied for the timing rows, as a planner that
  // must not enter the unseen wants).
  umbra::DistanceFieldOptions field_options;
  field_options.max_distance = options.max_distance;
  field_options.box = box;
  ::malloc_trim(0);
  std::size_t rss = rss_bytes();
  auto start = Clock::now();
  auto field = std::make_unique<umbra::DistanceField>(*map, field_options);
  row.umbra_build = seconds_since(start);
  row.umbra_rss = rss_bytes() - rss;
  row.umbra_bytes = field->memory_bytes();
  ::malloc_trim(0);
  rss = rss_bytes();
  start = Clock::now();
  auto edt = std::make_unique<DynamicEDTOctomap>(float(options.max_distance), tree.get(), bmin, bmax, true);
  edt->update();
  row.edt_build = seconds_since(start);
  row.edt_rss = rss_bytes() - rss;
  auto edt_free = std::make_unique<DynamicEDTOctomap>(float(options.max_distance), tree_free.get(), bmin, bmax, false);
  edt_free->update();
  row.edt_bytes = std::size_t(row.box_cells) * (24 + 1);
  {
    umbra::DistanceFieldOptions known = field_options;
    known.box.reset();
    start = Clock::now();
    const umbra::DistanceField whole(*map, known);
    row.umbra_known_build = seconds_since(start);
    row.umbra_known_bytes = whole.memory_bytes();
  }

  // The same field built and updated by all hardware threads.
  umbra::DistanceFieldOptions parallel_options = field_options;
  parallel_options.threads = 0;
  start = Clock::now();
  umbra::DistanceField parallel(*map, parallel_options);
  row.umbra_parallel_build = seconds_since(start);
  row.threads = std::thread::hardware_concurrency();

  for (std::size_t i = 1; i < scans.size(); ++i) {
    insert_scan(scans[i]);
    start = Clock::now();
    double cpu = thread_cpu_seconds();
    field->update();
    row.umbra_update_cpu.push_back(thread_cpu_seconds() - cpu);
    row.umbra_updates.push_back(seconds_since(start));
    const umbra::DistanceFieldStats st = field->stats();
    row.bricks_lowered += st.bricks_recomputed - st.bricks_transformed;
    row.bricks_transformed += st.bricks_transformed;
    start = Clock::now();
    parallel.update();
    row.umbra_parallel_updates.push_back(seconds_since(start));
    start = Clock::now();
    cpu = thread_cpu_seconds();
    edt->update();
    row.edt_update_cpu.push_back(thread_cpu_seconds() - cpu);
    row.edt_updates.push_back(seconds_since(start));
    start = Clock::now();
    cpu = thread_cpu_seconds();
    edt_free->update();
    row.edt_free_update_cpu.push_back(thread_cpu_seconds() - cpu);
    row.edt_free_updates.push_back(seconds_since(start));
  }

  if (scans.size() > 1) {
    const auto median_ms = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return 1e3 * v[v.size() / 2];
    };
    std::printf("%s: update per scan, median ms: umbra %.1f (1 thread), %.1f (%u threads); dynamicEDT3D %.1f "
                "(unknown as occupied), %.1f (unknown as free)\n",
                name.c_str(), median_ms(row.umbra_updates), median_ms(row.umbra_parallel_updates),
                std::thread::hardware_concurrency(), median_ms(row.edt_updates), median_ms(row.edt_free_updates));
    std::printf("%s: update per scan, median thread CPU ms: umbra %.1f (1 thread); dynamicEDT3D %.1f (unknown as "
                "occupied), %.1f (unknown as free); speed-up %.2fx (against unknown as occupied), %.2fx (against "
                "both)\n",
                name.c_str(), median_ms(row.umbra_update_cpu), median_ms(row.edt_update_cpu),
                median_ms(row.edt_free_update_cpu), median_ms(row.edt_update_cpu) / median_ms(row.umbra_update_cpu),
                (median_ms(row.edt_update_cpu) + median_ms(row.edt_free_update_cpu)) / median_ms(row.umbra_update_cpu));
    std::printf("%s: updates lowered %.0f and transformed %.0f bricks a scan (of %zu stored)\n", name.c_str(),
                double(row.bricks_lowered) / double(scans.size() - 1),
                double(row.bricks_transformed) / double(scans.size() - 1), field->stats().bricks);
  }

  // Queries.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(box.min.x, box.max.x), uy(box.min.y, box.max.y), uz(box.min.z, box.max.z);
  std::vector<umbra::Vec3d> points(options.queries);
  for (umbra::Vec3d& p : points) p = {ux(rng), uy(rng), uz(rng)};
  std::vector<umbra::DistanceSample> samples(points.size());
  // Thread CPU time: on a shared machine steadier than the wall clock.
  double cpu_start = 0;
  cpu_start = thread_cpu_seconds();
  field->distance_and_gradient(points, samples);
  row.umbra_query_ns = (thread_cpu_seconds() - cpu_start) * 1e9 / double(points.size());
  double sink = 0;
  cpu_start = thread_cpu_seconds();
  for (const umbra::Vec3d& p : points) sink += field->distance(p);
  row.umbra_query_single_ns = (thread_cpu_seconds() - cpu_start) * 1e9 / double(points.size());
  // The same single calls cycling over 1,000 points (their bricks stay in
  // cache): the call's own cost (read gate, lookup, arithmetic) without the
  // memory latency of a random point.
  const std::size_t hot = std::min<std::size_t>(1000, points.size());
  cpu_start = thread_cpu_seconds();
  for (std::size_t i = 0; i < points.size(); ++i) sink += field->distance(points[i % hot]);
  row.umbra_query_hot_ns = (thread_cpu_seconds() - cpu_start) * 1e9 / double(points.size());
  std::vector<octomap::point3d> octo_points;
  octo_points.reserve(points.size());
  for (const umbra::Vec3d& p : points) octo_points.emplace_back(float(p.x), float(p.y), float(p.z));
  cpu_start = thread_cpu_seconds();
  for (const octomap::point3d& p : octo_points) sink += edt->getDistance(p);
  row.edt_query_ns = (thread_cpu_seconds() - cpu_start) * 1e9 / double(points.size());
  if (sink == 42.0) std::printf(" ");

  std::printf("%s: resolution %.2f m, box (%.2f %.2f %.2f)-(%.2f %.2f %.2f), %lld cells, max distance %.2f m\n",
              name.c_str(), row.resolution, box.min.x, box.min.y, box.min.z, box.max.x, box.max.y, box.max.z,
              row.box_cells, options.max_distance);

  // Answers on sample points (the float points dynamicEDT3D gets, so both
  // look at the same voxel).
  const DenseStates dense = dense_states(*map, *tree, box);
  const int reach = int(std::ceil(options.max_distance / row.resolution)) + 1;
  const std::size_t n = std::min(options.samples, points.size());
  for (const bool unknown_blocks : {true, false}) {
    DynamicEDTOctomap& e = unknown_blocks ? *edt : *edt_free;
    std::size_t umbra_exact = 0, edt_exact = 0, agree = 0;
    double umbra_worst = 0, edt_worst = 0, worst_gap = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const octomap::point3d& q = octo_points[i];
      const umbra::Vec3d p(q.x(), q.y(), q.z());
      const umbra::Key voxel = map->key(p);
      const umbra::DistanceSample s = field->distance_and_gradient(p);
      const double mine = unknown_blocks ? s.blocking() : s.occupied;
      const double theirs = std::min<double>(e.getDistance(q), options.max_distance);
      const double mine_brute =
          brute_force(dense, dense.umbra_state, voxel, reach, unknown_blocks, false, row.resolution, options.max_distance);
      const double theirs_brute = brute_force(dense, dense.octomap_state, voxel, reach, unknown_blocks, true,
                                              row.resolution, options.max_distance);
      umbra_exact += std::abs(mine - mine_brute) < 1e-9;
      umbra_worst = std::max(umbra_worst, std::abs(mine - mine_brute));
      edt_exact += std::abs(theirs - theirs_brute) < 1e-4;
      edt_worst = std::max(edt_worst, std::abs(theirs - theirs_brute));
      agree += std::abs(mine - theirs) < 1e-4;
      worst_gap = std::max(worst_gap, std::abs(mine - theirs));
    }
    print_answers(unknown_blocks ? "unknown as occupied" : "unknown as free", n, umbra_exact, umbra_worst, edt_exact,
                  edt_worst, agree, worst_gap);
  }
  return row;
}

/// FNV-1a over the answers (both distances and the gradient, as bytes) at
/// every cell centre of the box: equal fingerprints, equal fields.
std::uint64_t field_fingerprint(const umbra::DistanceField& field, const umbra::OccupancyMap& map,
                                const umbra::Aabb& box) {
  const umbra::Key lo = map.key(box.min), hi = map.key(box.max);
  std::vector<umbra::Vec3d> points;
  std::vector<umbra::DistanceSample> answers;
  std::uint64_t hash = 1469598103934665603ull;
  for (std::uint32_t z = lo.z; z <= hi.z; ++z) {
    points.clear();
    for (std::uint32_t y = lo.y; y <= hi.y; ++y) {
      for (std::uint32_t x = lo.x; x <= hi.x; ++x) points.push_back(map.grid().center(umbra::Key{x, y, z}));
    }
    answers.resize(points.size());
    field.distance_and_gradient(points, answers);
    for (const umbra::DistanceSample& a : answers) {
      const double v[5] = {a.occupied, a.unknown, a.gradient.x, a.gradient.y, a.gradient.z};
      const auto* bytes = reinterpret_cast<const unsigned char*>(v);
      for (std::size_t i = 0; i < sizeof(v); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
    }
  }
  return hash;
}

/// --updates-only: umbra's per-scan update alone (see the file comment).
void run_updates_only(const std::string& name, const Options& options) {
  umbra::bench::DatasetOptions data_options;
  data_options.data_dir = options.data_dir;
  const umbra::bench::Dataset data = umbra::bench::load_dataset(name, data_options);
  umbra::OccupancyMap map(name == "tum" ? 0.02 : 0.05);
  umbra::InsertOptions insert;
  insert.max_range = data.max_range;
  map.insert_point_cloud(data.scans[0].origin, data.scans[0].points, insert);
  umbra::DistanceFieldOptions field_options;
  field_options.max_distance = options.max_distance;
  field_options.box = field_dataset_box(name, umbra::Vec3d(data.scans[0].origin));
  field_options.threads = options.threads;
  umbra::DistanceField field(map, field_options);
  std::vector<double> cpu_ms;
  for (std::size_t i = 1; i < data.scans.size(); ++i) {
    map.insert_point_cloud(data.scans[i].origin, data.scans[i].points, insert);
    const double cpu = thread_cpu_seconds();
    const double process_cpu = process_cpu_seconds();
    const auto start = Clock::now();
    field.update();
    cpu_ms.push_back(1e3 * (thread_cpu_seconds() - cpu));
    const double process_ms = 1e3 * (process_cpu_seconds() - process_cpu);
    const double wall_ms = 1e3 * seconds_since(start);
    const umbra::DistanceFieldStats st = field.stats();
    // With N threads the calling thread runs the serial part and about 1/N
    // of the parallel one, so serial ~ (N thread CPU - process CPU) / (N - 1),
    // whatever the machine's load (CPU time, not wall).
    std::printf("%s update %zu: %.1f ms thread CPU, %.1f ms process CPU, %.1f ms wall, bricks lowered %zu transformed %zu",
                name.c_str(), i, cpu_ms.back(), process_ms, wall_ms, st.bricks_recomputed - st.bricks_transformed,
                st.bricks_transformed);
    if (options.fingerprint) {
      std::printf(", fingerprint %016llx",
                  static_cast<unsigned long long>(field_fingerprint(field, map, *field_options.box)));
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("%s: update median %.1f ms thread CPU (%u threads)\n", name.c_str(), umbra::bench::median(cpu_ms),
              options.threads);
}

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    if (umbra::bench::take_dataset_flag(args, arg, options.data_dir, options.datasets)) continue;
    if (arg == "--max-distance") {
      options.max_distance = std::stod(args.value());
    } else if (arg == "--queries") {
      options.queries = std::stoul(args.value());
    } else if (arg == "--samples") {
      options.samples = std::stoul(args.value());
    } else if (arg == "--updates-only") {
      options.updates_only = true;
    } else if (arg == "--fingerprint") {
      options.fingerprint = true;
    } else if (arg == "--threads") {
      options.threads = unsigned(std::stoul(args.value()));
    } else {
      std::cerr << "usage: umbra_field_benchmark [--data DIR] [--datasets 3dtk,tum,geb079] [--max-distance M]"
                   " [--queries N] [--samples N] [--updates-only] [--threads N] [--fingerprint]\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  if (options.updates_only) {
    for (const std::string& name : options.datasets) run_updates_only(name, options);
    return 0;
  }
  std::vector<Row> rows;
  for (const std::string& name : options.datasets) {
    rows.push_back(run(name, options));
    std::fflush(stdout);
  }
  std::printf("\n| dataset | box cells | build umbra / dynamicEDT3D (s) | update per scan umbra / dynamicEDT3D (ms) | "
              "speed-up | query umbra batch / single / single in cache / dynamicEDT3D (ns) | memory umbra / dynamicEDT3D (MB) | "
              "umbra without box: build (s), memory (MB) | umbra on all threads: build (s), update (ms) |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const double uu = r.umbra_updates.empty() ? 0 : 1e3 * sum(r.umbra_updates) / double(r.umbra_updates.size());
    const double eu = r.edt_updates.empty() ? 0 : 1e3 * sum(r.edt_updates) / double(r.edt_updates.size());
    std::printf("| %s (%.2f m) | %lld | %.3f / %.3f | %s | %s | %.1f / %.1f / %.1f / %.1f | %.1f (rss %.1f) / %.1f (rss %.1f) "
                "| %.3f, %.1f | %u threads: %.3f, %.1f |\n",
                r.dataset.c_str(), r.resolution, r.box_cells, r.umbra_build, r.edt_build,
                r.umbra_updates.empty() ? "-" : (std::to_string(uu).substr(0, 7) + " / " + std::to_string(eu).substr(0, 7)).c_str(),
                r.umbra_updates.empty() ? "-" : (std::to_string(eu / uu).substr(0, 5) + "x").c_str(), r.umbra_query_ns,
                r.umbra_query_single_ns, r.umbra_query_hot_ns, r.edt_query_ns, double(r.umbra_bytes) / 1e6, double(r.umbra_rss) / 1e6,
                double(r.edt_bytes) / 1e6, double(r.edt_rss) / 1e6, r.umbra_known_build,
                double(r.umbra_known_bytes) / 1e6, r.threads, r.umbra_parallel_build,
                r.umbra_parallel_updates.empty()
                    ? 0.0
                    : 1e3 * sum(r.umbra_parallel_updates) / double(r.umbra_parallel_updates.size()));
  }
  return 0;
}
