// Whole-process benchmark: `umbra build` against a liboctomap program that
// does the same job, reading and writing included (docs/benchmarks.md,
// "Whole `umbra build`").
//
// Every run is a fresh process, measured by wait4(): wall-clock time from
// fork to exit, CPU time (user + system, all threads) and peak RSS
// (ru_maxrss). Methods:
//   umbra-simple / -discrete / -fast-n2 / -fast-n0 / -projective
//       the `umbra` program given with --umbra: `umbra build INPUT -o
//       OUT.umb --res R --integrator K [--fine-steps N] --max-range M
//       --threads T`, exactly what a user runs (pre-flight, reading,
//       insertion, atomic save with fsync, the statistics it prints)
//   octomap-plain / -discrete
//       this program again (--octomap-child): reads the same input with
//       umbra's readers (open_scan_source, as `umbra build` does), inserts
//       every scan with OcTree::insertPointCloud(..., discretize), writes
//       .bt with OcTree::writeBinary (which prunes to maximum likelihood
//       first, as OctoMap users get it)
//   octomap-discrete-ot
//       the same, writing .ot with OcTree::write (full log-odds)
// Each umbra method is compared with the OctoMap method of its semantics
// (simple with plain, the others with discrete .bt). Repetitions
// interleave the methods; the median of each column is reported (with
// --best the smallest: on a machine shared with other jobs, the run that
// waited least for a core). Both
// programs say how long reading, insertion and writing took (umbra build
// prints it; the OctoMap child writes it to its stdout), so the table
// shows what writing costs next to insertion.
//
// Usage: umbra_build_benchmark --umbra PATH [--data DIR] [--datasets 3dtk,tum]
//          [--res 0.05,0.02] [--methods LIST] [--threads 1,2] [--repeat 5]
//          [--max-range 30] [--tum-max-range 5] [--best] [--out DIR] [--markdown FILE]
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
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
#include "umbra/io/scan_source.hpp"

namespace {

namespace fs = std::filesystem;
using umbra::bench::median;
using umbra::bench::split_list;

struct Method {
  std::string name;
  bool octomap = false;
  bool discretize = false;        // OctoMap
  bool ot = false;                // OctoMap: .ot instead of .bt
  std::string integrator;         // umbra
  int fine_steps = 0;             // umbra fast
  std::string counterpart;        // the OctoMap method with the same semantics
};

const std::vector<Method> kAllMethods = {
    {"octomap-plain", true, false, false, "", 0, ""},
    {"octomap-discrete", true, true, false, "", 0, ""},
    {"octomap-discrete-ot", true, true, true, "", 0, ""},
    {"umbra-simple", false, false, false, "simple", 0, "octomap-plain"},
    {"umbra-discrete", false, false, false, "discrete", 0, "octomap-discrete"},
    {"umbra-fast-n2", false, false, false, "fast", 2, "octomap-discrete"},
    {"umbra-fast-n0", false, false, false, "fast", 0, "octomap-discrete"},
    {"umbra-projective", false, false, false, "projective", 0, "octomap-discrete"},
};

/// One process, as wait4() and its output saw it.
struct Run {
  double wall = 0.0;       // s
  double cpu = 0.0;        // s, user + system
  double peak_rss = 0.0;   // MiB
  double file = 0.0;       // MiB
  double insert = 0.0;     // s, reading and insertion as the program reports them
  double write = 0.0;      // s, writing the map file
};

// --- the OctoMap child ---------------------------------------------------------

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// --octomap-child INPUT RES MAX_RANGE DISCRETIZE(0|1) OUTPUT(.bt|.ot): prints "insert S write S".
int octomap_child(const std::string& input, double resolution, double max_range, bool discretize,
                  const std::string& output) {
  const auto start = std::chrono::steady_clock::now();
  octomap::OcTree tree(resolution);
  const auto source = umbra::open_scan_source(input);
  umbra::Scan scan;
  while (source->next(scan)) {
    octomap::Pointcloud cloud;
    cloud.reserve(scan.points.size());
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), max_range, false,
                          discretize);
  }
  const double insert = seconds_since(start);
  const auto write_start = std::chrono::steady_clock::now();
  const bool written = output.ends_with(".ot") ? tree.write(output) : tree.writeBinary(output);
  if (!written) {
    std::fprintf(stderr, "octomap: cannot write %s\n", output.c_str());
    return 1;
  }
  std::printf("insert %.6f write %.6f\n", insert, seconds_since(write_start));
  return 0;
}

// --- running and measuring a process ------------------------------------------

