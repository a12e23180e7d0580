// umbra_explore_study: the UFOMap paper's exploration case study, runnable.
//
//   build/bench/explore/umbra_explore_study --out explore-output              # 900 s each, as fast as possible
//   build/bench/explore/umbra_explore_study --out explore-output --real-time  # 900 s each, in real time
//
// The same next-best-view explorer (examples/explore) flies the same robot
// through the same procedural plant (sim/industrial_scene.hpp), with the
// same parameters and seed, once on an umbra map and once on an OctoMap map
// (octomap_exploration_map.hpp), one after the other. Each run maps and
// plans in two threads on its map. Written to --out:
//   coverage.csv   explored volume, coverage of the reachable free space and
//                  the map's memory over simulated time, both explorers
//   coverage.png   the plot of it (plot_coverage.py, matplotlib)
//   umbra.umb      the umbra map at the end
//   umbra.html     the umbra map in the viewer of `umbra view`
//   summary.md     the figures (times to coverage, iterations per second,
//                  time per query kind), also printed
//   summary.json   the same for programs
// --window-half-extent R runs the umbra explorer on a map that moves (a box
// of at least R metres around the robot, umbra/map/moving_window.hpp; what
// leaves is dropped), to measure the memory it saves and what it costs in
// coverage. docs/exploration.md reports a run.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "explorer.hpp"
#include "umbra/io/file_saving.hpp"
#include "octomap_exploration_map.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/sim/industrial_scene.hpp"
#include "umbra_exploration_map.hpp"
#include "viewer_data.hpp"
#include "viewer_page.hpp"

