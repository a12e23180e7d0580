// The input lines of `umbra query` (query_lines.hpp): a reader of one line
// at a time into a fixed buffer, a hand-written word splitter over
// std::from_chars (no locale, no allocation but the values), and the
// dispatch of a checked line to the library's is_free / cast_ray /
// information_gain.
#include "query_lines.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>

#include "printable_text.hpp"

namespace umbra::cli {

std::optional<LineQuery> line_query_named(std::string_view name) {
  for (const LineQuery kind :
       {LineQuery::sphere, LineQuery::box, LineQuery::line, LineQuery::raycast, LineQuery::gain, LineQuery::distance}) {
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
    case LineQuery::distance: return "distance";
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
    case LineQuery::distance: return 3;
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
    case LineQuery::distance: return "x y z";
  }
  return "?";
}

const char* answer_of(LineQuery kind) {
  switch (kind) {
    case LineQuery::sphere: return "1 if a voxel in the ball blocks (occupied, or unknown unless --unknown free), else 0";
    case LineQuery::box: return "1 if a voxel in the box blocks, else 0";
    case LineQuery::line: return "1 if a voxel along the segment blocks (--radius R: in the capsule around it), else 0";
    case LineQuery::raycast: return "'1 cx cy cz', the centre of the first occupied voxel within max_range, or 0";
    case LineQuery::gain: return "'unknown_voxels volume_m3': the unknown space a sensor at that pose would see";
    case LineQuery::distance:
      return "'d_occupied d_unknown gx gy gz': metres to the nearest occupied and unknown voxel (capped at "
             "--max-distance) and the unit gradient away from the nearest blocking one";
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

QueryLineReader::QueryLineReader(std::istream& in, LineQuery kind)
    : in_(in), kind_(kind), text_(kMaxQueryLineBytes + 1, '\0') {}

const QueryLine* QueryLineReader::next() {
  for (;;) {
    // istream::getline into a buffer of fixed size: it stops after
    // kMaxQueryLineBytes bytes (failbit, newline not reached) instead of
    // growing a string for as long as the input has no newline.
    in_.getline(text_.data(), static_cast<std::streamsize>(text_.size()));
    if (in_.bad()) {
      throw std::runtime_error("the input could not be read (after line " + std::to_string(number_) + ")");
    }
    const auto count = static_cast<std::size_t>(in_.gcount());
    const bool too_long = in_.fail() && !in_.eof() && count == kMaxQueryLineBytes;
    if (in_.fail() && !too_long) return nullptr;  // nothing left: failbit with nothing extracted
    // The newline, when one ended the line, is counted but not stored.
    const std::size_t length = too_long || in_.eof() ? count : count - 1;
    const std::string_view text(text_.data(), length);
    ++number_;
    line_.number = number_;
    line_.problem.clear();
    const std::size_t first = text.find_first_not_of(" \t\r");
    const bool comment = first != std::string_view::npos && text[first] == '#';
    if (too_long) {
      in_.clear();
      in_.ignore(std::numeric_limits<std::streamsize>::max(), '\n');  // the rest of the line, kept nowhere
      if (in_.bad()) {
        throw std::runtime_error("the input could not be read (in line " + std::to_string(number_) + ")");
      }
      if (comment) continue;
      const auto rest = static_cast<std::size_t>(in_.gcount()) - (in_.eof() ? 0 : 1);
      line_.values.clear();
      line_.problem = "the line holds " + std::to_string(length + rest) + " bytes, more than the " +
                      std::to_string(kMaxQueryLineBytes) + " a query line may hold";
      return &line_;
    }
    if (first == std::string_view::npos || comment) continue;
    if (auto problem = parse_query_line(text, kind_, line_.values)) line_.problem = std::move(*problem);
    return &line_;
  }
}

bool QueryLineReader::input_ready() const { return in_.good() && in_.rdbuf()->in_avail() > 0; }

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
      case LineQuery::distance:
        if (settings.field == nullptr) throw std::logic_error("answer_query_line: distance needs settings.field");
        a.sample = settings.field->distance_and_gradient({v[0], v[1], v[2]});
        break;
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
