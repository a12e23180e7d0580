// Frame cost benchmark: what each frame of the projective integrator costs
// in a fresh process, against the steady state.
//
// umbra_insert_benchmark builds a fresh map in a fresh process, so its
// figure holds the first touch of every buffer and of the map's growth
// (page faults). This program inserts a depth dataset's frames into one
// fresh map (pass 0) and then, with --passes above 1, the same frames again
// into the map they built (the steady state: the map holds their nodes
// already, the integrator's buffers are warm), and prints per frame the CPU
// time of the process and its minor page faults (getrusage), then each
// pass's means (docs/benchmarks.md, "what a fresh process pays").
//
// Usage: umbra_frame_cost_benchmark [--data DIR] [--dataset tum|sim-camera]
//          [--res 0.02] [--passes 2] [--threads 1] [--tum-max-range 5]
#include <sys/resource.h>

#include <cstdio>
#include <ctime>
#include <exception>
#include <string>

#include "bench_data.hpp"
#include "common/argument_cursor.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

double process_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

long minor_faults() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

}  // namespace

int main(int argc, char** argv) {
  umbra::bench::DatasetOptions data_options;
  std::string dataset = "tum";
  double resolution = 0.02;
  int passes = 2;
  unsigned threads = 1;
  umbra_bench::ArgumentCursor args{argc, argv};
  try {
    while (args.next()) {
      const std::string flag = args.flag();
      if (flag == "--data") data_options.data_dir = args.value();
      else if (flag == "--dataset") dataset = args.value();
      else if (flag == "--res") resolution = std::stod(args.value());
      else if (flag == "--passes") passes = std::stoi(args.value());
      else if (flag == "--threads") threads = static_cast<unsigned>(std::stoul(args.value()));
      else if (flag == "--tum-max-range") data_options.tum_max_range = std::stod(args.value());
      else {
        std::fprintf(stderr,
                     "unknown flag %s\nusage: umbra_frame_cost_benchmark [--data DIR] [--dataset tum|sim-camera] "
                     "[--res 0.02] [--passes 2] [--threads 1] [--tum-max-range 5]\n",
                     flag.c_str());
        return 2;
      }
    }
    if (passes < 1) throw std::invalid_argument("--passes must be at least 1");
    const umbra::bench::Dataset data = umbra::bench::load_dataset(dataset, data_options);
    umbra::MapConfig config;
    config.resolution = resolution;
    umbra::OccupancyMap map(config);
    umbra::InsertOptions options;
    options.integrator = umbra::IntegratorKind::projective;
    options.max_range = data.max_range;
    options.threads = threads;
    for (int pass = 0; pass < passes; ++pass) {
      double cpu_sum = 0.0;
      long fault_sum = 0;
      std::size_t frames = 0;
      std::printf("pass %d (%s), CPU ms / minor page faults per frame:", pass, pass == 0 ? "fresh map" : "again");
      for (const umbra::Scan& scan : data.scans) {
        if (!scan.image) throw std::invalid_argument(dataset + ": not a depth-image dataset");
        const umbra::ScanImage& image = *scan.image;
        const double cpu_start = process_cpu_seconds();
        const long faults_start = minor_faults();
        map.insert_depth_image(image.view(), image.camera, image.pose, {}, options);
        const double cpu = process_cpu_seconds() - cpu_start;
        const long faults = minor_faults() - faults_start;
        std::printf(" %.1f/%ld", 1e3 * cpu, faults);
        cpu_sum += cpu;
        fault_sum += faults;
        ++frames;
      }
      std::printf("\npass %d mean: %.2f ms CPU, %.0f minor page faults a frame\n", pass,
                  1e3 * cpu_sum / static_cast<double>(frames), static_cast<double>(fault_sum) / static_cast<double>(frames));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_frame_cost_benchmark: %s\n", e.what());
    return 1;
  }
  return 0;
}
