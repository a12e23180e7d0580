// `umbra query MAP KIND --input FILE|-`: answers queries about a map, one
// per input line, one answer per output line, in order.
//
//   sphere    x y z r                      -> 1 if the ball collides, else 0
//   box       minx miny minz maxx maxy maxz -> 1 / 0
//   line      x1 y1 z1 x2 y2 z2             -> 1 / 0 (--radius R: the capsule)
//   raycast   x y z dx dy dz max_range      -> "1 cx cy cz" (first occupied voxel's centre) or 0
//   gain      x y z yaw_deg pitch_deg        -> "unknown_voxels volume_m3" seen from that pose
//             (--hfov, --vfov, --min-range, --max-range, --method exact|fast)
//   nodes     (no input) --state S [--box ..|--sphere ..] [--count] -> "x y z size state" per node
//
// All lines are read and checked first, then answered in one timed loop,
// then printed, so that the timing on stderr's last line (one JSON object)
// is the answering alone. A bad line (not the right count of numbers, a
// number that is not finite, a shape outside the map) is reported on stderr
// with its line number and gets no answer; the exit code is then 1. Blank
// lines and lines starting with '#' are skipped. The lines' parser and the
// answering are query_lines.cpp (fuzzed by fuzz/fuzz_query_lines.cpp).
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "options.hpp"
#include "query_lines.hpp"
#include "umbra/io/map_formats.hpp"

