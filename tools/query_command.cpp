// `umbra query MAP KIND [--input FILE|-]`: answers queries about a map, one
// per input line, one answer per output line, in order. Without --input the
// lines come from standard input when it is not a terminal.
//
//   sphere    x y z r                      -> 1 if the ball collides, else 0
//   box       minx miny minz maxx maxy maxz -> 1 / 0
//   line      x1 y1 z1 x2 y2 z2             -> 1 / 0 (--radius R: the capsule)
//   raycast   x y z dx dy dz max_range      -> "1 cx cy cz" (first occupied voxel's centre) or 0
//   gain      x y z yaw_deg pitch_deg        -> "unknown_voxels volume_m3" seen from that pose
//             (--hfov, --vfov, --min-range, --max-range, --method exact|fast)
//   distance  x y z --max-distance D         -> "d_occupied d_unknown gx gy gz" (distance_field.hpp)
//   nodes     (no input) --state S [--box ..|--sphere ..] [--count] -> "x y z size state" per node
//
// Lines are answered as they arrive, in bounded memory: the lines the input
// holds ready (up to 4096) are read and checked, answered in one timed loop,
// then printed, and the answers are flushed whenever the next read could
// wait, so a program may write a query and wait for its answer. The timing
// on stderr's last line (one JSON object) is the answering alone, summed
// over these loops. A bad line (not the right count of numbers, a number
// that is not finite, a line over 64 KiB, a shape outside the map) is
// reported on stderr with its line number, in line order, and gets no
// answer; the exit code is then 1. Blank lines and lines starting with '#'
// are skipped. The lines' reader, parser and answering are query_lines.cpp
// (fuzzed by fuzz/fuzz_query_lines.cpp); the input is read through
// descriptor_input.hpp, which tells when a read would wait.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <istream>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "descriptor_input.hpp"
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
  // distance
  double max_distance = 1.0;
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

/// The lines read since the last answers: as many as the input holds ready,
/// up to kLines, so that a file is answered in long timed loops (two clock
/// readings per batch) and a writer waiting for an answer gets it at once.
/// Bad lines keep their place, so that every message comes in line order.
class LineBatch {
 public:
  static constexpr std::size_t kLines = 4096;

  explicit LineBatch(std::size_t numbers) : numbers_(numbers) {
    values_.reserve(kLines * numbers);
    lines_.reserve(kLines);
  }

  /// Reads the next lines; false when the input ended (the batch may still hold lines).
  bool read(QueryLineReader& reader) {
    lines_.clear();
    values_.clear();
    do {
      const QueryLine* line = reader.next();
      if (line == nullptr) return false;
      lines_.push_back({line->number, line->problem});
      values_.insert(values_.end(), line->values.begin(), line->values.end());
    } while (lines_.size() < kLines && reader.input_ready());
    return true;
  }

  struct Line {
    std::size_t number;
    std::string problem;  ///< why the line is bad; empty for a good one
  };
  [[nodiscard]] const std::vector<Line>& lines() const { return lines_; }
  /// The values of the good lines, numbers_of(kind) each, in order.
  [[nodiscard]] std::span<const double> values(std::size_t good_index) const {
    return std::span<const double>(values_).subspan(good_index * numbers_, numbers_);
  }

 private:
  std::size_t numbers_;
  std::vector<Line> lines_;
  std::vector<double> values_;
};

struct QueryTotals {
  std::size_t answered = 0;  ///< good lines given to the library
  std::size_t bad = 0;       ///< lines refused by the parser or the library
  double seconds = 0.0;      ///< time spent answering, reading and printing left out
};

/// Answers the good lines of the batch in one timed loop (into `answers`,
/// reused from batch to batch), then prints the answers on stdout and the
/// problems on stderr, in line order.
void answer_and_print(const OccupancyMap& map, LineQuery kind, const LineQuerySettings& settings,
                      const std::string& name, const LineBatch& batch, std::vector<QueryAnswer>& answers,
                      QueryTotals& totals) {
  answers.clear();
  std::size_t good = 0;
  for (const LineBatch::Line& line : batch.lines()) good += line.problem.empty() ? 1 : 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < good; ++i) answers.push_back(answer_query_line(map, kind, batch.values(i), settings));
  totals.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  totals.answered += good;

  std::size_t next = 0;
  for (const LineBatch::Line& line : batch.lines()) {
    if (!line.problem.empty()) {
      std::fprintf(stderr, "umbra: %s line %zu: %s\n", name.c_str(), line.number, line.problem.c_str());
      ++totals.bad;
      continue;
    }
    const QueryAnswer& a = answers[next++];
    if (!a.ok) {
      std::fprintf(stderr, "umbra: %s line %zu: %s\n", name.c_str(), line.number, a.problem.c_str());
      ++totals.bad;
    } else if (kind == LineQuery::gain) {
      std::printf("%llu %.10g\n", static_cast<unsigned long long>(a.gain.unknown_voxels), a.gain.volume);
    } else if (kind == LineQuery::distance) {
      std::printf("%.10g %.10g %.10g %.10g %.10g\n", a.sample.occupied, a.sample.unknown, a.sample.gradient.x,
                  a.sample.gradient.y, a.sample.gradient.z);
    } else if (kind == LineQuery::raycast && a.yes) {
      std::printf("1 %.10g %.10g %.10g\n", a.point.x, a.point.y, a.point.z);
    } else {
      std::printf("%d\n", a.yes ? 1 : 0);
    }
  }
}

