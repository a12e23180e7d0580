// Readers during insertion: what the concurrency contract costs.
//
// A writer thread inserts a dataset's scans into one map, in a loop; reader
// threads meanwhile run sphere collision checks (r = 0.25 m, unknown space
// blocking, centres drawn from the free voxels of the finished map with a
// fixed seed) as fast as they can, or at a fixed rate each. Reported, per
// dataset and setting:
//   - insertion time per scan alone and with the readers, and the slow-down.
//     Each setting runs --trials times as a pair (alone, then with readers,
//     each on a fresh map), and the slow-down is the median of the pairs'
//     ratios, so that load from other processes that comes and goes hits
//     both sides of a pair alike;
//   - the share of insertion time the map was closed to readers (the apply
//     phases: InsertStats::exclusive_seconds) and the longest such phase;
//   - reader latency (median, p99, max) and queries per second.
// Datasets (../shared/data): the TUM frames at 2 cm with the fast integrator
// (fine steps 0, max range 5 m) and the three 3DTK scans at 5 cm with the
// discrete integrator (max range 30 m).
//
// Usage: umbra_concurrency_benchmark [--data DIR] [--loops N] [--trials 3] [--readers 1,2]
//          [--rates 0,1000] [--datasets tum,3dtk]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Dataset {
  std::string name;
  std::string path;  // relative to --data
  double resolution;
  umbra::IntegratorKind integrator;
  int fine_steps;
  double max_range;
};

struct Options {
  std::string data = "../shared/data";
  int loops = 3;
  int trials = 3;
  std::vector<int> readers = {1, 2};
  std::vector<double> rates = {0.0, 1000.0};  // queries per second per reader; 0: flat out
  std::vector<std::string> datasets = {"tum", "3dtk"};
};

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) out.push_back(item);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--data") {
      o.data = value();
    } else if (arg == "--loops") {
      o.loops = std::stoi(value());
    } else if (arg == "--trials") {
      o.trials = std::stoi(value());
    } else if (arg == "--readers") {
      o.readers.clear();
      for (const std::string& v : split(value())) o.readers.push_back(std::stoi(v));
    } else if (arg == "--rates") {
      o.rates.clear();
      for (const std::string& v : split(value())) o.rates.push_back(std::stod(v));
    } else if (arg == "--datasets") {
      o.datasets = split(value());
    } else {
      throw std::invalid_argument("unknown argument " + arg + " (see the file comment)");
    }
  }
  return o;
}

struct WriterResult {
  double seconds = 0.0;
  double exclusive_seconds = 0.0;
  double longest_exclusive = 0.0;
  std::size_t scans = 0;
};