namespace umbra::explore {
namespace {

struct StudyOptions {
  std::string out = "explore-output";
  double budget = 900.0;
  bool real_time = false;
  std::uint32_t seed = 1;
  double resolution = 0.16;
  std::string gain = "exact";
  std::vector<std::string> explorers{"umbra", "octomap"};
  int image_width = 160;
  int image_height = 84;
  double speed = 1.0;
  double yaw_rate = 1.0;
  int max_nodes = 150;
  double extension_range = 1.5;
  int yaw_samples = 4;
  bool routing = true;
  double coverage_period = 2.0;
  std::string clearance = "collision";  ///< umbra's ball and capsule checks: "collision" or "field"
  double field_max_distance = 1.0;
  double window_half_extent = 0.0;  ///< umbra's moving window; 0: none
};

struct Run {
  ExplorationResult result;
  std::size_t memory_bytes = 0;
  double exclusive_seconds = -1.0;  ///< umbra only
  double field_update_seconds = -1.0;  ///< umbra with --clearance field only
  ClearanceCounts clearance_counts;    ///< the same
  double min_clearance = 0.0;
  /// The map's memory_bytes() at each coverage sample (same index).
  std::vector<std::size_t> memory;
  std::size_t peak_memory_bytes = 0;
};

ExplorerConfig config_for(const StudyOptions& options, const sim::IndustrialPlant& plant) {
  ExplorerConfig config;
  config.planner.bounds = Aabb{plant.interior.min, plant.interior.max};
  config.planner.max_nodes = options.max_nodes;
  config.planner.extension_range = options.extension_range;
  config.planner.yaw_samples = options.yaw_samples;
  config.planner.route_to_memory = options.routing;
  config.camera.width = options.image_width;
  config.camera.height = options.image_height;
  config.camera.hfov_deg = config.planner.camera.hfov_deg;
  config.camera.vfov_deg = config.planner.camera.vfov_deg;
  config.camera.max_range = config.planner.camera.max_range;
  // Pixels that see nothing within range clear free space up to it.
  config.camera.emit_no_return = true;
  config.camera.no_return_range = config.camera.max_range + 1.0;
  config.speed = options.speed;
  config.yaw_rate = options.yaw_rate;
  config.budget = options.budget;
  config.coverage_period = options.coverage_period;
  config.clock = options.real_time ? SimClock::Mode::real_time : SimClock::Mode::accelerated;
  config.seed = options.seed;
  return config;
}

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << value;
  return out.str();
}

std::string time_or_never(double t) { return t < 0.0 ? "not reached" : fixed(t, 0) + " s"; }

void write_text(const std::filesystem::path& path, const std::string& text, const char* kind) {
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(text.data());
  write_file_atomically(path, {std::span<const std::uint8_t>(bytes, text.size())}, kind);
}

/// Index of the coverage sample at `time`: the last at or before it (the
/// map only changes when a frame is inserted); -1 before the first.
std::ptrdiff_t sample_at(const ExplorationResult& result, double time) {
  std::ptrdiff_t found = -1;
  for (std::size_t i = 0; i < result.coverage.size(); ++i) {
    if (result.coverage[i].time > time + 1e-9) break;
    found = static_cast<std::ptrdiff_t>(i);
  }
  return found;
}

std::string coverage_csv(const std::vector<Run>& runs, double budget, double period) {
  std::ostringstream csv;
  csv << "time_s";
  for (const Run& run : runs) {
    const std::string& name = run.result.map_name;
    csv << ',' << name << "_explored_m3," << name << "_coverage_percent," << name << "_memory_mib";
  }
  csv << '\n';
  for (double t = 0.0; t <= budget + 1e-9; t += period) {
    csv << fixed(t, 1);
    for (const Run& run : runs) {
      const std::ptrdiff_t i = sample_at(run.result, t);
      const CoverageSample* s = i < 0 ? nullptr : &run.result.coverage[static_cast<std::size_t>(i)];
      const std::size_t bytes = i < 0 ? 0 : run.memory[static_cast<std::size_t>(i)];
      csv << ',' << (s ? fixed(s->explored_m3, 2) : "0.00") << ',' << (s ? fixed(100.0 * s->coverage, 3) : "0.000")
          << ',' << fixed(double(bytes) / 1048576.0, 2);
    }
    csv << '\n';
  }
  return csv.str();
}

struct Share {
  const char* kind;
  QueryTally tally;
};

std::vector<Share> shares_of(const Run& run) {
  const PlannerStats& p = run.result.planner;
  return {{"node collision (ball)", p.node_checks},
          {"edge (capsule / lines)", p.edge_checks},
          {"information gain", p.gains},
          {"insertion", run.result.insertions}};
}

std::string summary_markdown(const std::vector<Run>& runs, const StudyOptions& options, double reachable_m3) {
  std::ostringstream md;
  md << "Reachable free space: " << fixed(reachable_m3, 1) << " m^3 (robot radius 0.3 m, " << options.resolution
     << " m cells); budget " << fixed(options.budget, 0) << " s of simulated time, "
     << (options.real_time ? "real time" : "accelerated (CPU time charged)") << ", seed " << options.seed << ".\n\n";
  if (options.window_half_extent > 0.0) {
    md << "umbra's map moves with the robot: a box of at least " << fixed(options.window_half_extent, 1)
       << " m around it, what leaves dropped (coverage counts what the map still holds).\n\n";
  }
  md << "| | " ;
  for (const Run& run : runs) md << run.result.map_name << " | ";
  md << "\n|---|";
  for (std::size_t i = 0; i < runs.size(); ++i) md << "---|";
  md << '\n';
  auto row = [&](const std::string& name, auto&& value) {
    md << "| " << name << " | ";
    for (const Run& run : runs) md << value(run) << " | ";
    md << '\n';
  };
  row("time to 50% coverage", [](const Run& r) { return time_or_never(r.result.time_to(0.5)); });
  row("time to 90% coverage", [](const Run& r) { return time_or_never(r.result.time_to(0.9)); });
  row("time to 95% coverage", [](const Run& r) { return time_or_never(r.result.time_to(0.95)); });
  row("final coverage", [](const Run& r) {
    return r.result.coverage.empty() ? std::string("-") : fixed(100.0 * r.result.coverage.back().coverage, 1) + "%";
  });
  row("explored volume at the end", [](const Run& r) {
    return r.result.coverage.empty() ? std::string("-") : fixed(r.result.coverage.back().explored_m3, 0) + " m^3";
  });
  row("ended", [](const Run& r) {
    return std::string(r.result.finished ? "no gain left at " : "budget spent at ") + fixed(r.result.end_time, 0) + " s";
  });
  row("planner iterations", [](const Run& r) { return std::to_string(r.result.planner.steps); });
  row("iterations that grew the tree on (no gain near)", [](const Run& r) { return std::to_string(r.result.planner.grown_on); });
  row("gain threshold halvings (end game)", [](const Run& r) { return std::to_string(r.result.planner.threshold_lowered); });
  row("steps back (trapped by a newly seen surface)", [](const Run& r) { return std::to_string(r.result.planner.backtracks); });
  row("routes to a remembered pose (edges flown on them, routes blocked)", [](const Run& r) {
    const PlannerStats& p = r.result.planner;
    return std::to_string(p.routes) + " (" + std::to_string(p.route_steps) + ", " + std::to_string(p.routes_blocked) + ")";
  });
  row("roadmap vertices at the end", [](const Run& r) { return std::to_string(r.result.planner.roadmap_vertices); });
  row("planner time per iteration (simulated, i.e. CPU)", [](const Run& r) {
    return fixed(1e3 * r.result.planning_time / double(std::max<std::uint64_t>(1, r.result.planner.steps)), 1) + " ms";
  });
  row("planner iterations per second of planning", [](const Run& r) {
    return fixed(double(r.result.planner.steps) / std::max(1e-9, r.result.planning_time), 2);
  });
  row("tree nodes per second of planning", [](const Run& r) {
    return fixed(double(r.result.planner.nodes) / std::max(1e-9, r.result.planning_time), 1);
  });
  row("simulated time hovering to plan", [](const Run& r) { return fixed(r.result.planning_time, 0) + " s"; });
  row("simulated time flying", [](const Run& r) { return fixed(r.result.flight_time, 0) + " s"; });
  row("distance flown", [](const Run& r) { return fixed(r.result.flight_distance, 0) + " m"; });
  row("frames inserted / dropped", [](const Run& r) {
    return std::to_string(r.result.insertions.count) + " / " + std::to_string(r.result.frames_dropped);
  });
  row("planner queries while inserting", [](const Run& r) { return std::to_string(r.result.planner.queries_during_insertion); });
  row("closest approach to a surface", [](const Run& r) { return fixed(r.min_clearance, 3) + " m"; });
  row("map memory at the end", [](const Run& r) { return fixed(double(r.memory_bytes) / 1048576.0, 1) + " MiB"; });
  row("map memory, peak over the run", [](const Run& r) { return fixed(double(r.peak_memory_bytes) / 1048576.0, 1) + " MiB"; });
  row("real time of the run", [](const Run& r) { return fixed(r.result.wall_seconds, 0) + " s"; });
  md << "\nTime per query kind (wall clock inside the calls; share of their sum; mean per call):\n\n";
  md << "| query | ";
  for (const Run& run : runs) md << run.result.map_name << " | ";
  md << "\n|---|";
  for (std::size_t i = 0; i < runs.size(); ++i) md << "---|";
  md << '\n';
  for (std::size_t k = 0; k < 4; ++k) {
    md << "| " << shares_of(runs.front())[k].kind << " | ";
    for (const Run& run : runs) {
      const std::vector<Share> shares = shares_of(run);
      double total = 0.0;
      for (const Share& s : shares) total += s.tally.seconds;
      const QueryTally& t = shares[k].tally;
      md << fixed(t.seconds, 1) << " s, " << fixed(100.0 * t.seconds / std::max(1e-12, total), 1) << "%, "
         << t.count << " calls, " << fixed(1e3 * t.seconds / double(std::max<std::uint64_t>(1, t.count)), 3)
         << " ms | ";
    }
    md << '\n';
  }
  for (const Run& run : runs) {
    if (run.exclusive_seconds >= 0.0) {
      md << "\n" << run.result.map_name << ": inserting kept queries out for " << fixed(run.exclusive_seconds, 2)
         << " s in all (InsertStats::exclusive_seconds; this waiting is not charged to simulated time).\n";
    }
    if (run.field_update_seconds >= 0.0) {
      const ClearanceCounts& c = run.clearance_counts;
      md << "\n" << run.result.map_name << ": clearance from a distance field (max distance "
         << fixed(options.field_max_distance, 2) << " m): updating it after each frame took "
         << fixed(run.field_update_seconds, 2) << " CPU seconds in all (part of the insertion row); balls "
         << c.balls_by_field << " decided by the field, " << c.balls_by_map << " by the map; capsules "
         << c.capsules_by_field << " by the field, " << c.capsules_by_map << " by the map; " << c.field_queries
         << " field queries.\n";
    }
  }
  return md.str();
}

std::string summary_json(const std::vector<Run>& runs, double reachable_m3) {
  std::ostringstream j;
  j << "{\"reachable_m3\": " << fixed(reachable_m3, 3) << ", \"explorers\": [";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const ExplorationResult& r = runs[i].result;
    j << (i ? ", " : "") << "{\"name\": \"" << r.map_name << "\", \"time_to_95\": " << fixed(r.time_to(0.95), 2)
      << ", \"time_to_90\": " << fixed(r.time_to(0.9), 2)
      << ", \"final_coverage\": " << fixed(r.coverage.empty() ? 0.0 : r.coverage.back().coverage, 5)
      << ", \"finished\": " << (r.finished ? "true" : "false") << ", \"end_time\": " << fixed(r.end_time, 2)
      << ", \"steps\": " << r.planner.steps << ", \"grown_on\": " << r.planner.grown_on
      << ", \"routes\": " << r.planner.routes << ", \"route_steps\": " << r.planner.route_steps << ", \"nodes\": " << r.planner.nodes
      << ", \"planning_time\": " << fixed(r.planning_time, 3) << ", \"flight_time\": " << fixed(r.flight_time, 3)
      << ", \"node_check_seconds\": " << fixed(r.planner.node_checks.seconds, 4)
      << ", \"edge_check_seconds\": " << fixed(r.planner.edge_checks.seconds, 4)
      << ", \"gain_seconds\": " << fixed(r.planner.gains.seconds, 4)
      << ", \"insert_seconds\": " << fixed(r.insertions.seconds, 4) << ", \"frames\": " << r.insertions.count
      << ", \"frames_dropped\": " << r.frames_dropped
      << ", \"queries_during_insertion\": " << r.planner.queries_during_insertion
      << ", \"min_clearance\": " << fixed(runs[i].min_clearance, 4) << ", \"wall_seconds\": " << fixed(r.wall_seconds, 1)
      << ", \"field_update_seconds\": " << fixed(runs[i].field_update_seconds, 4)
      << ", \"memory_bytes\": " << runs[i].memory_bytes << ", \"peak_memory_bytes\": " << runs[i].peak_memory_bytes
      << "}";
  }
  j << "]}\n";
  return j.str();
}