int run_query(const QueryOptions& options) {
  // No --input: standard input, unless it is a terminal (a user who forgot
  // --input would otherwise sit before a program waiting for them). Checked
  // before the map is loaded: a usage error reads nothing.
  const bool line_kind = options.kind != "nodes";
  const bool from_stdin = options.input == "-" || (options.input.empty() && ::isatty(STDIN_FILENO) != 1);
  if (line_kind && options.input.empty() && !from_stdin) {
    throw UsageError("query " + options.kind + " reads one query per line (" +
                     layout_of(*line_query_named(options.kind)) +
                     ") from --input FILE, or from standard input when it is a pipe or a file; standard input is a "
                     "terminal here (use --input - to type the lines)");
  }
  const OccupancyMap map = load_any_map(options.map_path);
  if (options.depth < 0 || options.depth > map.depth_levels()) {
    std::fprintf(stderr, "umbra: --depth %d is outside [0, %d] for this map\n", options.depth, map.depth_levels());
    return 2;
  }
  if (!line_kind) return run_nodes(map, options);
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
  const std::string name = from_stdin ? "standard input" : options.input;
  LineQuerySettings settings;
  settings.collision = {options.unknown == "free", options.depth};
  settings.radius = options.radius;
  settings.hfov = options.hfov;
  settings.vfov = options.vfov;
  settings.min_range = options.min_range;
  settings.max_range = options.max_range;
  settings.method = options.method == "fast" ? GainMethod::fast : GainMethod::exact;
  std::unique_ptr<DistanceField> field;
  if (*kind == LineQuery::distance) {
    // The whole known space, built once before the lines are read (not timed).
    DistanceFieldOptions field_options;
    field_options.max_distance = options.max_distance;
    field_options.depth = options.depth;
    try {
      field = std::make_unique<DistanceField>(map, field_options);
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "umbra: query distance: %s\n", e.what());
      return 2;
    }
    settings.field = field.get();
  }

  std::unique_ptr<DescriptorInput> input;
  try {
    input = from_stdin ? std::make_unique<DescriptorInput>(STDIN_FILENO)
                                 : std::make_unique<DescriptorInput>(options.input);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(name + ": " + e.what());
  }
  std::istream stream(input.get());
  QueryLineReader reader(stream, *kind);
  LineBatch batch(numbers_of(*kind));
  std::vector<QueryAnswer> answers;
  QueryTotals totals;
  bool ended = false;
  while (!ended) {
    try {
      ended = !batch.read(reader);
    } catch (const std::runtime_error& e) {
      const std::string reason = input->read_error().empty() ? "" : ": " + input->read_error();
      answer_and_print(map, *kind, settings, name, batch, answers, totals);  // what came before the failure
      std::fflush(stdout);
      throw std::runtime_error(name + ": " + e.what() + reason);
    }
    answer_and_print(map, *kind, settings, name, batch, answers, totals);
    if (!reader.input_ready()) std::fflush(stdout);  // the next read may wait for the writer: let it see its answers
  }
  std::fflush(stdout);
  print_timing(options.kind, totals.answered, totals.seconds);
  return totals.bad > 0 ? 1 : 0;
}

/// Each kind with its input line and its answer line, for --help.
std::string query_help_footer() {
  std::string text = "Kinds: the numbers of each input line -> the answer line printed for it\n";
  char row[512];
  for (const LineQuery kind : kLineQueries) {
    std::snprintf(row, sizeof row, "  %-8s %-30s -> %s\n", to_string(kind), layout_of(kind), answer_of(kind));
    text += row;
  }
  std::snprintf(row, sizeof row, "  %-8s %-30s -> %s\n", "nodes", "(no input)",
                "'x y z size state' per node (--state, --box, --sphere, --depth), or their count (--count)");
  text += row;
  text +=
      "gain's sensor: --hfov, --vfov (degrees), --min-range, --max-range (m), --method exact|fast.\n"
      "Lines come from --input FILE, from standard input with --input -, or from standard input when --input is not "
      "given and standard input is a pipe or a file. Numbers are separated by spaces, tabs or commas; blank lines and "
      "lines starting with # are skipped; a bad line is reported on stderr with its number, gets no answer, and makes "
      "the exit code 1. The time spent answering is one JSON object on stderr's last line.";
  return text;
}

}  // namespace

Command add_query_command(CLI::App& app) {
  auto options = std::make_shared<QueryOptions>();
  CLI::App* command = app.add_subcommand(
      "query", "Answer collision, line, ray-cast, information-gain, distance and node queries about a map, one per input line");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required();  // a missing file is an input failure (exit code 1), named when it is loaded
  command->add_option("kind", options->kind, "sphere | box | line | raycast | gain | distance | nodes")
      ->required()
      ->check(CLI::IsMember({"sphere", "box", "line", "raycast", "gain", "distance", "nodes"}));
  command->add_option("--input", options->input,
                      "file of queries, one per line; - for standard input (the default when it is a pipe or a file)");
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
  command->add_option("--max-distance", options->max_distance,
                      "distance: distances are capped here (m); the field's cost grows with it")
      ->check(number_in(1e-9, 1e6, "the maximum distance in metres"));
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
  command->footer(query_help_footer());
  return [options] { return run_query(*options); };
}

}  // namespace umbra::cli