WriterResult insert_all(umbra::OccupancyMap& map, const std::vector<umbra::Scan>& scans, const Dataset& d, int loops) {
  umbra::InsertOptions options;
  options.integrator = d.integrator;
  options.fine_steps = d.fine_steps;
  options.max_range = d.max_range;
  options.threads = 1;
  WriterResult r;
  const auto start = Clock::now();
  for (int loop = 0; loop < loops; ++loop) {
    for (const umbra::Scan& scan : scans) {
      const umbra::InsertStats stats = map.insert_point_cloud(scan.origin, scan.points, options);
      r.exclusive_seconds += stats.exclusive_seconds;
      r.longest_exclusive = std::max(r.longest_exclusive, stats.exclusive_seconds);
      ++r.scans;
    }
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void run(const Dataset& d, const Options& o) {
  const auto source = umbra::open_scan_source(o.data + "/" + d.path);
  std::vector<umbra::Scan> scans;
  for (umbra::Scan scan; source->next(scan);) scans.push_back(scan);

  // Sphere centres: free voxels of the finished map.
  std::vector<umbra::Vec3d> centres;
  {
    umbra::OccupancyMap reference(d.resolution);
    insert_all(reference, scans, d, 1);
    std::vector<umbra::Vec3d> free_voxels;
    for (const umbra::Node& n : reference.query(umbra::pred::leaf() && umbra::pred::free())) {
      if (n.depth == 0) free_voxels.push_back(n.center);
    }
    std::mt19937 rng(42);
    std::uniform_int_distribution<std::size_t> pick(0, free_voxels.size() - 1);
    for (int i = 0; i < 100000; ++i) centres.push_back(free_voxels[pick(rng)]);
  }

  for (const int readers : o.readers) {
    for (const double rate : o.rates) {
      std::vector<double> ratios;
      std::vector<double> alone_ms;
      std::vector<double> with_ms;
      std::vector<double> all;  // every latency of every trial, in us
      WriterResult with_total;
      double reader_seconds = 0.0;
      for (int trial = 0; trial < o.trials; ++trial) {
        umbra::OccupancyMap alone_map(d.resolution);
        const WriterResult alone = insert_all(alone_map, scans, d, o.loops);
        umbra::OccupancyMap map(d.resolution);
        std::atomic<bool> stop{false};
        std::vector<std::vector<double>> latencies(static_cast<std::size_t>(readers));
        std::vector<std::thread> threads;
        for (int r = 0; r < readers; ++r) {
          threads.emplace_back([&, r] {
            std::vector<double>& mine = latencies[static_cast<std::size_t>(r)];
            mine.reserve(1 << 22);
            std::size_t i = static_cast<std::size_t>(r) * 7919;
            const auto period = rate > 0 ? std::chrono::duration<double>(1.0 / rate) : std::chrono::duration<double>(0);
            auto next = Clock::now();
            while (!stop.load(std::memory_order_relaxed)) {
              const umbra::Vec3d c = centres[i++ % centres.size()];
              const auto start = Clock::now();
              (void)map.is_free(umbra::Sphere{c, 0.25});
              const auto end = Clock::now();
              mine.push_back(std::chrono::duration<double, std::micro>(end - start).count());
              if (rate > 0) {
                next += std::chrono::duration_cast<Clock::duration>(period);
                std::this_thread::sleep_until(next);
              }
            }
          });
        }
        const WriterResult with = insert_all(map, scans, d, o.loops);
        stop.store(true);
        for (std::thread& t : threads) t.join();
        for (const auto& v : latencies) all.insert(all.end(), v.begin(), v.end());
        alone_ms.push_back(1e3 * alone.seconds / static_cast<double>(alone.scans));
        with_ms.push_back(1e3 * with.seconds / static_cast<double>(with.scans));
        ratios.push_back(with_ms.back() / alone_ms.back());
        with_total.seconds += with.seconds;
        with_total.exclusive_seconds += with.exclusive_seconds;
        with_total.longest_exclusive = std::max(with_total.longest_exclusive, with.longest_exclusive);
        reader_seconds += with.seconds;
      }
      const double qps = static_cast<double>(all.size()) / reader_seconds;
      const double p50 = percentile(all, 0.5);
      const double p99 = percentile(all, 0.99);
      const double max = all.empty() ? 0.0 : *std::max_element(all.begin(), all.end());
      char setting[64];
      std::snprintf(setting, sizeof setting, "%d reader%s, %s", readers, readers == 1 ? "" : "s",
                    rate > 0 ? (std::to_string(static_cast<int>(rate)) + " q/s each").c_str() : "flat out");
      std::printf("| %s | %s | %.1f%% | %.1f | %.1f | %.0f | %.1f%% | %.2f | %.2f | %.2f | %.0f | %.0f |\n",
                  d.name.c_str(), setting, 100.0 * (median(ratios) - 1.0), median(alone_ms), median(with_ms), qps,
                  100.0 * with_total.exclusive_seconds / with_total.seconds, 1e3 * with_total.longest_exclusive, p50,
                  p99, max, static_cast<double>(all.size()));
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    std::printf("| dataset | readers | insertion slow-down (median of pairs) | ms/scan alone | ms/scan with readers "
                "| queries/s | closed to readers | longest closed (ms) | p50 (us) | p99 (us) | max (us) | queries |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    const std::vector<Dataset> all = {
        {"TUM frames, 2 cm, fast n=0", "tum_fr2_pioneer_slam2", 0.02, umbra::IntegratorKind::fast, 0, 5.0},
        {"3DTK scans, 5 cm, discrete", "3dtk/3dtk_registered.graph", 0.05, umbra::IntegratorKind::discrete, 2, 30.0},
    };
    for (const std::string& name : o.datasets) {
      const Dataset& d = name == "tum" ? all[0] : all[1];
      run(d, o);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_concurrency_benchmark: %s\n", e.what());
    return 1;
  }
}