/// Runs `argv` with stdout captured, stderr passed through; throws unless it exits with 0.
Run run_process(const std::vector<std::string>& argv, std::string& out) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  std::fflush(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t child = ::fork();
  if (child < 0) throw std::runtime_error("fork failed");
  if (child == 0) {
    ::dup2(fds[1], STDOUT_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    std::perror(args[0]);
    ::_exit(127);
  }
  ::close(fds[1]);
  out.clear();
  char buffer[4096];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    out.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  rusage usage{};
  if (::wait4(child, &status, 0, &usage) != child) throw std::runtime_error("wait4 failed");
  Run run;
  run.wall = seconds_since(start);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error(argv[0] + " " + argv[1] + " failed (status " + std::to_string(status) + "): " + out);
  }
  auto seconds = [](timeval t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  run.cpu = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  run.peak_rss = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  return run;
}

/// The number after `label` in `text`, or throws.
double number_after(const std::string& text, const std::string& label) {
  const std::size_t at = text.find(label);
  if (at == std::string::npos) throw std::runtime_error("no '" + label + "' in the output:\n" + text);
  return std::stod(text.substr(at + label.size()));
}

struct Settings {
  std::string self;
  std::string umbra;
  fs::path out_dir;
};

Run measure(const Settings& settings, const umbra::bench::Dataset& data, const Method& method, double resolution,
            unsigned threads) {
  const fs::path output = settings.out_dir / (method.name + (method.octomap ? (method.ot ? ".ot" : ".bt") : ".umb"));
  fs::remove(output);
  char res_text[32];
  std::snprintf(res_text, sizeof res_text, "%g", resolution);
  char range_text[32];
  std::snprintf(range_text, sizeof range_text, "%g", data.max_range);
  std::string out;
  Run run;
  if (method.octomap) {
    run = run_process({settings.self, "--octomap-child", data.path, res_text, range_text, method.discretize ? "1" : "0",
                       output.string()},
                      out);
    run.insert = number_after(out, "insert ");
    run.write = number_after(out, "write ");
  } else {
    std::vector<std::string> argv = {settings.umbra, "build", data.path, "-o", output.string(), "--res", res_text,
                                     "--integrator", method.integrator, "--max-range", range_text, "--threads",
                                     std::to_string(threads)};
    if (method.integrator == "fast") {
      argv.push_back("--fine-steps");
      argv.push_back(std::to_string(method.fine_steps));
    }
    run = run_process(argv, out);
    // "total: ...; read R s, insert I s (...), T s in all" and "wrote PATH in W s".
    run.insert = number_after(out, "; read ") + number_after(out, " s, insert ");
    run.write = number_after(out, output.string() + " in ");
  }
  run.file = static_cast<double>(fs::file_size(output)) / (1024.0 * 1024.0);
  return run;
}

std::string ratio(double theirs, double mine) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1fx", theirs / mine);
  return text;
}

