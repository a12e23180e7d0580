// `umbra render MAP -o map.png`: a picture of a map file (.umb, .bt, .ot).
//
// The drawing is the library's (umbra/io/map_render.hpp); the command parses
// the options, checks them against the map (a bad one is a usage error,
// exit code 2, before anything is drawn) and writes the PNG atomically.
// Its defaults are what a user of an indoor map expects (README, "Pictures"):
// top and iso views cut the ceiling found by find_ceiling (render_cuts.hpp),
// a top view colored by state the floor too (find_floor), front
// and side views cut the map in the middle and color by distance, pictures
// are annotated (title, axes, legend, scale bar).
// Cost: loading the map, two or three query walks, the pixels; see
// map_render.hpp and render_cuts.hpp.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/io/render_cuts.hpp"

namespace umbra::cli {
namespace {

struct RenderCommandOptions {
  std::string map_path;
  std::string output;
  std::string view;   // empty: iso, or the slice's own view
  std::string color;  // empty: see default_color
  std::string slice;  // "z=1.2"
  int depth = 0;
  int width = 1024;
  std::string min_z;    // METRES, "auto" or "none"; empty: auto for a top view colored by state, else none
  std::string max_z;    // METRES, "auto" or "none"; empty: auto for top and iso views, else none
  std::string section;  // METRES, "middle" or "none"; empty: middle for front and side views
  std::string frame;    // minx,miny,minz,maxx,maxy,maxz; empty: what is drawn
  bool bare = false;
};

/// A number, or nothing when the text is not one (whole text, finite).
std::optional<double> parse_number(const std::string& text) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

/// CLI11 check: METRES or one of two words.
CLI::Validator number_or(const std::string& option, const std::string& word, const std::string& other) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        if (text == word || text == other || parse_number(text)) return "";
        return option + " must be a height in metres, '" + word + "' or '" + other + "', got '" + text + "'";
      },
      "METRES|" + word + "|" + other);
}

/// CLI11 check of -o: umbra writes PNG only.
CLI::Validator png_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::string extension = std::filesystem::path(text).extension().string();
        for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (extension == ".png") return "";
        return "-o " + text + ": umbra render writes PNG pictures only, so the file name must end in .png (got '" +
               (extension.empty() ? std::string("no extension") : extension) + "')";
      },
      "FILE.png");
}

