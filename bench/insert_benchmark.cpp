// Insertion benchmark: umbra against liboctomap on the same scans, in one run.
//
// For every dataset and resolution, each method builds a fresh map from all
// scans of the dataset, in a forked child process so that every measurement
// starts from the same clean heap (OctoMap frees millions of small hash-set
// nodes after each scan, which would otherwise slow down whatever runs next)
// and so that the child's peak RSS is that method's alone. Repetitions
// interleave the methods; the median per-scan time is reported. Methods:
//   octomap-plain     OcTree::insertPointCloud(..., discretize = false)
//   octomap-discrete  OcTree::insertPointCloud(..., discretize = true)
//   umbra-simple      OccupancyMap::insert_point_cloud, IntegratorKind::simple
//   umbra-discrete    OccupancyMap::insert_point_cloud, IntegratorKind::discrete
// umbra-simple is compared with octomap-plain and umbra-discrete with
// octomap-discrete: the same semantics, voxel for voxel.
//
// Memory: OctoMap's memoryUsage() and umbra's memory_bytes() for the
// finished map, and the peak RSS growth of the child while inserting.
//
// Usage: umbra_insert_benchmark [--data DIR] [--res 0.05,0.02] [--repeat 3]
//          [--max-range 30] [--datasets scan.dat,3dtk] [--markdown FILE]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

struct Dataset {
  std::string name;
  std::vector<umbra::Scan> scans;
  std::vector<octomap::Pointcloud> clouds;  // the same points for OctoMap
};

enum class Method { octomap_plain, octomap_discrete, umbra_simple, umbra_discrete };
const Method kMethods[] = {Method::octomap_plain, Method::umbra_simple, Method::octomap_discrete,
                           Method::umbra_discrete};

const char* name_of(Method m) {
  switch (m) {
    case Method::octomap_plain: return "octomap-plain";
    case Method::octomap_discrete: return "octomap-discrete";
    case Method::umbra_simple: return "umbra-simple";
    case Method::umbra_discrete: return "umbra-discrete";
  }
  return "?";
}

/// What one child measured.
struct Measurement {
  static constexpr int kMaxScans = 64;
  int scans = 0;
  double scan_seconds[kMaxScans] = {};
  std::uint64_t map_bytes = 0;    // memoryUsage() / memory_bytes()
  std::uint64_t peak_rss_growth = 0;  // bytes, peak RSS minus RSS before inserting
  bool ok = false;
};

std::uint64_t current_rss_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0;
  std::uint64_t resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

std::uint64_t peak_rss_bytes() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
}

Measurement measure_in_this_process(const Dataset& data, Method method, double resolution, double max_range) {
  Measurement m;
  m.scans = static_cast<int>(std::min<std::size_t>(data.scans.size(), Measurement::kMaxScans));
  const std::uint64_t rss_before = current_rss_bytes();
  using Clock = std::chrono::steady_clock;
  if (method == Method::octomap_plain || method == Method::octomap_discrete) {
    octomap::OcTree tree(resolution);
    const bool discretize = method == Method::octomap_discrete;
    for (int i = 0; i < m.scans; ++i) {
      const umbra::Vec3f o = data.scans[i].origin;
      const auto start = Clock::now();
      tree.insertPointCloud(data.clouds[i], octomap::point3d(o.x, o.y, o.z), max_range, false, discretize);
      m.scan_seconds[i] = std::chrono::duration<double>(Clock::now() - start).count();
    }
    m.map_bytes = tree.memoryUsage();
  } else {
    umbra::OccupancyMap map(resolution);
    umbra::InsertOptions options;
    options.integrator =
        method == Method::umbra_discrete ? umbra::IntegratorKind::discrete : umbra::IntegratorKind::simple;
    options.max_range = max_range;
    for (int i = 0; i < m.scans; ++i) {
      const auto start = Clock::now();
      map.insert_point_cloud(data.scans[i].origin, data.scans[i].points, options);
      m.scan_seconds[i] = std::chrono::duration<double>(Clock::now() - start).count();
    }
    m.map_bytes = map.memory_bytes();
  }
  const std::uint64_t peak = peak_rss_bytes();
  m.peak_rss_growth = peak > rss_before ? peak - rss_before : 0;
  m.ok = true;
  return m;
}

Measurement measure_in_child(const Dataset& data, Method method, double resolution, double max_range) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  std::fflush(nullptr);
  const pid_t child = ::fork();
  if (child < 0) throw std::runtime_error("fork failed");
  if (child == 0) {
    ::close(fds[0]);
    Measurement m;
    try {
      m = measure_in_this_process(data, method, resolution, max_range);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s failed: %s\n", name_of(method), e.what());
    }
    const ssize_t written = ::write(fds[1], &m, sizeof m);
    ::_exit(written == static_cast<ssize_t>(sizeof m) ? 0 : 1);
  }
  ::close(fds[1]);
  Measurement m;
  std::size_t got = 0;
  while (got < sizeof m) {
    const ssize_t n = ::read(fds[0], reinterpret_cast<char*>(&m) + got, sizeof m - got);
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (got != sizeof m || !m.ok) throw std::runtime_error(std::string(name_of(method)) + ": child failed");
  return m;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

Dataset load(const std::string& name, const std::string& path) {
  Dataset data;
  data.name = name;
  const auto source = umbra::open_scan_source(path);
  umbra::Scan scan;
  while (source->next(scan)) {
    octomap::Pointcloud cloud;
    cloud.reserve(scan.points.size());
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    data.clouds.push_back(std::move(cloud));
    data.scans.push_back(scan);
  }
  return data;
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) parts.push_back(part);
  return parts;
}

