// The input lines of `umbra query` (sphere, box, line, raycast, gain): what a line
// must hold, reading and checking the lines of an input one by one, and
// answering one checked line against a map. Kept apart from the command
// (query_command.cpp) so that the libFuzzer target fuzz/fuzz_query_lines.cpp
// feeds lines through exactly this code without the command-line parser.
// Cost: reading is one pass over the text with no allocation per line (one
// buffer of kMaxQueryLineBytes, the values and the message of a bad line
// reused); answering is the library's query.
#pragma once

#include <cstddef>
#include <istream>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/distance_field.hpp"
#include "umbra/query/information_gain.hpp"

namespace umbra::cli {

/// The kinds of query that read lines, with their layout.
enum class LineQuery { sphere, box, line, raycast, gain, distance };

/// "sphere", "box", "line", "raycast", "gain" or "distance"; nullopt for anything else.
std::optional<LineQuery> line_query_named(std::string_view name);
const char* to_string(LineQuery kind);
/// How many numbers a line of this kind holds, and their names ("x y z r").
std::size_t numbers_of(LineQuery kind);
const char* layout_of(LineQuery kind);
/// What the answer line to one input line holds, in words (`umbra query --help`).
const char* answer_of(LineQuery kind);
/// Every kind that reads lines, in the order the help lists them.
inline constexpr LineQuery kLineQueries[] = {LineQuery::sphere, LineQuery::box,  LineQuery::line,
                                             LineQuery::raycast, LineQuery::gain, LineQuery::distance};

/// The numbers of one line (blank and '#' lines are not passed here):
/// separated by spaces, tabs or commas, each finite, exactly numbers_of(kind)
/// of them. Returns what is wrong (with `values` empty), or nullopt with
/// `values` filled.
std::optional<std::string> parse_query_line(std::string_view text, LineQuery kind, std::vector<double>& values);

/// The longest line a query may be, in bytes without its newline: far more
/// than any layout needs (7 numbers), small enough that a file with no
/// newline cannot fill the memory. A longer line is bad; a longer comment
/// is skipped.
inline constexpr std::size_t kMaxQueryLineBytes = 65536;

/// One line that was read: its number (from 1), and its values when it is
/// good or what is wrong with it when it is not.
struct QueryLine {
  std::size_t number = 0;
  std::vector<double> values;  ///< numbers_of(kind) values when good, empty when bad
  std::string problem;         ///< empty when good
  [[nodiscard]] bool good() const { return problem.empty(); }
};

/// The lines of an input, one at a time, so that `umbra query` answers a
/// line as soon as it arrives and holds at most one line (and a buffer)
/// whatever the input's length. Blank lines and lines starting with '#'
/// (after blanks) are skipped.
class QueryLineReader {
 public:
  QueryLineReader(std::istream& in, LineQuery kind);

  /// The next line that is not blank or a comment, or nullptr at the end of
  /// the input; valid until the next call. Throws std::runtime_error when
  /// the stream fails to read (bad lines are not errors: they come back
  /// with their problem).
  const QueryLine* next();

  /// Whether the stream holds more input that next() can read without
  /// waiting (buffered, or ready in the file or pipe). False means that
  /// next() may wait for a writer, or that the input ended: answers waiting
  /// to be printed should be flushed first. From std::streambuf::in_avail().
  [[nodiscard]] bool input_ready() const;

 private:
  std::istream& in_;
  LineQuery kind_;
  std::string text_;  ///< kMaxQueryLineBytes + 1 bytes, reused for every line
  QueryLine line_;
  std::size_t number_ = 0;
};

/// One answer: collides / hit, the centre of the voxel hit (raycast), the
/// gain, or the reason there is no answer (the library's
/// std::invalid_argument or std::out_of_range message: a negative radius, a
/// shape outside the map...).
struct QueryAnswer {
  bool ok = false;
  bool yes = false;
  Vec3d point;
  GainResult gain{};
  DistanceSample sample;  ///< distance
  std::string problem;
};

/// What the command line sets for every line.
struct LineQuerySettings {
  CollisionOptions collision;  ///< sphere, box, line, raycast (its depth)
  /// line: other than 0 turns the segment into a capsule (so a negative or
  /// NaN radius is refused like any bad capsule).
  double radius = 0.0;
  double hfov = 115.0;  ///< gain: the field of view in degrees and the ranges in metres
  double vfov = 60.0;
  double min_range = 0.0;
  double max_range = 6.5;
  GainMethod method = GainMethod::exact;
  /// distance: the field to ask (made from the map with --max-distance and --depth).
  const DistanceField* field = nullptr;
};

/// Answers one line's values (numbers_of(kind) of them, as parse_query_line
/// gives them). Raycasts pass through unknown space and stop at the first
/// occupied voxel.
QueryAnswer answer_query_line(const OccupancyMap& map, LineQuery kind, std::span<const double> values,
                              const LineQuerySettings& settings);

}  // namespace umbra::cli
