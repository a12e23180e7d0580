// `umbra build INPUT... -o MAP`: integrate point clouds into a map, saved as
// .umb, or as OctoMap's .bt / .ot (map_output.hpp).
//
// In three steps, so that a problem costs as little work as possible: the
// options are checked (any problem is a usage error, exit code 2); the
// pre-flight opens every input, checks its header and every sensor origin it
// states, and checks that the output folder can be written (a problem is a
// failure, exit code 1, before anything is inserted); then the scans are
// inserted and the map saved. A failure names the input and the scan. With
// --keep-going a bad input, or scan, is skipped with a warning, the rest is
// saved, and the exit code is 3.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "map_output.hpp"
#include "options.hpp"
#include "progress_bar.hpp"
#include "report.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/decay.hpp"
#ifdef UMBRA_WITH_ROS
#include "umbra_ros/rosbag_source.hpp"
#endif

namespace umbra::cli {
namespace {

struct BuildOptions {
  std::vector<std::string> inputs;
  std::string output;
  double resolution = 0.1;
  int depth_levels = 16;
  std::string integrator = "simple";
  int clear_depth = -1;
  int fine_steps = 2;
  unsigned threads = 0;
  double max_range = -1.0;
  std::string origin = "0,0,0";
  std::string bbox;
  bool color = false;
  std::string format;
  std::string poses;
  std::string calibration;
  std::string association;
  std::string camera;
  bool keep_going = false;
  std::vector<std::string> topics;
  std::string frame = "map";
  bool resolution_given = false;  ///< --res was on the command line
  double decay_occupied = 0.0;    ///< log-odds per second (DecayRates)
  double decay_free = 0.0;
  double scan_period = 0.0;       ///< > 0: scan k is stamped k * scan_period seconds
};

struct ScanRow {
  std::string name;
  InsertStats stats;
  double read_seconds = 0.0;
  double insert_seconds = 0.0;
};

/// Warns about clouds a .bag reader skipped for want of a transform.
void report_skipped(const ScanSource& source) {
#ifdef UMBRA_WITH_ROS
  if (const auto* bag = dynamic_cast<const ros_io::RosbagScanSource*>(&source); bag && bag->skipped_clouds() > 0) {
    std::printf("warning: %zu clouds had no transform to the map frame and were skipped (first: %s)\n",
                bag->skipped_clouds(), bag->first_skip_reason().c_str());
  }
#else
  (void)source;
#endif
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// What the options decide, checked: any problem is a UsageError (exit code 2).
struct BuildPlan {
  ScanSourceOptions sources;
  MapConfig config;
  std::optional<Aabb> box;
  InsertOptions insert;
  DecayRates decay;
};

/// The formats whose scans carry their time (Scan::stamp).
bool format_has_stamps(const std::string& format) { return format == "tum" || format == "rosbag"; }

BuildPlan plan_build(const BuildOptions& options) {
  return as_usage([&] {
    const std::filesystem::path output = options.output;
    (void)check_map_output(options.output, options.depth_levels, "-o");
    const std::filesystem::path folder = output.parent_path().empty() ? "." : output.parent_path();
    if (!std::filesystem::is_directory(folder)) {
      throw std::invalid_argument("output folder " + folder.string() + " does not exist");
    }
    BuildPlan plan;
    plan.sources.format = options.format;
    const std::vector<double> origin = parse_numbers(options.origin, 3, "--origin");
    plan.sources.origin = {static_cast<float>(origin[0]), static_cast<float>(origin[1]), static_cast<float>(origin[2])};
    plan.sources.poses = options.poses;
    plan.sources.calibration = options.calibration;
    plan.sources.association = options.association;
    plan.sources.topics = options.topics;
    plan.sources.frame = options.frame;
    if (!options.camera.empty()) {
      const std::vector<double> c = parse_numbers(options.camera, 5, "--camera");
      if (!(c[0] > 0 && c[1] > 0 && c[4] > 0)) {
        throw std::invalid_argument("--camera: fx, fy and depth_scale must be > 0, got '" + options.camera + "'");
      }
      plan.sources.depth_camera = {c[0], c[1], c[2], c[3], c[4]};
    }
    // The format of every input that exists; a missing one is an input
    // failure (exit code 1), named by the pre-flight.
    for (const std::string& input : options.inputs) {
      std::error_code ignored;
      if (std::filesystem::exists(input, ignored)) (void)scan_format_for(input, options.format);
    }
    plan.config.resolution = options.resolution;
    plan.config.depth_levels = options.depth_levels;
    plan.config.color = options.color;
    plan.config.validate();
    if (!options.bbox.empty()) {
      const std::vector<double> b = parse_numbers(options.bbox, 6, "--bbox");
      plan.box = Aabb{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
      plan.box->validate();
    }
    plan.insert.integrator = parse_integrator_kind(options.integrator);
    plan.insert.max_range = options.max_range;
    plan.insert.clear_depth = options.clear_depth;
    plan.insert.fine_steps = options.fine_steps;
    plan.insert.threads = options.threads;
    plan.insert.validate(plan.config.depth_levels);
    plan.decay.occupied_per_second = options.decay_occupied;
    plan.decay.free_per_second = options.decay_free;
    plan.decay.validate();
    if (plan.decay.enabled() && options.scan_period <= 0.0) {
      for (const std::string& input : options.inputs) {
        std::error_code ignored;
        if (!std::filesystem::exists(input, ignored) || format_has_stamps(scan_format_for(input, options.format))) continue;
        throw std::invalid_argument("--decay-occupied / --decay-free need the time of each scan, and " + input + " (" +
                                    scan_format_for(input, options.format) +
                                    ") does not carry it (TUM sequences and ROS bags do): give --scan-period SECONDS");
      }
    }
    return plan;
  });
}

/// "input 2 of 3 (path)"
std::string input_text(const BuildOptions& options, std::size_t input) {
  return "input " + std::to_string(input + 1) + " of " + std::to_string(options.inputs.size()) + " (" +
         options.inputs[input] + ")";
}

/// "(x, y, z)"
std::string point_text(Vec3f p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%g, %g, %g)", p.x, p.y, p.z);
  return text;
}

/// Throws std::runtime_error ("cannot read PATH: No such file or directory")
/// when the input is not there (or a folder above it cannot be searched).
void check_input_exists(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw std::runtime_error("cannot read " + path.string() + ": " +
                             (error ? error.message() : std::string("No such file or directory")));
  }
}

/// What the pre-flight found out about one input.
struct CheckedInput {
  bool skipped = false;              // --keep-going: the input cannot be read
  std::size_t scans = 0;             // as the input says (0: it does not say)
  std::set<std::size_t> bad_scans;   // --keep-going: scans whose sensor lies outside the map
};

/// Problems met while building: fatal without --keep-going, warnings with it.
class Problems {
 public:
  explicit Problems(bool keep_going) : keep_going_(keep_going) {}
  /// Throws std::runtime_error(`where` + ": " + what) without --keep-going;
  /// with it, prints a warning saying what is skipped.
  void report(const std::string& where, const std::string& what, const std::string& skipped) {
    if (!keep_going_) throw std::runtime_error(where + ": " + what);
    std::fprintf(stderr, "umbra: warning: %s: %s; skipping %s (--keep-going)\n", where.c_str(), what.c_str(),
                 skipped.c_str());
    ++count_;
  }
  [[nodiscard]] std::size_t count() const { return count_; }

