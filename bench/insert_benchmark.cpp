// Insertion benchmark: umbra's integrators against liboctomap on the same
// scans, in one run.
//
// For every dataset, resolution and thread count, each method builds a fresh
// map from all scans of the dataset, in a forked child process so that every
// measurement starts from the same clean heap (OctoMap frees millions of
// small hash-set nodes after each scan, which would otherwise slow down
// whatever runs next) and so that the child's peak RSS is that method's
// alone. Repetitions interleave the methods; the median per-scan time is
// reported. Methods:
//   octomap-plain     OcTree::insertPointCloud(..., discretize = false)
//   octomap-discrete  OcTree::insertPointCloud(..., discretize = true)
//   umbra-simple      IntegratorKind::simple   (same voxels as octomap-plain)
//   umbra-discrete    IntegratorKind::discrete (same voxels as octomap-discrete)
//   umbra-fast-n2     IntegratorKind::fast, fine_steps 2, clear depth at 16 cm
//   umbra-fast-n0     IntegratorKind::fast, fine_steps 0, clear depth at 16 cm
//   umbra-projective  IntegratorKind::projective: depth images as images
//                     (OccupancyMap::insert_depth_image; TUM, sim-camera),
//                     other scans binned into range images
// Each umbra method is compared with the OctoMap method of its semantics:
// simple with octomap-plain, the others with octomap-discrete. OctoMap runs
// single-threaded whatever --threads says.
//
// Time is wall-clock time per scan. The CPU columns add the child's CPU time
// per scan (all its threads): on a machine shared with other jobs a process
// waits for a core some of the time, which counts in the wall-clock figure but
// not in the CPU one, so with one thread the CPU ratio is the steadier one.
//
// Memory: OctoMap's memoryUsage() and umbra's memory_bytes() for the
// finished map, and the peak RSS growth of the child while inserting.
//
// Usage: umbra_insert_benchmark [--data DIR] [--datasets scan.dat,3dtk,tum,sim-camera]
//          [--res 0.05,0.02] [--methods LIST] [--threads 1,2] [--repeat 3]
//          [--max-range 30] [--tum-max-range 5] [--color] [--serial-share] [--markdown FILE]
//
// --serial-share adds a table of where the CPU time of the umbra methods goes
// (umbra::job_cpu_times(): the pools' jobs counted per worker): the serial
// part (CPU time outside the jobs), its share s of the run's CPU time and
// Amdahl's bound on two threads 1 / (s + (1 - s) / 2); and the critical
// path, serial + the busiest worker of each job, with its bound CPU time /
// critical path (which also counts uneven jobs). Both within one run: the
// one-thread run is another process under another load. CPU times are
// steadier than wall-clock ratios on a machine shared with other work. But
// on a loaded machine the busiest worker is busiest partly because the
// other was preempted (the pool hands the running worker more tasks), so
// the table also gives the scheduled path: serial + each job's tasks
// scheduled on the pool's workers from their CPU times as if nothing else
// ran (JobCpuTimes::scheduled_seconds), and the one-thread run's CPU time
// over it (the speed-up an idle machine would show, cache and memory
// contention between the workers included, wake-ups not).
#include <malloc.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "bench_data.hpp"
#include "common/argument_cursor.hpp"
#include "common/sweep_flags.hpp"
#include "umbra/core/job_cpu_times.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using umbra::bench::median;
using umbra::bench::split_list;

struct Dataset : umbra::bench::Dataset {
  std::vector<octomap::Pointcloud> clouds;  // the same points for OctoMap
};

struct Method {
  std::string name;
  bool octomap = false;
  bool discretize = false;          // OctoMap
  umbra::IntegratorKind kind{};     // umbra
  int fine_steps = 0;               // umbra fast
  std::string counterpart;          // the OctoMap method with the same semantics
};

const std::vector<Method> kAllMethods = {
    {"octomap-plain", true, false, {}, 0, ""},
    {"octomap-discrete", true, true, {}, 0, ""},
    {"umbra-simple", false, false, umbra::IntegratorKind::simple, 0, "octomap-plain"},
    {"umbra-discrete", false, false, umbra::IntegratorKind::discrete, 0, "octomap-discrete"},
    {"umbra-fast-n2", false, false, umbra::IntegratorKind::fast, 2, "octomap-discrete"},
    {"umbra-fast-n0", false, false, umbra::IntegratorKind::fast, 0, "octomap-discrete"},
    {"umbra-projective", false, false, umbra::IntegratorKind::projective, 0, "octomap-discrete"},
};