namespace umbra::cli {
namespace {

struct QueryOptions {
  std::string map_path;
  std::string kind;
  std::string input;
  std::string unknown = "blocks";
  int depth = 0;
  double radius = 0.0;
  // gain
  double hfov = 115.0;
  double vfov = 60.0;
  double min_range = 0.0;
  double max_range = 6.5;
  std::string method = "exact";
  // nodes
  std::string state;
  std::vector<double> box;
  std::vector<double> sphere;
  bool count = false;
};

void print_timing(const std::string& kind, std::size_t queries, double seconds) {
  const double per_query = queries > 0 ? seconds * 1e6 / static_cast<double>(queries) : 0.0;
  std::fprintf(stderr, "{\"kind\": \"%s\", \"queries\": %zu, \"seconds\": %.9g, \"us_per_query\": %.6g}\n",
               kind.c_str(), queries, seconds, per_query);
}

int print_nodes(const OccupancyMap& map, const QueryOptions& options);

int run_nodes(const OccupancyMap& map, const QueryOptions& options) {
  try {
    return print_nodes(map, options);
  } catch (const std::invalid_argument& e) {  // a bad --box or --sphere
    std::fprintf(stderr, "umbra: %s\n", e.what());
    return 2;
  }
}

int print_nodes(const OccupancyMap& map, const QueryOptions& options) {
  Predicate predicate = pred::leaf();
  if (options.state == "occupied") {
    predicate = predicate && pred::occupied();
  } else if (options.state == "free") {
    predicate = predicate && pred::free();
  } else if (options.state == "unknown") {
    predicate = predicate && pred::unknown();
  }
  if (!options.box.empty()) {
    predicate = predicate && pred::intersects(Aabb{{options.box[0], options.box[1], options.box[2]},
                                                   {options.box[3], options.box[4], options.box[5]}});
  }
  if (!options.sphere.empty()) {
    predicate =
        predicate && pred::intersects(Sphere{{options.sphere[0], options.sphere[1], options.sphere[2]}, options.sphere[3]});
  }
  const auto start = std::chrono::steady_clock::now();
  std::size_t count = 0;
  if (options.count) {
    count = map.count(predicate, options.depth);
    std::printf("%zu\n", count);
  } else {
    for (const Node& node : map.query(predicate, options.depth)) {
      std::printf("%.10g %.10g %.10g %.10g %s\n", node.center.x, node.center.y, node.center.z, node.size,
                  to_string(node.state));
      ++count;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  print_timing("nodes", count, seconds);
  return 0;
}

int run_query(const QueryOptions& options) {
  const OccupancyMap map = load_any_map(options.map_path);
  if (options.depth < 0 || options.depth > map.depth_levels()) {
    std::fprintf(stderr, "umbra: --depth %d is outside [0, %d] for this map\n", options.depth, map.depth_levels());
    return 2;
  }
  if (options.kind == "nodes") return run_nodes(map, options);
  if (options.input.empty()) {
    std::fprintf(stderr, "umbra: query %s needs --input FILE (or - for standard input)\n", options.kind.c_str());
    return 2;
  }
  if (options.kind == "gain") {
    try {  // the field of view and ranges, checked once rather than on every line
      Frustum::from_degrees({}, 0.0, 0.0, options.hfov, options.vfov, options.min_range, options.max_range).validate();
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "umbra: query gain: %s\n", e.what());
      return 2;
    }
  }
  const std::optional<LineQuery> kind = line_query_named(options.kind);
  if (!kind) throw std::logic_error("unknown query kind " + options.kind);  // CLI11 checked the name
  const std::string name = options.input == "-" ? "standard input" : options.input;
  QueryLines lines;
  try {
    if (options.input == "-") {
      lines = read_query_lines(std::cin, *kind);
    } else {
      std::ifstream in(options.input);
      if (!in) throw std::runtime_error("cannot be opened for reading");
      lines = read_query_lines(in, *kind);
    }
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(name + ": " + e.what());
  }
  for (const BadQueryLine& line : lines.bad) {
    std::fprintf(stderr, "umbra: %s line %zu: %s\n", name.c_str(), line.number, line.problem.c_str());
  }
  std::size_t bad = lines.bad.size();
  LineQuerySettings settings;
  settings.collision = {options.unknown == "free", options.depth};
  settings.radius = options.radius;
  settings.hfov = options.hfov;
  settings.vfov = options.vfov;
  settings.min_range = options.min_range;
  settings.max_range = options.max_range;
  settings.method = options.method == "fast" ? GainMethod::fast : GainMethod::exact;

  std::vector<QueryAnswer> answers;
  answers.reserve(lines.good.size());
  const auto start = std::chrono::steady_clock::now();
  for (const QueryLine& line : lines.good) {
    answers.push_back(answer_query_line(map, *kind, line.values, settings));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (std::size_t i = 0; i < answers.size(); ++i) {
    const QueryAnswer& a = answers[i];
    if (!a.ok) {
      std::fprintf(stderr, "umbra: %s line %zu: %s\n", name.c_str(), lines.good[i].number, a.problem.c_str());
      ++bad;
    } else if (*kind == LineQuery::gain) {
      std::printf("%llu %.10g\n", static_cast<unsigned long long>(a.gain.unknown_voxels), a.gain.volume);
    } else if (*kind == LineQuery::raycast && a.yes) {
      std::printf("1 %.10g %.10g %.10g\n", a.point.x, a.point.y, a.point.z);
    } else {
      std::printf("%d\n", a.yes ? 1 : 0);
    }
  }
  std::fflush(stdout);
  print_timing(options.kind, answers.size(), seconds);
  return bad > 0 ? 1 : 0;
}

}  // namespace

Command add_query_command(CLI::App& app) {
  auto options = std::make_shared<QueryOptions>();
  CLI::App* command = app.add_subcommand(
      "query", "Answer collision, line, ray-cast, information-gain and node queries about a map, one per input line");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("kind", options->kind, "sphere | box | line | raycast | gain | nodes")
      ->required()
      ->check(CLI::IsMember({"sphere", "box", "line", "raycast", "gain", "nodes"}));
  command->add_option("--input", options->input, "file of queries, one per line; - for standard input");
  command->add_option("--unknown", options->unknown, "unknown space blocks (default) or counts as free")
      ->check(CLI::IsMember({"blocks", "free"}));
  command->add_option("--depth", options->depth, "answer at this depth (0: finest voxels; coarser is conservative)")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--radius", options->radius, "line: check the capsule of this radius (m) around each segment")
      ->check(number_in(0.0, 1e6, "the capsule radius in metres"));
  command->add_option("--hfov", options->hfov, "gain: horizontal field of view (degrees)")
      ->check(CLI::Range(0.0, 180.0, "in (0, 180)"));
  command->add_option("--vfov", options->vfov, "gain: vertical field of view (degrees)")
      ->check(CLI::Range(0.0, 180.0, "in (0, 180)"));
  command->add_option("--min-range", options->min_range, "gain: near range (m)")->check(CLI::NonNegativeNumber);
  command->add_option("--max-range", options->max_range, "gain: far range (m)")->check(CLI::PositiveNumber);
  command->add_option("--method", options->method, "gain: exact, or fast (a few per cent off, faster)")
      ->check(CLI::IsMember({"exact", "fast"}));
  command->add_option("--state", options->state, "nodes: only occupied, free or unknown ones")
      ->check(CLI::IsMember({"occupied", "free", "unknown"}));
  command->add_option("--box", options->box, "nodes: only those meeting minx,miny,minz,maxx,maxy,maxz")
      ->delimiter(',')
      ->expected(6);
  command->add_option("--sphere", options->sphere, "nodes: only those meeting the ball x,y,z,r")
      ->delimiter(',')
      ->expected(4);
  command->add_flag("--count", options->count, "nodes: print only how many there are");
  add_memory_option(*command);
  return [options] { return run_query(*options); };
}

}  // namespace umbra::cli