 private:
  bool keep_going_;
  std::size_t count_ = 0;
};

/// The message of the exception in flight, with a sentence for a bare std::bad_alloc.
std::string current_error(const std::string& while_doing) {
  try {
    throw;
  } catch (const MemoryLimitError& e) {
    return e.what();
  } catch (const std::bad_alloc&) {
    return "out of memory while " + while_doing;
  } catch (const std::exception& e) {
    return e.what();
  }
}

/// Before anything is inserted: the output can be written, every input opens
/// and its header (and, for the formats that state them, every sensor origin)
/// is checked, so that a bad later input does not throw away the work on the
/// earlier ones.
std::vector<CheckedInput> preflight(const BuildOptions& options, const BuildPlan& plan, const Grid& grid,
                                    Problems& problems) {
  check_can_save(options.output);
  std::vector<CheckedInput> checked(options.inputs.size());
  std::size_t scans = 0;
  for (std::size_t input = 0; input < options.inputs.size(); ++input) {
    CheckedInput& entry = checked[input];
    std::vector<Vec3f> origins;
    try {
      check_input_exists(options.inputs[input]);
      const std::unique_ptr<ScanSource> source = open_scan_source(options.inputs[input], plan.sources);
      for (const std::string& warning : source->warnings()) std::fprintf(stderr, "umbra: warning: %s\n", warning.c_str());
      entry.scans = source->scan_count();
      origins = source->origins();
    } catch (const std::exception&) {
      problems.report(input_text(options, input), current_error("opening it"), "that input");
      entry.skipped = true;
      continue;
    }
    for (std::size_t scan = 0; scan < origins.size(); ++scan) {
      if (grid.key_checked(origins[scan])) continue;
      std::ostringstream extent;
      extent << "the sensor origin " << point_text(origins[scan]) << " lies outside the map, which spans ["
             << -grid.half_extent() << ", " << grid.half_extent() << ") on every axis; raise --depth-levels or --res";
      problems.report(input_text(options, input) + ", scan " + std::to_string(scan + 1) + " of " +
                          std::to_string(origins.size()),
                      extent.str(), "that scan");
      entry.bad_scans.insert(scan);
    }
    scans += entry.scans;
  }
  std::size_t usable = 0;
  for (const CheckedInput& entry : checked) usable += entry.skipped ? 0 : 1;
  if (usable == 0) throw std::runtime_error("every input was skipped: nothing to build");
  std::printf("checked %zu of %zu %s (%zu %s); every sensor origin they state lies inside the map; the output "
              "folder is writable\n",
              usable, options.inputs.size(), options.inputs.size() == 1 ? "input" : "inputs", scans,
              scans == 1 ? "scan" : "scans");
  return checked;
}

/// "3 of 120 scans inserted (input 1 of 2)", for the progress bar.
std::string progress_detail(std::size_t inserted, std::size_t total_scans, const BuildOptions& options,
                            std::size_t input) {
  std::string text = std::to_string(inserted);
  text += total_scans > 0 ? " of " + std::to_string(total_scans) + (total_scans == 1 ? " scan" : " scans")
                          : (inserted == 1 ? " scan" : " scans");
  text += " inserted";
  if (options.inputs.size() > 1) {
    text += " (input " + std::to_string(input + 1) + " of " + std::to_string(options.inputs.size()) + ")";
  }
  return text;
}

/// The width of the table's first column: its longest scan name (TUM's
/// frame names run past 48 characters), at least that of its heading.
int name_column_width(const std::vector<ScanRow>& rows) {
  std::size_t width = 4;  // "scan"
  for (const ScanRow& row : rows) width = std::max(width, row.name.size());
  return static_cast<int>(width);
}

int run_build(const BuildOptions& options) {
  const BuildPlan plan = plan_build(options);
  OccupancyMap map(plan.config);
  if (plan.box) map.set_bounding_box(plan.box);
  if (plan.decay.enabled()) map.set_decay(plan.decay);
  InsertOptions insert = plan.insert;
  Problems problems(options.keep_going);
  // The resolution decides everything about the map: say it, and say when it is the default.
  std::printf("%g m voxels%s, %d depth levels (the map spans +-%g m), integrator %s\n", map.resolution(),
              options.resolution_given ? "" : " (the default; set it with --res)", map.depth_levels(),
              map.grid().half_extent(), to_string(insert.integrator));
  if (plan.decay.enabled()) {
    std::printf("decay toward unknown: %g log-odds per second off occupied voxels, %g onto free ones, by %s\n",
                plan.decay.occupied_per_second, plan.decay.free_per_second,
                options.scan_period > 0.0 ? "--scan-period" : "the scans' own times");
  }
  const std::vector<CheckedInput> checked = preflight(options, plan, map.grid(), problems);

  std::vector<ScanRow> rows;
  InsertStats total;
  std::size_t uncolored = 0;
  std::size_t total_scans = 0;  // 0: some input does not say how many it holds
  for (const CheckedInput& entry : checked) {
    if (entry.skipped) continue;
    if (entry.scans == 0) {
      total_scans = 0;
      break;
    }
    total_scans += entry.scans;
  }
  ProgressBar bar("building");
  const auto start = std::chrono::steady_clock::now();
  std::size_t scans_read = 0;  // over all inputs, for --scan-period
  for (std::size_t file = 0; file < options.inputs.size(); ++file) {
    if (checked[file].skipped) continue;
    const std::string where = input_text(options, file);
    std::printf("inserting %s\n", where.c_str());
    std::fflush(stdout);
    std::unique_ptr<ScanSource> source;
    try {
      source = open_scan_source(options.inputs[file], plan.sources);
    } catch (const std::exception&) {
      problems.report(where, current_error("opening it"), "that input");
      continue;
    }
    Scan scan;
    for (std::size_t index = 0;; ++index) {
      const std::string scan_where = where + ", scan " + std::to_string(index + 1);
      const auto read_start = std::chrono::steady_clock::now();
      try {
        if (!source->next(scan)) break;
      } catch (const std::exception&) {
        problems.report(scan_where, current_error("reading it"), "the rest of that input");
        break;
      }
      const std::size_t scan_number = scans_read++;
      if (checked[file].bad_scans.count(index) != 0) continue;  // reported by the pre-flight
      if (plan.decay.enabled()) {
        if (options.scan_period > 0.0) {
          insert.stamp = static_cast<double>(scan_number) * options.scan_period;
        } else if (scan.stamp) {
          insert.stamp = scan.stamp;
        } else {
          problems.report(scan_where + " (" + scan.name + ")",
                          "the scan has no time stamp, which decay needs (give --scan-period SECONDS)", "that scan");
          continue;
        }
      }
      ScanRow row;
      row.name = scan.name;
      row.read_seconds = seconds_since(read_start);
      const auto insert_start = std::chrono::steady_clock::now();
      try {
        if (insert.integrator == IntegratorKind::projective && scan.image) {
          // A depth image goes in as an image: the projective integrator reads it.
          const bool colored = options.color && !scan.image->colors.empty();
          uncolored += options.color && !colored ? 1 : 0;
          row.stats = map.insert_depth_image(scan.image->view(), scan.image->camera, scan.image->pose,
                                             colored ? std::span<const Rgb>(scan.image->colors)
                                                      : std::span<const Rgb>(),
                                             insert);
        } else if (options.color && !scan.colors.empty()) {
          row.stats = map.insert_point_cloud(scan.origin, scan.points, scan.colors, insert);
        } else {
          uncolored += options.color ? 1 : 0;
          row.stats = map.insert_point_cloud(scan.origin, scan.points, insert);
        }
      } catch (const std::exception&) {
        problems.report(scan_where + " (" + scan.name + ")",
                        current_error("inserting its " + std::to_string(scan.points.size()) + " points"), "that scan");
        continue;
      }
      row.insert_seconds = seconds_since(insert_start);
      total += row.stats;
      rows.push_back(row);
      const double fraction = (static_cast<double>(file) + source->progress()) / static_cast<double>(options.inputs.size());
      bar.update(fraction, progress_detail(rows.size(), total_scans, options, file));
    }
    report_skipped(*source);
  }
  bar.complete(progress_detail(rows.size(), total_scans, options, options.inputs.size() - 1));
  const double build_seconds = seconds_since(start);

  double insert_seconds = 0.0;
  double read_seconds = 0.0;
  const int name_width = name_column_width(rows);
  std::printf("%-*s %10s %10s %9s %9s %12s\n", name_width, "scan", "points", "rays", "read ms", "insert ms",
              "M points/s");
  for (const ScanRow& row : rows) {
    std::printf("%-*s %10zu %10zu %9.1f %9.1f %12.2f\n", name_width, row.name.c_str(), row.stats.points, row.stats.rays,
                row.read_seconds * 1e3, row.insert_seconds * 1e3,
                row.insert_seconds > 0 ? static_cast<double>(row.stats.points) / row.insert_seconds / 1e6 : 0.0);
    insert_seconds += row.insert_seconds;
    read_seconds += row.read_seconds;
  }
  const double rate = insert_seconds > 0 ? static_cast<double>(rows.size()) / insert_seconds : 0.0;
  std::printf("total: %zu scans, %zu points, %zu rays; read %.3f s, insert %.3f s (%.2f M points/s, %.1f scans/s "
              "of insertion alone), %.3f s in all\n",
              rows.size(), total.points, total.rays, read_seconds, insert_seconds,
              insert_seconds > 0 ? static_cast<double>(total.points) / insert_seconds / 1e6 : 0.0, rate, build_seconds);
  std::printf("integrator %s", to_string(insert.integrator));
  if (insert.integrator == IntegratorKind::fast) {
    std::printf(" (clear depth %d = %.3g m nodes, %d fine steps)", insert.resolved_clear_depth(map.grid()),
                map.grid().node_size(insert.resolved_clear_depth(map.grid())), insert.fine_steps);
  }
  const unsigned asked = insert.threads == 0 ? hardware_threads() : insert.threads;
  const unsigned used = total.threads != 0 ? total.threads : asked;
  std::printf(", %u %s\n", used, used == 1 ? "thread" : "threads");
  if (total.threads != 0 && total.threads < asked) {
    std::fprintf(stderr,
                 "umbra: warning: only %u of the %u threads asked for could be started (the system refused more: a "
                 "process limit such as ulimit -u?); the scans were inserted with %u\n",
                 total.threads, asked, total.threads);
  }
  if (total.non_finite > 0) std::printf("warning: %zu points were NaN or infinite and were skipped\n", total.non_finite);
  if (total.out_of_bounds > 0) {
    std::printf("warning: %zu points lie outside the map (half extent %.1f m) and were skipped; "
                "raise --depth-levels or --res to cover them\n",
                total.out_of_bounds, map.grid().half_extent());
  }
  if (total.truncated > 0) std::printf("note: %zu rays were cut at --max-range %g m\n", total.truncated, options.max_range);
  if (total.outside_box > 0) std::printf("note: %zu rays missed the --bbox and were skipped\n", total.outside_box);
  if (uncolored > 0) std::printf("warning: --color, but %zu scans carry no colors\n", uncolored);

  const auto save_start = std::chrono::steady_clock::now();
  print_format_notes(map, std::nullopt, map_file_format_for(options.output));
  save_map_as(map, options.output, options.threads);
  std::printf("wrote %s in %.3f s\n", options.output.c_str(), seconds_since(save_start));
  print_statistics(stdout, compute_statistics(map));
  if (problems.count() > 0) {
    std::fprintf(stderr, "umbra: warning: %zu problems were skipped (--keep-going); the map holds the rest\n",
                 problems.count());
    return kSavedWithSkips;
  }
  return kSuccess;
}

}  // namespace

Command add_build_command(CLI::App& app) {
  auto options = std::make_shared<BuildOptions>();
  CLI::App* command = app.add_subcommand(
      "build",
      "Build a map from point clouds: OctoMap ScanGraph (.graph), ASCII x y z [r g b] (.xyz .dat .txt, also .bz2), "
      "PLY, PCD, KITTI velodyne (.bin or a folder, with --poses), TUM RGB-D (a sequence folder), ROS bags (.bag, "
      "PointCloud2 with TF; ROS builds only)");
  // No CLI11 existence check: a missing input is an input failure (exit code 1), named by the pre-flight.
  command->add_option("inputs", options->inputs, "point-cloud files or sequence folders, inserted in order")
      ->required();
  command->add_option("-o,--output", options->output,
                      "map file to write: .umb (umbra), or OctoMap's .bt / .ot (16 depth levels); replaced atomically")
      ->required();
  CLI::Option* res = command->add_option("--res", options->resolution,
                                         "voxel edge in metres, 0.0001 to 1000 (default 0.1, as OctoMap's tools; "
                                         "the build's first line says which was used)")
                         ->check(number_in(kMinResolution, kMaxResolution, "the voxel edge in metres"));
  command->add_option("--depth-levels", options->depth_levels, "tree depth levels (1-21; 16 like OctoMap)")
      ->capture_default_str()
      ->check(CLI::Range(1, 21));
  command->add_option("--integrator", options->integrator,
                      "simple, discrete (OctoMap's discretize=true), fast (coarse free-space clearing) or "
                      "projective (free space from depth images, or range images of scans)")
      ->capture_default_str()
      ->check(CLI::IsMember({"simple", "discrete", "fast", "projective"}));
  command->add_option("--clear-depth", options->clear_depth,
                      "fast: depth of the nodes free space is cleared with (-1: nodes closest to 16 cm)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 21));
  command->add_option("--fine-steps", options->fine_steps,
                      "fast: coarse nodes before each end point traced voxel by voxel (0: none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--threads", options->threads,
                      "threads that discretise, trace and apply each scan, and compress the map file while it is "
                      "written (0: all cores; at most " +
                          std::to_string(max_threads()) + ", 4 per core)")
      ->capture_default_str()
      ->check(number_in(0, max_threads(), "the number of threads (4 per core at most)"));
  command->add_option("--max-range", options->max_range, "metres; longer rays are cut there without a hit (<= 0: unlimited)")
      ->capture_default_str()
      ->check(not_nan());
  command->add_option("--bbox", options->bbox, "only map inside minx,miny,minz,maxx,maxy,maxz (rays are clipped)");
  command->add_flag("--color", options->color, "keep an RGB color per voxel (inputs with colors: xyz rgb, PLY, PCD, TUM)");
  command->add_option("--origin", options->origin, "sensor origin x,y,z for files without poses (.xyz, .ply, .pcd, lone .bin)")
      ->capture_default_str();
  command->add_option("--decay-occupied", options->decay_occupied,
                      "log-odds per second that occupied voxels lose toward unknown (0: none; needs the scans' "
                      "times: TUM, ROS bags, or --scan-period)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--decay-free", options->decay_free,
                      "log-odds per second that free voxels lose toward unknown (0: none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--scan-period", options->scan_period,
                      "seconds between scans for decay: scan k (from 0, over all inputs) is taken at k times this, "
                      "instead of the inputs' own times (0: theirs)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--format", options->format, "input format for every input (default: by name)")
      ->check(CLI::IsMember({"graph", "xyz", "ply", "pcd", "kitti", "tum", "rosbag"}));
  command->add_option("--poses", options->poses, "kitti: poses file (12 numbers per line)");
  command->add_option("--calibration", options->calibration, "kitti: calib.txt with the velodyne-to-camera Tr");
  command->add_option("--association", options->association, "tum: association file (default: the folder's *assoc*.txt)");
  command->add_option("--camera", options->camera, "tum: fx,fy,cx,cy,depth_scale (default: TUM fr2 Kinect, 5000)");
  command->add_flag("--keep-going", options->keep_going,
                    "skip an input that cannot be read, or a scan that cannot be inserted, with a warning, and save the "
                    "rest (exit code 3)");
  add_memory_option(*command);
  command->add_option("--topic", options->topics, "rosbag: a PointCloud2 topic to read (repeatable; default: all)");
  command->add_option("--frame", options->frame, "rosbag: the map frame, clouds are moved into it with the bag's TF")
      ->capture_default_str();
  return [options, res] {
    options->resolution_given = res->count() > 0;
    return run_build(*options);
  };
}

}  // namespace umbra::cli