/// What one child measured.
struct Measurement {
  static constexpr int kMaxScans = 64;
  int scans = 0;
  double scan_seconds[kMaxScans] = {};
  double scan_cpu_seconds[kMaxScans] = {};  // CPU time of the process (all threads)
  double scan_job_seconds[kMaxScans] = {};      // --serial-share: CPU time in the pools' jobs
  double scan_busiest_seconds[kMaxScans] = {};  // --serial-share: per job the busiest worker's, summed
  double scan_scheduled_seconds[kMaxScans] = {};  // --serial-share: per job its tasks scheduled, summed
  std::uint64_t map_bytes = 0;        // memoryUsage() / memory_bytes()
  std::uint64_t peak_rss_growth = 0;  // bytes, peak RSS minus RSS before inserting
  bool ok = false;
};

/// CPU time this process has used so far (all its threads), in seconds.
double process_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::uint64_t current_rss_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0;
  std::uint64_t resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

/// Resets the kernel's peak-RSS mark to the current RSS (Linux >= 4.0), so
/// that the peak read later is this measurement's and not the parent's.
void reset_peak_rss() {
  std::ofstream clear_refs("/proc/self/clear_refs");
  clear_refs << "5";
  if (!clear_refs.flush()) throw std::runtime_error("cannot reset the peak RSS through /proc/self/clear_refs");
}

/// VmHWM of /proc/self/status: the peak RSS since reset_peak_rss().
std::uint64_t peak_rss_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;  // "VmHWM:   1234 kB"
  }
  throw std::runtime_error("no VmHWM in /proc/self/status");
}

Measurement measure_in_this_process(const Dataset& data, const Method& method, double resolution, unsigned threads,
                                    bool color, bool serial_share) {
  Measurement m;
  if (serial_share) umbra::set_job_cpu_accounting(true);
  m.scans = static_cast<int>(std::min<std::size_t>(data.scans.size(), Measurement::kMaxScans));
  // Hand the heap the parent freed (parsing buffers) back to the system, or
  // the child reuses those resident pages and its growth reads near zero.
  ::malloc_trim(0);
  reset_peak_rss();
  const std::uint64_t rss_before = current_rss_bytes();
  using Clock = std::chrono::steady_clock;
  if (method.octomap) {
    octomap::OcTree tree(resolution);
    for (int i = 0; i < m.scans; ++i) {
      const umbra::Vec3f o = data.scans[i].origin;
      const auto start = Clock::now();
      const double cpu_start = process_cpu_seconds();
      tree.insertPointCloud(data.clouds[i], octomap::point3d(o.x, o.y, o.z), data.max_range, false,
                            method.discretize);
      m.scan_seconds[i] = std::chrono::duration<double>(Clock::now() - start).count();
      m.scan_cpu_seconds[i] = process_cpu_seconds() - cpu_start;
    }
    m.map_bytes = tree.memoryUsage();
  } else {
    umbra::MapConfig config;
    config.resolution = resolution;
    config.color = color;
    umbra::OccupancyMap map(config);
    umbra::InsertOptions options;
    options.integrator = method.kind;
    options.fine_steps = method.fine_steps;
    options.max_range = data.max_range;
    options.threads = threads;
    for (int i = 0; i < m.scans; ++i) {
      const umbra::Scan& scan = data.scans[i];
      const auto start = Clock::now();
      const double cpu_start = process_cpu_seconds();
      const umbra::JobCpuTimes jobs_start = umbra::job_cpu_times();
      if (method.kind == umbra::IntegratorKind::projective && scan.image) {
        const umbra::ScanImage& image = *scan.image;
        map.insert_depth_image(image.view(), image.camera, image.pose,
                               color ? std::span<const umbra::Rgb>(image.colors) : std::span<const umbra::Rgb>(),
                               options);
      } else if (color && !scan.colors.empty()) {
        map.insert_point_cloud(scan.origin, scan.points, scan.colors, options);
      } else {
        map.insert_point_cloud(scan.origin, scan.points, options);
      }
      m.scan_seconds[i] = std::chrono::duration<double>(Clock::now() - start).count();
      m.scan_cpu_seconds[i] = process_cpu_seconds() - cpu_start;
      const umbra::JobCpuTimes jobs_end = umbra::job_cpu_times();
      // The pools' spinning waits are neither jobs nor serial work: counted with the jobs, so that
      // the serial part stays the work outside them (the CPU columns keep the spin).
      m.scan_job_seconds[i] = jobs_end.all_seconds - jobs_start.all_seconds +
                              (jobs_end.waiting_seconds - jobs_start.waiting_seconds);
      m.scan_busiest_seconds[i] = jobs_end.busiest_seconds - jobs_start.busiest_seconds;
      m.scan_scheduled_seconds[i] = jobs_end.scheduled_seconds - jobs_start.scheduled_seconds;
    }
    m.map_bytes = map.memory_bytes();
  }
  const std::uint64_t peak = peak_rss_bytes();
  m.peak_rss_growth = peak > rss_before ? peak - rss_before : 0;
  m.ok = true;
  return m;
}