std::string mib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data_dir = "../shared/data";
  std::string resolutions = "0.05,0.02";
  std::string datasets = "scan.dat,3dtk";
  std::string markdown_path;
  int repeat = 3;
  double max_range = 30.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--data") data_dir = value();
    else if (arg == "--res") resolutions = value();
    else if (arg == "--datasets") datasets = value();
    else if (arg == "--repeat") repeat = std::stoi(value());
    else if (arg == "--max-range") max_range = std::stod(value());
    else if (arg == "--markdown") markdown_path = value();
    else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/insert_benchmark.cpp)\n", arg.c_str());
      return 2;
    }
  }

  std::vector<Dataset> loaded;
  for (const std::string& name : split(datasets)) {
    const std::string path = name == "scan.dat" ? data_dir + "/octomap/scan.dat.bz2"
                             : name == "3dtk"   ? data_dir + "/3dtk/3dtk_registered.graph"
                                                : name;
    try {
      loaded.push_back(load(name, path));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cannot load %s: %s\n", name.c_str(), e.what());
      return 1;
    }
    std::size_t points = 0;
    for (const auto& s : loaded.back().scans) points += s.points.size();
    std::fprintf(stderr, "loaded %s: %zu scans, %zu points\n", name.c_str(), loaded.back().scans.size(), points);
  }

  std::ostringstream table;
  table << "| dataset | res (m) | semantics | OctoMap ms/scan | umbra ms/scan | speed-up | OctoMap memoryUsage (MiB) | "
           "umbra memory (MiB) | umbra/OctoMap memory | OctoMap peak RSS growth (MiB) | umbra peak RSS growth (MiB) |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Dataset& data : loaded) {
    for (const std::string& res_text : split(resolutions)) {
      const double resolution = std::stod(res_text);
      std::map<Method, std::vector<std::vector<double>>> times;  // method -> per scan -> repeats
      std::map<Method, Measurement> last;
      for (int r = 0; r < repeat; ++r) {
        for (const Method method : kMethods) {
          const Measurement m = measure_in_child(data, method, resolution, max_range);
          auto& per_scan = times[method];
          per_scan.resize(static_cast<std::size_t>(m.scans));
          double total = 0;
          for (int s = 0; s < m.scans; ++s) {
            per_scan[static_cast<std::size_t>(s)].push_back(m.scan_seconds[s]);
            total += m.scan_seconds[s];
          }
          last[method] = m;
          std::fprintf(stderr, "%s %s res %.3f run %d: %.3f s, map %s MiB, peak RSS growth %s MiB\n",
                       data.name.c_str(), name_of(method), resolution, r + 1, total, mib(m.map_bytes).c_str(),
                       mib(m.peak_rss_growth).c_str());
        }
      }
      auto ms_per_scan = [&](Method method) {
        double sum = 0;
        for (const auto& repeats : times[method]) sum += median(repeats);
        return 1e3 * sum / static_cast<double>(times[method].size());
      };
      const std::pair<Method, Method> pairs[] = {{Method::octomap_plain, Method::umbra_simple},
                                                 {Method::octomap_discrete, Method::umbra_discrete}};
      for (const auto& [octo, mine] : pairs) {
        const double octo_ms = ms_per_scan(octo);
        const double mine_ms = ms_per_scan(mine);
        char row[512];
        std::snprintf(row, sizeof row, "| %s | %.3g | %s | %.1f | %.1f | %.1fx | %s | %s | %.1f%% | %s | %s |\n",
                      data.name.c_str(), resolution,
                      octo == Method::octomap_plain ? "simple (discretize=false)" : "discrete (discretize=true)",
                      octo_ms, mine_ms, octo_ms / mine_ms, mib(last[octo].map_bytes).c_str(),
                      mib(last[mine].map_bytes).c_str(),
                      100.0 * static_cast<double>(last[mine].map_bytes) / static_cast<double>(last[octo].map_bytes),
                      mib(last[octo].peak_rss_growth).c_str(), mib(last[mine].peak_rss_growth).c_str());
        table << row;
        std::fputs(row, stderr);
      }
    }
  }
  std::printf("%s", table.str().c_str());
  if (!markdown_path.empty()) {
    std::ofstream out(markdown_path);
    out << table.str();
  }
  return 0;
}