std::string percent(double mine, double theirs) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f%%", 100.0 * mine / theirs);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 7 && std::string(argv[1]) == "--octomap-child") {
    return octomap_child(argv[2], std::stod(argv[3]), std::stod(argv[4]), std::string(argv[5]) == "1", argv[6]);
  }
  Settings settings;
  settings.self = fs::canonical("/proc/self/exe").string();
  umbra_bench::SweepFlags sweep;
  sweep.datasets = "3dtk,tum";
  sweep.methods = "octomap-discrete,umbra-discrete,umbra-fast-n0";
  sweep.threads = "1,2";
  sweep.repeat = 5;
  std::string out_dir;
  bool best = false;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    auto value = [&] { return args.value(); };
    if (sweep.take(arg, args)) continue;
    if (arg == "--umbra") settings.umbra = value();
    else if (arg == "--best") best = true;
    else if (arg == "--out") out_dir = value();
    else if (arg == "--help" || arg == "-h") {
      std::printf(
          "usage: umbra_build_benchmark --umbra PATH [--data DIR] [--datasets 3dtk,tum] [--res 0.05,0.02]\n"
          "         [--methods LIST] [--threads 1,2] [--repeat 5] [--max-range 30] [--tum-max-range 5]\n"
          "         [--best] [--out DIR] [--markdown FILE]\n"
          "methods:");
      for (const Method& m : kAllMethods) std::printf(" %s", m.name.c_str());
      std::printf("\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/build_benchmark.cpp)\n", arg.c_str());
      return 2;
    }
  }
  if (settings.umbra.empty() || !fs::is_regular_file(settings.umbra)) {
    std::fprintf(stderr, "--umbra must name the umbra program (build/tools/umbra), got '%s'\n", settings.umbra.c_str());
    return 2;
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
  settings.out_dir = out_dir.empty() ? fs::temp_directory_path() / ("umbra-build-benchmark-" + std::to_string(::getpid()))
                                     : fs::path(out_dir);
  fs::create_directories(settings.out_dir);

  std::ostringstream table;
  table << "| dataset | res (m) | method | threads | wall (s) | CPU (s) | peak RSS (MiB) | file (MiB) | "
           "read + insert (s) | write (s) | wall vs OctoMap | CPU vs OctoMap | RSS vs OctoMap | file vs OctoMap | "
           "file vs .ot |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  try {
    for (const std::string& name : split_list(sweep.datasets)) {
      umbra::bench::Dataset data;  // only its path and range: each process reads the input itself
      data.name = name;
      data.path = umbra::bench::dataset_path(name, sweep.data);
      data.max_range = name == "tum" ? sweep.data.tum_max_range : sweep.data.max_range;
      if (data.path.empty()) throw std::runtime_error(name + " is not read from a file; use 3dtk, tum, scan.dat or a path");
      for (const std::string& res_text : split_list(sweep.resolutions)) {
        const double resolution = std::stod(res_text);
        // Runs per (method, threads); OctoMap has no threads and runs once per repetition.
        std::map<std::pair<std::string, unsigned>, std::vector<Run>> runs;
        for (int r = 0; r < sweep.repeat; ++r) {
          for (const Method& method : methods) {
            for (const std::string& threads_text : split_list(sweep.threads)) {
              const unsigned threads = method.octomap ? 1 : static_cast<unsigned>(std::stoul(threads_text));
              if (method.octomap && threads_text != split_list(sweep.threads).front()) continue;
              const Run run = measure(settings, data, method, resolution, threads);
              runs[{method.name, threads}].push_back(run);
              std::fprintf(stderr, "%s res %g %s threads %u run %d: wall %.3f s, CPU %.3f s, peak RSS %.1f MiB, file %.2f MiB, "
                           "read+insert %.3f s, write %.3f s\n",
                           name.c_str(), resolution, method.name.c_str(), threads, r + 1, run.wall, run.cpu,
                           run.peak_rss, run.file, run.insert, run.write);
            }
          }
        }
        std::map<std::pair<std::string, unsigned>, Run> medians;
        for (const auto& [key, list] : runs) {
          auto column = [&](double Run::*field) {
            std::vector<double> values;
            for (const Run& run : list) values.push_back(run.*field);
            return best ? *std::min_element(values.begin(), values.end()) : median(values);
          };
          medians[key] = {column(&Run::wall), column(&Run::cpu), column(&Run::peak_rss),
                          column(&Run::file), column(&Run::insert), column(&Run::write)};
        }
        for (const auto& [key, mine] : medians) {
          const Method& method = *std::find_if(kAllMethods.begin(), kAllMethods.end(), [&](const Method& m) { return m.name == key.first; });
          std::string versus[5] = {"-", "-", "-", "-", "-"};
          if (const auto theirs = medians.find({method.counterpart, 1}); !method.octomap && theirs != medians.end()) {
            versus[0] = ratio(theirs->second.wall, mine.wall);
            versus[1] = ratio(theirs->second.cpu, mine.cpu);
            versus[2] = percent(mine.peak_rss, theirs->second.peak_rss);
            versus[3] = percent(mine.file, theirs->second.file);
          }
          // .bt keeps only free / occupied; .ot keeps the log-odds, as .umb does.
          if (const auto ot = medians.find({"octomap-discrete-ot", 1}); !method.octomap && ot != medians.end()) {
            versus[4] = percent(mine.file, ot->second.file);
          }
          char row[512];
          std::snprintf(row, sizeof row,
                        "| %s | %g | %s | %u | %.3f | %.3f | %.1f | %.2f | %.3f | %.3f | %s | %s | %s | %s | %s |\n",
                        name.c_str(), resolution, method.name.c_str(), key.second, mine.wall, mine.cpu, mine.peak_rss,
                        mine.file, mine.insert, mine.write, versus[0].c_str(), versus[1].c_str(), versus[2].c_str(),
                        versus[3].c_str(), versus[4].c_str());
          table << row;
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_build_benchmark: %s\n", e.what());
    return 1;
  }
  std::printf("%s of %d runs each\n\n%s", best ? "Best" : "Median", sweep.repeat, table.str().c_str());
  if (!sweep.markdown.empty()) std::ofstream(sweep.markdown) << table.str();
  if (out_dir.empty()) fs::remove_all(settings.out_dir);
  return 0;
}
