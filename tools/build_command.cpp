// `umbra build INPUT... -o MAP.umb`: integrate point clouds into a map.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "progress_bar.hpp"
#include "report.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::cli {
namespace {

struct BuildOptions {
  std::vector<std::string> inputs;
  std::string output;
  double resolution = 0.1;
  int depth_levels = 16;
  std::string integrator = "simple";
  double max_range = -1.0;
  std::string origin = "0,0,0";
  std::string format;
};

struct ScanRow {
  std::string name;
  InsertStats stats;
  double read_seconds = 0.0;
  double insert_seconds = 0.0;
};

Vec3f parse_origin(const std::string& text) {
  std::istringstream in(text);
  Vec3f origin;
  char comma1 = 0;
  char comma2 = 0;
  if (!(in >> origin.x >> comma1 >> origin.y >> comma2 >> origin.z) || comma1 != ',' || comma2 != ',' ||
      !(in >> std::ws).eof() || !origin.is_finite()) {
    throw std::invalid_argument("--origin expects three finite numbers x,y,z, got '" + text + "'");
  }
  return origin;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void check_output_path(const std::filesystem::path& output) {
  if (output.extension() != ".umb") {
    throw std::invalid_argument("output " + output.string() + ": unknown map format (expected a .umb file)");
  }
  const std::filesystem::path folder = output.parent_path().empty() ? "." : output.parent_path();
  if (!std::filesystem::is_directory(folder)) {
    throw std::invalid_argument("output folder " + folder.string() + " does not exist");
  }
}

int run_build(const BuildOptions& options) {
  check_output_path(options.output);
  ScanSourceOptions source_options;
  source_options.format = options.format;
  source_options.origin = parse_origin(options.origin);
  for (const std::string& input : options.inputs) (void)scan_format_for(input, options.format);  // fail early

  OccupancyMap map(options.resolution, options.depth_levels);
  InsertOptions insert;
  insert.integrator = parse_integrator_kind(options.integrator);
  insert.max_range = options.max_range;

  std::vector<ScanRow> rows;
  InsertStats total;
  ProgressBar bar("building");
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t file = 0; file < options.inputs.size(); ++file) {
    const std::unique_ptr<ScanSource> source = open_scan_source(options.inputs[file], source_options);
    Scan scan;
    for (;;) {
      const auto read_start = std::chrono::steady_clock::now();
      if (!source->next(scan)) break;
      ScanRow row;
      row.name = scan.name;
      row.read_seconds = seconds_since(read_start);
      const auto insert_start = std::chrono::steady_clock::now();
      row.stats = map.insert_point_cloud(scan.origin, scan.points, insert);
      row.insert_seconds = seconds_since(insert_start);
      total += row.stats;
      rows.push_back(row);
      const double fraction = (static_cast<double>(file) + source->progress()) / static_cast<double>(options.inputs.size());
      bar.update(fraction, std::to_string(rows.size()) + " scans");
    }
  }
  bar.finish();
  const double build_seconds = seconds_since(start);

  double insert_seconds = 0.0;
  double read_seconds = 0.0;
  std::printf("%-40s %10s %10s %9s %9s\n", "scan", "points", "rays", "read ms", "insert ms");
  for (const ScanRow& row : rows) {
    std::printf("%-40s %10zu %10zu %9.1f %9.1f\n", row.name.c_str(), row.stats.points, row.stats.rays,
                row.read_seconds * 1e3, row.insert_seconds * 1e3);
    insert_seconds += row.insert_seconds;
    read_seconds += row.read_seconds;
  }
  std::printf("total: %zu scans, %zu points, %zu rays, read %.3f s, insert %.3f s (%.2f M points/s), %.3f s in all\n",
              rows.size(), total.points, total.rays, read_seconds, insert_seconds,
              insert_seconds > 0 ? static_cast<double>(total.points) / insert_seconds / 1e6 : 0.0, build_seconds);
  if (total.non_finite > 0) std::printf("warning: %zu points were NaN or infinite and were skipped\n", total.non_finite);
  if (total.out_of_bounds > 0) {
    std::printf("warning: %zu points lie outside the map (half extent %.1f m) and were skipped; "
                "raise --depth-levels or --res to cover them\n",
                total.out_of_bounds, map.grid().half_extent());
  }
  if (total.truncated > 0) std::printf("note: %zu rays were cut at --max-range %g m\n", total.truncated, options.max_range);

  const auto save_start = std::chrono::steady_clock::now();
  save_map(map, options.output);
  std::printf("wrote %s in %.3f s\n", options.output.c_str(), seconds_since(save_start));
  print_statistics(stdout, compute_statistics(map));
  return 0;
}

}  // namespace

Command add_build_command(CLI::App& app) {
  auto options = std::make_shared<BuildOptions>();
  CLI::App* command = app.add_subcommand(
      "build", "Build a map from point clouds: OctoMap ScanGraph (.graph) or ASCII x y z (.xyz, .dat, .txt, also .bz2)");
  command->add_option("inputs", options->inputs, "point-cloud files, inserted in order")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("-o,--output", options->output, "map file to write (.umb)")->required();
  command->add_option("--res", options->resolution, "voxel edge in metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--depth-levels", options->depth_levels, "tree depth levels (1-21; 16 like OctoMap)")
      ->capture_default_str()
      ->check(CLI::Range(1, 21));
  command->add_option("--integrator", options->integrator, "simple or discrete (OctoMap's discretize=true)")
      ->capture_default_str()
      ->check(CLI::IsMember({"simple", "discrete"}));
  command->add_option("--max-range", options->max_range, "metres; longer rays are cut there without a hit (<= 0: unlimited)")
      ->capture_default_str();
  command->add_option("--origin", options->origin, "sensor origin x,y,z for files without poses (.xyz)")
      ->capture_default_str();
  command->add_option("--format", options->format, "input format for every input: graph or xyz (default: by extension)")
      ->check(CLI::IsMember({"graph", "xyz"}));
  return [options] { return run_build(*options); };
}

}  // namespace umbra::cli