Measurement measure_in_child(const Dataset& data, const Method& method, double resolution, unsigned threads,
                             bool color, bool serial_share) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  std::fflush(nullptr);
  const pid_t child = ::fork();
  if (child < 0) throw std::runtime_error("fork failed");
  if (child == 0) {
    ::close(fds[0]);
    Measurement m;
    try {
      m = measure_in_this_process(data, method, resolution, threads, color, serial_share);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s failed: %s\n", method.name.c_str(), e.what());
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
  if (got != sizeof m || !m.ok) throw std::runtime_error(method.name + ": child failed");
  return m;
}

Dataset load(const std::string& name, const umbra::bench::DatasetOptions& options) {
  Dataset data;
  static_cast<umbra::bench::Dataset&>(data) = umbra::bench::load_dataset(name, options);
  for (const umbra::Scan& scan : data.scans) {
    octomap::Pointcloud cloud;
    cloud.reserve(scan.points.size());
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    data.clouds.push_back(std::move(cloud));
  }
  return data;
}

std::string mib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return text;
}

struct Result {
  double ms_per_scan = 0.0;
  double cpu_ms_per_scan = 0.0;
  double serial_ms_per_scan = 0.0;    // --serial-share: CPU time outside the pools' jobs
  double critical_ms_per_scan = 0.0;  // --serial-share: serial + the busiest worker of each job
  double scheduled_ms_per_scan = 0.0;  // --serial-share: serial + each job's tasks scheduled
  Measurement last;
};

}  // namespace

