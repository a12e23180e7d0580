// The input lines of `umbra query` (query_lines.hpp): a hand-written word
// splitter over std::from_chars (no locale, no allocation but the values),
// and the dispatch of a checked line to the library's is_free / cast_ray /
// information_gain.
#include "query_lines.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>

#include "printable_text.hpp"

namespace umbra::cli {

std::optional<LineQuery> line_query_named(std::string_view name) {
  for (const LineQuery kind :
       {LineQuery::sphere, LineQuery::box, LineQuery::line, LineQuery::raycast, LineQuery::gain}) {
    if (name == to_string(kind)) return kind;
  }
  return std::nullopt;
}

const char* to_string(LineQuery kind) {
  switch (kind) {
    case LineQuery::sphere: return "sphere";
    case LineQuery::box: return "box";
    case LineQuery::line: return "line";
    case LineQuery::raycast: return "raycast";
    case LineQuery::gain: return "gain";
  }
  return "?";
}

std::size_t numbers_of(LineQuery kind) {
  switch (kind) {
    case LineQuery::sphere: return 4;
    case LineQuery::box: return 6;
    case LineQuery::line: return 6;
    case LineQuery::raycast: return 7;
    case LineQuery::gain: return 5;
  }
  return 0;
}

const char* layout_of(LineQuery kind) {
  switch (kind) {
    case LineQuery::sphere: return "x y z r";
    case LineQuery::box: return "minx miny minz maxx maxy maxz";
    case LineQuery::line: return "x1 y1 z1 x2 y2 z2";
    case LineQuery::raycast: return "x y z dx dy dz max_range";
    case LineQuery::gain: return "x y z yaw_deg pitch_deg";
  }
  return "?";
}

namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == '\r' || c == ','; }

}  // namespace

std::optional<std::string> parse_query_line(std::string_view text, LineQuery kind, std::vector<double>& values) {
  values.clear();
  const std::size_t expected = numbers_of(kind);
  std::size_t words = 0;
  std::size_t at = 0;
  while (at < text.size()) {
    while (at < text.size() && is_separator(text[at])) ++at;
    if (at == text.size()) break;
    std::size_t end = at;
    while (end < text.size() && !is_separator(text[end])) ++end;
    const std::string_view word = text.substr(at, end - at);
    // from_chars takes no '+'; a user writing "+1" means 1 (but "+-1" stays wrong).
    const std::string_view digits = word.size() > 1 && word[0] == '+' && word[1] != '-' ? word.substr(1) : word;
    double value = 0.0;
    const auto [ptr, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (error == std::errc::result_out_of_range && ptr == digits.data() + digits.size()) {
      values.clear();
      return "'" + printable(word) + "' is beyond the range of a double";
    }
    if (error != std::errc() || ptr != digits.data() + digits.size() || !std::isfinite(value)) {
      values.clear();
      return "'" + printable(word) + "' is not a finite number";
    }
    if (++words <= expected) values.push_back(value);  // a line of a million numbers holds only `expected`
    at = end;
  }
  if (words != expected) {
    values.clear();
    return "expected " + std::to_string(expected) + " numbers (" + layout_of(kind) + "), found " +
           std::to_string(words);
  }
  return std::nullopt;
}

QueryLines read_query_lines(std::istream& in, LineQuery kind) {
  QueryLines lines;
  std::string text;
  std::size_t number = 0;
  std::vector<double> values;
  while (std::getline(in, text)) {
    ++number;
    const std::size_t first = text.find_first_not_of(" \t\r");
    if (first == std::string::npos || text[first] == '#') continue;
    if (auto problem = parse_query_line(text, kind, values)) {
      lines.bad.push_back({number, std::move(*problem)});
      continue;
    }
    lines.good.push_back({number, values});
  }
  if (in.bad()) throw std::runtime_error("the input could not be read (after line " + std::to_string(number) + ")");
  return lines;
}

QueryAnswer answer_query_line(const OccupancyMap& map, LineQuery kind, std::span<const double> v,
                              const LineQuerySettings& settings) {
  if (v.size() != numbers_of(kind)) {
    throw std::logic_error(std::string("answer_query_line: ") + to_string(kind) + " needs " +
                           std::to_string(numbers_of(kind)) + " values, got " + std::to_string(v.size()));
  }
  const CollisionOptions& collision = settings.collision;
  QueryAnswer a;
  try {
    switch (kind) {
      case LineQuery::sphere:
        a.yes = !map.is_free(Sphere{{v[0], v[1], v[2]}, v[3]}, collision).free;
        break;
      case LineQuery::box:
        a.yes = !map.is_free(Aabb{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}}, collision).free;
        break;
      case LineQuery::line:
        if (settings.radius != 0.0) {  // a NaN or negative radius goes to the library, which refuses it
          a.yes = !map.is_free(Capsule{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, settings.radius}, collision).free;
        } else {
          a.yes = !map.is_free(Segment{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}}, collision).free;
        }
        break;
      case LineQuery::raycast: {
        const RayHit hit = map.cast_ray({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], false, collision.depth});
        a.yes = hit.hit;
        a.point = hit.node.center;
        break;
      }
      case LineQuery::gain: {
        const Frustum view = Frustum::from_degrees({v[0], v[1], v[2]}, v[3], v[4], settings.hfov, settings.vfov,
                                                   settings.min_range, settings.max_range);
        GainOptions gain_options;
        gain_options.method = settings.method;
        a.gain = map.information_gain(view, gain_options);
        break;
      }
    }
    a.ok = true;
  } catch (const std::invalid_argument& e) {
    a.problem = e.what();
  } catch (const std::out_of_range& e) {
    a.problem = e.what();
  }
  return a;
}

}  // namespace umbra::cli
