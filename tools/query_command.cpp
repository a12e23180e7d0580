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
// lines and lines starting with '#' are skipped.
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "commands.hpp"
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

/// One input line: its number and its values.
struct Line {
  std::size_t number;
  std::vector<double> values;
};

/// The values of `text`, or a message saying what is wrong with them.
std::optional<std::string> parse_numbers(std::string_view text, std::size_t expected, const char* layout,
                                         std::vector<double>& values) {
  values.clear();
  std::size_t at = 0;
  while (at < text.size()) {
    while (at < text.size() && (text[at] == ' ' || text[at] == '\t' || text[at] == '\r' || text[at] == ',')) ++at;
    if (at == text.size()) break;
    std::size_t end = at;
    while (end < text.size() && text[end] != ' ' && text[end] != '\t' && text[end] != '\r' && text[end] != ',') ++end;
    const std::string_view word = text.substr(at, end - at);
    double value = 0.0;
    const auto [ptr, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (error != std::errc() || ptr != word.data() + word.size() || !std::isfinite(value)) {
      return "'" + std::string(word) + "' is not a finite number";
    }
    values.push_back(value);
    at = end;
  }
  if (values.size() != expected) {
    return "expected " + std::to_string(expected) + " numbers (" + layout + "), found " +
           std::to_string(values.size());
  }
  return std::nullopt;
}

struct Kind {
  std::size_t numbers;
  const char* layout;
};

Kind kind_of(const std::string& kind) {
  if (kind == "sphere") return {4, "x y z r"};
  if (kind == "box") return {6, "minx miny minz maxx maxy maxz"};
  if (kind == "line") return {6, "x1 y1 z1 x2 y2 z2"};
  if (kind == "raycast") return {7, "x y z dx dy dz max_range"};
  if (kind == "gain") return {5, "x y z yaw_deg pitch_deg"};
  throw std::logic_error("unknown query kind " + kind);
}

/// Reads every line of the input; bad lines are reported and dropped.
std::vector<Line> read_lines(std::istream& in, const std::string& name, const Kind& kind, std::size_t& bad) {
  std::vector<Line> lines;
  std::string text;
  std::size_t number = 0;
  std::vector<double> values;
  while (std::getline(in, text)) {
    ++number;
    const std::size_t first = text.find_first_not_of(" \t\r");
    if (first == std::string::npos || text[first] == '#') continue;
    if (const auto problem = parse_numbers(text, kind.numbers, kind.layout, values)) {
      std::fprintf(stderr, "umbra: %s line %zu: %s\n", name.c_str(), number, problem->c_str());
      ++bad;
      continue;
    }
    lines.push_back({number, values});
  }
  if (in.bad()) throw std::runtime_error("cannot read " + name);
  return lines;
}

/// One answer: a line of output, or the reason there is none.
struct Answer {
  bool ok = false;
  bool yes = false;     // collides / hit
  Vec3d point;          // raycast: the centre of the voxel hit
  GainResult gain{};    // gain
  std::string problem;  // when !ok
};

Answer answer(const OccupancyMap& map, const QueryOptions& options, const std::vector<double>& v,
              const CollisionOptions& collision) {
  const std::string& kind = options.kind;
  const double radius = options.radius;
  Answer a;
  try {
    if (kind == "gain") {
      const Frustum view = Frustum::from_degrees({v[0], v[1], v[2]}, v[3], v[4], options.hfov, options.vfov,
                                                 options.min_range, options.max_range);
      GainOptions gain_options;
      gain_options.method = options.method == "fast" ? GainMethod::fast : GainMethod::exact;
      a.gain = map.information_gain(view, gain_options);
    } else if (kind == "sphere") {
      a.yes = !map.is_free(Sphere{{v[0], v[1], v[2]}, v[3]}, collision).free;
    } else if (kind == "box") {
      const Aabb box{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
      a.yes = !map.is_free(box, collision).free;
    } else if (kind == "line") {
      if (radius > 0.0) {
        a.yes = !map.is_free(Capsule{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, radius}, collision).free;
      } else {
        a.yes = !map.is_free(Segment{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}}, collision).free;
      }
    } else {  // raycast: the first occupied voxel; unknown space is passed through
      const RayHit hit = map.cast_ray({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], false, collision.depth});
      a.yes = hit.hit;
      a.point = hit.node.center;
    }
    a.ok = true;
  } catch (const std::invalid_argument& e) {
    a.problem = e.what();
  } catch (const std::out_of_range& e) {
    a.problem = e.what();
  }
  return a;
}

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
  const Kind kind = kind_of(options.kind);
  std::size_t bad = 0;
  std::vector<Line> lines;
  if (options.input == "-") {
    lines = read_lines(std::cin, "standard input", kind, bad);
  } else {
    std::ifstream in(options.input);
    if (!in) throw std::runtime_error("cannot open " + options.input + " for reading");
    lines = read_lines(in, options.input, kind, bad);
  }
  const CollisionOptions collision{options.unknown == "free", options.depth};

  std::vector<Answer> answers;
  answers.reserve(lines.size());
  const auto start = std::chrono::steady_clock::now();
  for (const Line& line : lines) answers.push_back(answer(map, options, line.values, collision));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (std::size_t i = 0; i < answers.size(); ++i) {
    const Answer& a = answers[i];
    if (!a.ok) {
      std::fprintf(stderr, "umbra: %s line %zu: %s\n", options.input == "-" ? "standard input" : options.input.c_str(),
                   lines[i].number, a.problem.c_str());
      ++bad;
    } else if (options.kind == "gain") {
      std::printf("%llu %.10g\n", static_cast<unsigned long long>(a.gain.unknown_voxels), a.gain.volume);
    } else if (options.kind == "raycast" && a.yes) {
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
      ->check(CLI::NonNegativeNumber);
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
  return [options] { return run_query(*options); };
}

}  // namespace umbra::cli