int main(int argc, char** argv) {
  umbra_bench::SweepFlags sweep;
  sweep.datasets = "scan.dat,3dtk";
  sweep.methods = "octomap-plain,umbra-simple,octomap-discrete,umbra-discrete";
  bool color = false;
  bool serial_share = false;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    if (sweep.take(arg, args)) continue;
    if (arg == "--color") color = true;
    else if (arg == "--serial-share") serial_share = true;
    else if (arg == "--help" || arg == "-h") {
      std::printf(
          "usage: umbra_insert_benchmark [--data DIR] [--datasets scan.dat,3dtk,tum,sim-camera] [--res 0.05,0.02]\n"
          "         [--methods LIST] [--threads 1,2] [--repeat 3] [--max-range 30] [--tum-max-range 5]\n"
          "         [--color] [--serial-share] [--markdown FILE]\n"
          "methods:");
      for (const Method& m : kAllMethods) std::printf(" %s", m.name.c_str());
      std::printf("\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/insert_benchmark.cpp)\n", arg.c_str());
      return 2;
    }
  }
  std::vector<Method> methods;
  for (const std::string& name : split_list(sweep.methods)) {
    const auto it = std::find_if(kAllMethods.begin(), kAllMethods.end(), [&](const Method& m) { return m.name == name; });
    if (it == kAllMethods.end()) {
      std::fprintf(stderr, "unknown method %s\n", name.c_str());
      return 2;
    }
    methods.push_back(*it);
  }

  std::vector<Dataset> loaded;
  for (const std::string& name : split_list(sweep.datasets)) {
    try {
      loaded.push_back(load(name, sweep.data));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cannot load %s: %s\n", name.c_str(), e.what());
      return 1;
    }
    std::size_t points = 0;
    for (const auto& s : loaded.back().scans) points += s.points.size();
    std::fprintf(stderr, "loaded %s: %zu scans, %zu points, max range %g m\n", name.c_str(), loaded.back().scans.size(),
                 points, loaded.back().max_range);
  }

  std::ostringstream table;
  table << "| dataset | res (m) | threads | method | ms/scan | scans/s | speed-up vs OctoMap | map (MiB) | "
           "map vs OctoMap | peak RSS growth (MiB) | CPU ms/scan | CPU speed-up |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::ostringstream share_table;
  share_table << "| dataset | res (m) | threads | method | CPU ms/scan | serial CPU ms/scan | serial share s | "
                 "Amdahl bound, 2 threads | critical path ms/scan | CPU / critical path | scheduled path ms/scan | "
                 "one-thread CPU / scheduled path |\n"
              << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Dataset& data : loaded) {
    for (const std::string& res_text : split_list(sweep.resolutions)) {
      const double resolution = std::stod(res_text);
      std::map<std::string, Result> octomap_results;
      std::map<std::string, double> one_thread_cpu;  // --serial-share: method -> CPU ms/scan on one thread
      for (const std::string& threads_text : split_list(sweep.threads)) {
        const unsigned threads = static_cast<unsigned>(std::stoul(threads_text));
        std::map<std::string, std::vector<std::vector<double>>> times;  // method -> scan -> repeats
        std::map<std::string, std::vector<std::vector<double>>> cpu_times;
        std::map<std::string, std::vector<std::vector<double>>> serial_times;
        std::map<std::string, std::vector<std::vector<double>>> critical_times;
        std::map<std::string, std::vector<std::vector<double>>> scheduled_times;
        std::map<std::string, Measurement> last;
        for (int r = 0; r < sweep.repeat; ++r) {
          for (const Method& method : methods) {
            if (method.octomap && octomap_results.count(method.name)) continue;  // OctoMap: once
            const Measurement m = measure_in_child(data, method, resolution, threads, color, serial_share);
            auto& per_scan = times[method.name];
            per_scan.resize(static_cast<std::size_t>(m.scans));
            auto& cpu_per_scan = cpu_times[method.name];
            cpu_per_scan.resize(static_cast<std::size_t>(m.scans));
            auto& serial_per_scan = serial_times[method.name];
            serial_per_scan.resize(static_cast<std::size_t>(m.scans));
            auto& critical_per_scan = critical_times[method.name];
            critical_per_scan.resize(static_cast<std::size_t>(m.scans));
            auto& scheduled_per_scan = scheduled_times[method.name];
            scheduled_per_scan.resize(static_cast<std::size_t>(m.scans));
            double total = 0;
            for (int s = 0; s < m.scans; ++s) {
              per_scan[static_cast<std::size_t>(s)].push_back(m.scan_seconds[s]);
              cpu_per_scan[static_cast<std::size_t>(s)].push_back(m.scan_cpu_seconds[s]);
              const double serial = m.scan_cpu_seconds[s] - m.scan_job_seconds[s];
              serial_per_scan[static_cast<std::size_t>(s)].push_back(serial);
              critical_per_scan[static_cast<std::size_t>(s)].push_back(serial + m.scan_busiest_seconds[s]);
              scheduled_per_scan[static_cast<std::size_t>(s)].push_back(serial + m.scan_scheduled_seconds[s]);
              total += m.scan_seconds[s];
            }
            last[method.name] = m;
            std::fprintf(stderr, "%s res %.3f %s threads %u run %d: %.3f s, map %s MiB, peak RSS growth %s MiB\n",
                         data.name.c_str(), resolution, method.name.c_str(), threads, r + 1, total,
                         mib(m.map_bytes).c_str(), mib(m.peak_rss_growth).c_str());
          }
        }
        std::map<std::string, Result> results = octomap_results;
        for (const auto& [name, per_scan] : times) {
          double sum = 0;
          for (const auto& repeats : per_scan) sum += median(repeats);
          double cpu_sum = 0;
          for (const auto& repeats : cpu_times[name]) cpu_sum += median(repeats);
          double serial_sum = 0;
          for (const auto& repeats : serial_times[name]) serial_sum += median(repeats);
          double critical_sum = 0;
          for (const auto& repeats : critical_times[name]) critical_sum += median(repeats);
          double scheduled_sum = 0;
          for (const auto& repeats : scheduled_times[name]) scheduled_sum += median(repeats);
          const auto scans = static_cast<double>(per_scan.size());
          results[name] = {1e3 * sum / scans, 1e3 * cpu_sum / scans, 1e3 * serial_sum / scans,
                           1e3 * critical_sum / scans, 1e3 * scheduled_sum / scans, last[name]};
          if (threads == 1) one_thread_cpu[name] = 1e3 * cpu_sum / scans;
        }
        for (const Method& method : methods) {
          if (method.octomap) octomap_results[method.name] = results[method.name];
        }
        for (const Method& method : methods) {
          const Result& mine = results[method.name];
          std::string speedup = "-";
          std::string memory_ratio = "-";
          std::string cpu_speedup = "-";
          if (!method.octomap && results.count(method.counterpart)) {
            const Result& theirs = results[method.counterpart];
            char text[64];
            std::snprintf(text, sizeof text, "%.1fx", theirs.ms_per_scan / mine.ms_per_scan);
            speedup = text;
            std::snprintf(text, sizeof text, "%.1fx", theirs.cpu_ms_per_scan / mine.cpu_ms_per_scan);
            cpu_speedup = text;
            std::snprintf(text, sizeof text, "%.1f%%",
                          100.0 * static_cast<double>(mine.last.map_bytes) / static_cast<double>(theirs.last.map_bytes));
            memory_ratio = text;
          }
          char row[512];
          std::snprintf(row, sizeof row, "| %s | %.3g | %s | %s | %.1f | %.2f | %s | %s | %s | %s | %.1f | %s |\n",
                        data.name.c_str(), resolution, method.octomap ? "1" : threads_text.c_str(),
                        method.name.c_str(), mine.ms_per_scan, 1e3 / mine.ms_per_scan, speedup.c_str(),
                        mib(mine.last.map_bytes).c_str(), memory_ratio.c_str(),
                        mib(mine.last.peak_rss_growth).c_str(), mine.cpu_ms_per_scan, cpu_speedup.c_str());
          table << row;
          std::fputs(row, stderr);
          if (!serial_share || method.octomap) continue;
          const double s = mine.serial_ms_per_scan / mine.cpu_ms_per_scan;
          char share[32];
          std::snprintf(share, sizeof share, "%.1f%%", 100.0 * s);
          char amdahl[32];
          std::snprintf(amdahl, sizeof amdahl, "%.2fx", 1.0 / (s + (1.0 - s) / 2.0));
          char critical_bound[32];
          std::snprintf(critical_bound, sizeof critical_bound, "%.2fx", mine.cpu_ms_per_scan / mine.critical_ms_per_scan);
          char scheduled_bound[32] = "-";  // without a one-thread run of this sweep
          if (one_thread_cpu.count(method.name)) {
            std::snprintf(scheduled_bound, sizeof scheduled_bound, "%.2fx",
                          one_thread_cpu[method.name] / mine.scheduled_ms_per_scan);
          }
          std::snprintf(row, sizeof row, "| %s | %.3g | %s | %s | %.1f | %.1f | %s | %s | %.1f | %s | %.1f | %s |\n",
                        data.name.c_str(), resolution, threads_text.c_str(), method.name.c_str(),
                        mine.cpu_ms_per_scan, mine.serial_ms_per_scan, share, amdahl, mine.critical_ms_per_scan,
                        critical_bound, mine.scheduled_ms_per_scan, scheduled_bound);
          share_table << row;
          std::fputs(row, stderr);
        }
      }
    }
  }
  std::printf("%s", table.str().c_str());
  if (serial_share) std::printf("\n%s", share_table.str().c_str());
  if (!sweep.markdown.empty()) {
    std::ofstream out(sweep.markdown);
    out << table.str();
    if (serial_share) out << "\n" << share_table.str();
  }
  return 0;
}
