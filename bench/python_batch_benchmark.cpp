// The C++ half of the Python bindings benchmark (bench/python_batch_benchmark.py
// runs it; results and command in docs/benchmarks.md, "Python bindings"):
// the work the Python module does for map.spheres_free(centers, radii) and
// map.states(points), written as a C++ user writes it, on the map and the
// inputs the Python script saved.
//
//   spheres  rows (cx, cy, cz, r) -> std::vector<Sphere> -> the batch
//            OccupancyMap::is_free(span<const Sphere>, span<uint8_t>)
//   states   rows (x, y, z) -> OccupancyMap::state(p) per point into a
//            std::vector<uint8_t>
//
// Inputs are raw little-endian float64 rows (numpy's tofile). Times are the
// thread's CPU time (the machines are shared), the median of --repeat runs,
// as the Python half measures them. It prints one line per task:
//   <task> <seconds> <answers that are 1 (free / occupied)>
// so that the script can check both halves gave the same answers.
//
// Usage: umbra_python_batch_benchmark MAP.umb SPHERES.f64 POINTS.f64 [--repeat N]
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <time.h>

#include "common/argument_cursor.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/shapes.hpp"

namespace {

double thread_seconds() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

/// The rows of a raw float64 file, `width` numbers each.
std::vector<double> read_rows(const std::filesystem::path& path, std::size_t width) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  const auto bytes = std::filesystem::file_size(path);
  if (bytes % (width * sizeof(double)) != 0) {
    throw std::runtime_error(path.string() + ": " + std::to_string(bytes) + " bytes is not a whole number of rows of " +
                             std::to_string(width) + " float64");
  }
  std::vector<double> values(bytes / sizeof(double));
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(bytes));
  if (!in) throw std::runtime_error("cannot read " + path.string());
  return values;
}

/// Median thread CPU seconds of `repeat` runs of task().
template <typename Task>
double median_seconds(int repeat, const Task& task) {
  std::vector<double> times;
  for (int r = 0; r < repeat; ++r) {
    const double start = thread_seconds();
    task();
    times.push_back(thread_seconds() - start);
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

std::size_t ones(const std::vector<std::uint8_t>& answers) {
  return static_cast<std::size_t>(std::count(answers.begin(), answers.end(), std::uint8_t{1}));
}

int run(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MAP.umb SPHERES.f64 POINTS.f64 [--repeat N]\n", argv[0]);
    return 2;
  }
  int repeat = 5;
  umbra_bench::ArgumentCursor arguments{argc, argv, 3};
  while (arguments.next()) {
    if (arguments.flag() == "--repeat") {
      repeat = std::max(1, std::stoi(arguments.value()));
    } else {
      std::fprintf(stderr, "unknown option %s\n", arguments.flag().c_str());
      return 2;
    }
  }
  const umbra::OccupancyMap map = umbra::load_map(argv[1]);
  const std::vector<double> sphere_rows = read_rows(argv[2], 4);
  const std::vector<double> point_rows = read_rows(argv[3], 3);

  const std::size_t spheres = sphere_rows.size() / 4;
  std::vector<std::uint8_t> free(spheres);
  const double sphere_seconds = median_seconds(repeat, [&] {
    std::vector<umbra::Sphere> shapes;
    shapes.reserve(spheres);
    for (std::size_t i = 0; i < spheres; ++i) {
      const double* row = &sphere_rows[4 * i];
      shapes.push_back(umbra::Sphere{{row[0], row[1], row[2]}, row[3]});
    }
    map.is_free(std::span<const umbra::Sphere>(shapes), std::span<std::uint8_t>(free));
  });

  const std::size_t points = point_rows.size() / 3;
  std::vector<std::uint8_t> states(points);
  const double state_seconds = median_seconds(repeat, [&] {
    for (std::size_t i = 0; i < points; ++i) {
      const double* row = &point_rows[3 * i];
      states[i] = static_cast<std::uint8_t>(map.state(umbra::Vec3d{row[0], row[1], row[2]}));
    }
  });
  const auto occupied = static_cast<std::size_t>(
      std::count(states.begin(), states.end(), static_cast<std::uint8_t>(umbra::OccupancyState::occupied)));

  std::printf("spheres %.6f %zu\n", sphere_seconds, ones(free));
  std::printf("states %.6f %zu\n", state_seconds, occupied);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_python_batch_benchmark: %s\n", e.what());
    return 1;
  }
}