int run_study(const StudyOptions& options) {
  const std::filesystem::path out(options.out);
  std::filesystem::create_directories(out);
  const sim::IndustrialPlant plant = sim::make_industrial_scene(options.seed);
  const ExplorerConfig config = config_for(options, plant);
  const sim::ReachableSpace truth(plant.scene, plant.interior, options.resolution, config.planner.robot_radius,
                                  plant.start);
  std::printf("plant: %zu primitives; reachable free space %.1f m^3 (%zu cells of %g m)\n",
              plant.scene.primitive_count(), truth.volume(), truth.cell_count(), options.resolution);
  const Pose start{plant.start, 0.0};

  std::vector<Run> runs;
  std::unique_ptr<UmbraExplorationMap> umbra_map;
  for (const std::string& name : options.explorers) {
    std::unique_ptr<ExplorationMap> map;
    if (name == "umbra") {
      UmbraMapOptions umbra_options;
      umbra_options.resolution = options.resolution;
      umbra_options.gain = options.gain == "fast" ? GainMethod::fast : GainMethod::exact;
      umbra_options.clearance =
          options.clearance == "field" ? ClearanceSource::distance_field : ClearanceSource::collision_checks;
      umbra_options.field_max_distance = options.field_max_distance;
      umbra_options.window_half_extent = options.window_half_extent;
      umbra_map = std::make_unique<UmbraExplorationMap>(umbra_options);
    } else {
      map = std::make_unique<OctomapExplorationMap>(options.resolution);
    }
    ExplorationMap& chosen = map ? *map : *umbra_map;
    std::printf("exploring with %s...\n", name.c_str());
    std::fflush(stdout);
    double reported = -1e9;
    Run run;
    run.result = explore(chosen, plant.scene, truth, start, config, [&](const CoverageSample& s) {
      // Called with the mapping thread paused: the map holds still.
      run.memory.push_back(chosen.memory_bytes());
      run.peak_memory_bytes = std::max(run.peak_memory_bytes, run.memory.back());
      if (s.time - reported >= 60.0) {
        reported = s.time;
        std::fprintf(stderr, "  %s: %5.0f s simulated, coverage %5.1f%%\n", name.c_str(), s.time, 100.0 * s.coverage);
      }
    });
    run.memory_bytes = chosen.memory_bytes();
    run.peak_memory_bytes = std::max(run.peak_memory_bytes, run.memory_bytes);
    run.min_clearance = min_clearance(run.result, plant.scene);
    if (!map) {
      run.exclusive_seconds = umbra_map->exclusive_seconds();
      if (const FieldClearance* clearance = umbra_map->field_clearance()) {
        run.field_update_seconds = umbra_map->field_update_seconds();
        run.clearance_counts = clearance->counts();
      }
    }
    std::printf("  %s: coverage %.1f%% at %.0f s, 95%% %s; %.0f s of real time\n", name.c_str(),
                run.result.coverage.empty() ? 0.0 : 100.0 * run.result.coverage.back().coverage, run.result.end_time,
                time_or_never(run.result.time_to(0.95)).c_str(), run.result.wall_seconds);
    runs.push_back(std::move(run));
  }

  write_text(out / "coverage.csv", coverage_csv(runs, options.budget, options.coverage_period), "coverage table");
  const std::string markdown = summary_markdown(runs, options, truth.volume());
  write_text(out / "summary.md", markdown, "summary");
  write_text(out / "summary.json", summary_json(runs, truth.volume()), "summary");
  std::printf("\n%s\n", markdown.c_str());
  if (umbra_map) {
    save_map(umbra_map->map(), out / "umbra.umb");
    if (cli::viewer_page_available()) {
      const cli::ViewerData data = cli::collect_viewer_data(umbra_map->map(), cli::kDefaultViewerBudget);
      write_text(out / "umbra.html", cli::viewer_page(umbra_map->map(), data, "exploration: umbra map"), "page");
    } else {
      std::printf("umbra.html not written: this build has no viewer page (node and npm were missing)\n");
    }
  }
  const std::string plot = std::string("\"") + UMBRA_PLOT_PYTHON + "\" \"" + UMBRA_PLOT_SCRIPT + "\" \"" +
                           (out / "coverage.csv").string() + "\" \"" + (out / "coverage.png").string() + "\"";
  if (std::system(plot.c_str()) != 0) {
    std::printf("coverage.png not written: the plot needs python3 with matplotlib (Debian: python3-matplotlib):\n  %s\n",
                plot.c_str());
  }
  std::printf("wrote %s\n", out.string().c_str());
  return 0;
}

}  // namespace
}  // namespace umbra::explore

