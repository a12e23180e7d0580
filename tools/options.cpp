// Option checks and --max-memory (options.hpp).
#include "options.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "umbra/core/memory_limit.hpp"
#include "umbra/io/map_formats.hpp"

namespace umbra::cli {
namespace {

/// The whole text as a double (strtod: "nan" and "inf" too; beyond double range, +-inf or 0).
bool parse_double(const std::string& text, double& value) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

/// As people write bounds: 0.0001, 1000, 16.
std::string bound_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

/// "--bbox " before a message, or nothing where CLI11 names the option itself.
std::string named(const std::string& option) { return option.empty() ? std::string() : option + " "; }

}  // namespace

CLI::Validator number_in(double low, double high, const std::string& what) {
  return CLI::Validator(
      [low, high, what](std::string& text) -> std::string {
        double value = 0.0;
        if (!parse_double(text, value) || !(value >= low && value <= high)) {
          return what + " must be a number in [" + bound_text(low) + ", " + bound_text(high) + "], got '" + text + "'";
        }
        return "";
      },
      "NUMBER in [" + bound_text(low) + ", " + bound_text(high) + "]");
}

CLI::Validator not_nan() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0.0;
        if (!parse_double(text, value) || std::isnan(value)) return "expected a number, got '" + text + "'";
        return "";
      },
      "NUMBER");
}

std::uint64_t parse_size(const std::string& text) {
  const auto bad = [&] {
    return UsageError("--max-memory expects a size such as 512M, 2G or 1.5GiB (bytes without a unit), got '" + text +
                      "'");
  };
  double number = 0.0;
  const char* const end = text.data() + text.size();
  const auto [unit, status] = std::from_chars(text.data(), end, number);
  if (status != std::errc() || unit == text.data() || !(number > 0.0)) throw bad();
  std::string suffix(unit, end);
  double scale = 1.0;
  if (!suffix.empty()) {
    const std::string units = "KMGT";
    const std::size_t power = units.find(static_cast<char>(std::toupper(static_cast<unsigned char>(suffix[0]))));
    if (power == std::string::npos) throw bad();
    scale = std::ldexp(1.0, 10 * static_cast<int>(power + 1));
    suffix.erase(0, 1);
    if (!(suffix.empty() || suffix == "B" || suffix == "iB")) throw bad();
  }
  const double bytes = number * scale;
  if (!(bytes >= 1.0 && bytes < 1.8e19)) throw bad();
  return static_cast<std::uint64_t>(bytes);
}

std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    double value = 0.0;
    if (!parse_double(item, value) || !std::isfinite(value)) {
      throw std::invalid_argument(named(option) + "expects " + std::to_string(count) +
                                  " finite numbers separated by commas, got '" + text + "'");
    }
    values.push_back(value);
  }
  if (values.size() != count) {
    throw std::invalid_argument(named(option) + "expects " + std::to_string(count) +
                                " numbers separated by commas, got '" + text + "'");
  }
  return values;
}

Aabb parse_box(const std::string& text, const std::string& option) {
  const std::vector<double> b = parse_numbers(text, 6, option);
  const Aabb box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
  if (!(box.min.x <= box.max.x && box.min.y <= box.max.y && box.min.z <= box.max.z)) {
    throw std::invalid_argument(named(option) + "expects minx,miny,minz,maxx,maxy,maxz with each min <= its max, got '" +
                                text + "'");
  }
  return box;
}

CLI::Validator box_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          (void)parse_box(text, "");  // CLI11 puts the option's name before the message
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "minx,miny,minz,maxx,maxy,maxz");
}

CLI::Validator map_extension() {
  return CLI::Validator(
      [](std::string& name) -> std::string {
        try {
          (void)map_file_format_for(name);
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "MAP(.umb|.bt|.ot)");
}

void add_memory_option(CLI::App& command) {
  auto text = std::make_shared<std::string>();
  command.add_option("--max-memory", *text,
                     "the most memory one map file or scan may need, e.g. 4G (default: half of this machine's "
                     "memory or of the process's limit)")
      ->check(CLI::Validator(
          [](std::string& value) -> std::string {
            try {
              (void)parse_size(value);
              return "";
            } catch (const UsageError& e) {
              return e.what();
            }
          },
          "SIZE"));
  command.callback([text] {
    if (!text->empty()) set_memory_limit(parse_size(*text));
  });
}

}  // namespace umbra::cli