/// "z=1.2" -> {2, 1.2}; nothing when the text is not AXIS=NUMBER.
std::optional<RenderSlice> parse_slice(const std::string& text) {
  if (text.size() < 3 || text[1] != '=') return std::nullopt;
  const std::string axes = "xyz";
  const std::size_t axis = axes.find(text[0]);
  if (axis == std::string::npos) return std::nullopt;
  const std::string number = text.substr(2);
  try {
    std::size_t used = 0;
    const double position = std::stod(number, &used);
    if (used != number.size()) return std::nullopt;
    return RenderSlice{static_cast<int>(axis), position};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

RenderView view_named(const std::string& name) {
  for (const RenderView view : {RenderView::top, RenderView::front, RenderView::side, RenderView::iso}) {
    if (name == to_string(view)) return view;
  }
  throw std::invalid_argument("unknown view '" + name + "'");  // CLI11 checked the name already
}

RenderColor color_named(const std::string& name) {
  for (const RenderColor color : {RenderColor::height, RenderColor::rgb, RenderColor::state, RenderColor::depth}) {
    if (name == to_string(color)) return color;
  }
  throw std::invalid_argument("unknown color mode '" + name + "'");
}

/// The color a picture gets unless told: state for a slice, distance for
/// front and side views (height would repeat the row), else height.
RenderColor default_color(const RenderOptions& options) {
  if (options.slice) return RenderColor::state;
  if (options.view == RenderView::front || options.view == RenderView::side) return RenderColor::depth;
  return RenderColor::height;
}

/// The options as given; the cuts that depend on the map come later (apply_cuts).
RenderOptions render_options(const RenderCommandOptions& command) {
  RenderOptions options;
  options.depth = command.depth;
  options.width = command.width;
  options.annotate = !command.bare;
  if (!command.slice.empty()) options.slice = parse_slice(command.slice);  // CLI11 checked the form
  if (!command.view.empty()) {
    options.view = view_named(command.view);
  } else if (options.slice) {
    options.view = slice_view(options.slice->axis);
  }
  options.color = command.color.empty() ? default_color(options) : color_named(command.color);
  if (!command.frame.empty()) {
    const std::vector<double> b = parse_numbers(command.frame, 6, "--frame");
    options.frame = Aabb{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
    options.frame->validate();
  }
  if (options.slice && (!command.min_z.empty() || !command.max_z.empty() || !command.section.empty())) {
    throw std::invalid_argument(std::string(!command.min_z.empty() ? "--min-z" : (!command.max_z.empty() ? "--max-z" : "--section")) +
                                " is for views; a slice is one layer already");
  }
  if (const auto height = parse_number(command.min_z)) options.min_z = *height;
  if (const auto height = parse_number(command.max_z)) options.max_z = *height;
  if (const auto plane = parse_number(command.section)) options.section = *plane;
  if (!command.section.empty() && options.view != RenderView::front && options.view != RenderView::side) {
    throw std::invalid_argument("--section is for front and side views (a top view is cut with --max-z), got --view " +
                                std::string(to_string(options.view)));
  }
  return options;
}

/// The cuts found in the map: the ceiling (--max-z auto, the default for
/// top and iso views, which look from above), the floor (--min-z auto, the default for a top view colored
/// by state) and the middle section (--section middle, the default for front
/// and side views). Returns what was cut, for the summary line.
std::string apply_cuts(const OccupancyMap& map, const RenderCommandOptions& command, RenderOptions& options) {
  if (options.slice) return "";
  std::string said;
  char text[200];
  const bool top = options.view == RenderView::top;
  if (command.min_z == "auto" || (command.min_z.empty() && top && options.color == RenderColor::state)) {
    if (const auto floor = find_floor(map, options.depth)) {
      options.min_z = floor->min_z;
      std::snprintf(text, sizeof text, "; floor found, its top at %.3f m, cut away (--min-z none keeps it)",
                    floor->top_z);
      said += text;
    } else {
      said += "; no floor found, nothing cut below";
    }
  }
  const bool from_above = top || options.view == RenderView::iso;
  if (command.max_z == "auto" || (command.max_z.empty() && from_above)) {
    const auto ceiling = find_ceiling(map, options.depth);
    if (ceiling && options.min_z && *options.min_z > ceiling->max_z) {
      said += "; the ceiling found is below the lowest height drawn, nothing cut above";
    } else if (ceiling) {
      options.max_z = ceiling->max_z;
      std::snprintf(text, sizeof text, "; ceiling found at %.3f m and cut away (--max-z none keeps it)",
                    ceiling->underside_z);
      said += text;
    } else {
      said += "; no ceiling found, nothing cut above";
    }
  }
  const bool across = options.view == RenderView::front || options.view == RenderView::side;
  if (across && (command.section == "middle" || command.section.empty())) {
    if (const auto middle = middle_section(map, options.view, options.depth)) {
      options.section = *middle;
      std::snprintf(text, sizeof text, "; cut in the middle, %s %s %.3f m drawn (--section none draws it all)",
                    options.view == RenderView::front ? "y" : "x", options.view == RenderView::front ? ">=" : "<=",
                    *middle);
      said += text;
    }
  }
  return said;
}

/// A wrong option: main() prints it with the pointer to --help and exits with kBadUsage.
[[noreturn]] void usage_error(const std::exception& error) { throw UsageError(error.what()); }

int run_render(const RenderCommandOptions& command) {
  RenderOptions options;
  try {
    options = render_options(command);
    if (options.annotate) {
      RenderOptions widest = options;
      widest.width = kMaxRenderPixels;
      widest.validate();  // every field but the width: the width's own message below names the option
      try {
        options.validate();
      } catch (const std::invalid_argument&) {
        throw std::invalid_argument("--width " + std::to_string(command.width) +
                                    " is too narrow for the title, axes, legend and scale bar (at least " +
                                    std::to_string(kMinAnnotatedRenderWidth) + "); --bare draws the map alone");
      }
    }
    options.validate();
  } catch (const std::invalid_argument& error) {
    usage_error(error);
  }
  const OccupancyMap map = load_any_map(command.map_path);
  try {
    check_render_options(map, options);
  } catch (const std::invalid_argument& error) {
    usage_error(error);
  }
  const std::string cuts = apply_cuts(map, command, options);
  const MapPicture picture = render_map(map, options);
  write_png(picture.image, command.output);

  std::printf("%s: %d x %d pixels, %s %s, %zu nodes of depth %d (%g m) drawn, %g m per pixel", command.output.c_str(),
              picture.image.width, picture.image.height, options.slice ? "slice seen from" : "view from",
              to_string(options.view), picture.nodes_drawn, options.depth, map.grid().node_size(options.depth),
              picture.camera.metres_per_pixel);
  if (options.color == RenderColor::height && picture.ramp_high >= picture.ramp_low) {
    std::printf(", heights %.3f (blue) to %.3f m (red)", picture.ramp_low, picture.ramp_high);
  }
  std::printf("%s\n", cuts.c_str());
  return 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto options = std::make_shared<RenderCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "render",
      "Draw a map as a PNG: its occupied voxels as shaded cubes seen from a side, or a slice through it showing "
      "occupied (red), free (light grey) and unknown (dark) space; with a title, axes in metres, a legend and a "
      "scale bar");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required();  // a missing file is an input failure (exit code 1), named when it is loaded, as in `view`
  command->add_option("-o,--output", options->output, "PNG file to write (replaced atomically; .png only)")
      ->required()
      ->check(png_path());
  command->add_option("--view", options->view, "top, front (looking north), side (looking west) or iso; default iso")
      ->check(CLI::IsMember({"top", "front", "side", "iso"}));
  command->add_option("--color", options->color,
                      "height (blue low to red high), depth (red near to blue far), rgb (the map's colors) or state "
                      "(occupied cubes over free and unknown space); default depth for front and side views, state "
                      "for a slice, else height")
      ->check(CLI::IsMember({"height", "depth", "rgb", "state"}));
  command
      ->add_option("--slice", options->slice,
                   "AXIS=METRES, e.g. z=1.2: the one-node-thick layer there, seen along the axis")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            return parse_slice(text) ? "" : "--slice must be AXIS=METRES with AXIS x, y or z (e.g. z=1.2), got '" + text + "'";
          },
          "AXIS=METRES"));
  command->add_option("--depth", options->depth, "depth of the nodes drawn (0 = finest voxels)")
      ->capture_default_str()
      ->check(CLI::Range(0, 21));
  command
      ->add_option("--min-z", options->min_z,
                   "a view draws only nodes reaching above this height (metres); auto: just above the floor, if the "
                   "map has one (the default for a top view colored by state); none: no cut")
      ->check(number_or("--min-z", "auto", "none"));
  command
      ->add_option("--max-z", options->max_z,
                   "a view draws only nodes reaching below this height (metres); auto: just below the ceiling, if "
                   "the map has one (the default for top and iso views); none: no cut")
      ->check(number_or("--max-z", "auto", "none"));
  command
      ->add_option("--section", options->section,
                   "front and side views draw only what lies behind this plane (metres on y for front, x for side); "
                   "middle: through the middle of the map (the default); none: the whole map from outside")
      ->check(number_or("--section", "middle", "none"));
  command->add_option("--width", options->width, "picture width in pixels (at least 200 unless --bare)")
      ->capture_default_str()
      ->check(CLI::Range(17, kMaxRenderPixels));
  command->add_option("--frame", options->frame,
                      "frame the box minx,miny,minz,maxx,maxy,maxz (metres) instead of what is drawn, so that "
                      "pictures of several maps line up");
  command->add_flag("--bare", options->bare, "the map drawing alone: no title, axes, legend or scale bar");
  add_memory_option(*command);
  return [options] { return run_render(*options); };
}

}  // namespace umbra::cli