int main(int argc, char** argv) {
  umbra::explore::StudyOptions options;
  CLI::App app("The UFOMap paper's exploration case study: the same next-best-view explorer on umbra and on "
               "OctoMap in a procedural plant (docs/exploration.md)");
  app.add_option("-o,--out", options.out, "folder for the results")->capture_default_str();
  app.add_option("--budget", options.budget, "seconds of simulated time per explorer")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_flag("--real-time", options.real_time, "simulate in real time instead of as fast as possible");
  app.add_option("--seed", options.seed, "seed of the plant and of the planners")->capture_default_str();
  app.add_option("--resolution", options.resolution, "map voxel edge, metres")
      ->capture_default_str()
      ->check(CLI::Range(0.02, 1.0));
  app.add_option("--gain", options.gain, "umbra's information gain method")
      ->capture_default_str()
      ->check(CLI::IsMember({"exact", "fast"}));
  app.add_option("--explorers", options.explorers, "which explorers run, in order")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember({"umbra", "octomap"}));
  app.add_option("--image-width", options.image_width, "depth image width, pixels")->capture_default_str()->check(CLI::Range(8, 4096));
  app.add_option("--image-height", options.image_height, "depth image height, pixels")->capture_default_str()->check(CLI::Range(8, 4096));
  app.add_option("--speed", options.speed, "robot speed, m/s")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--yaw-rate", options.yaw_rate, "robot turn rate, rad/s")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-nodes", options.max_nodes, "planner tree nodes at most per step")->capture_default_str()->check(CLI::Range(15, 100000));
  app.add_flag("!--no-routing", options.routing,
               "never route to remembered poses over the roadmap (the local tree alone, as before)");
  app.add_option("--yaw-samples", options.yaw_samples, "headings tried per planner node (the best gain is kept)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--extension-range", options.extension_range, "planner edge length at most, metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--coverage-period", options.coverage_period, "seconds of simulated time between coverage samples")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--clearance", options.clearance,
                 "umbra's ball and capsule checks: the map's collision checks, or a distance field updated after "
                 "every frame (the same answers; docs/exploration.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"collision", "field"}));
  app.add_option("--field-max-distance", options.field_max_distance,
                 "the distance field's max distance, metres (with --clearance field)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 10.0));
  app.add_option("--window-half-extent", options.window_half_extent,
                 "umbra's map keeps only a box of at least this many metres around the robot (a map that moves; "
                 "0: the whole map)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);
  try {
    return umbra::explore::run_study(options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "umbra_explore_study: %s\n", error.what());
    return 1;
  }
}
