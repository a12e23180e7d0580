// `umbra render MAP -o map.png`: a picture of a map file (.umb, .bt, .ot).
//
// The drawing is the library's (umbra/io/map_render.hpp); the command parses
// the options, checks them against the map (a bad one is a usage error,
// exit code 2, before anything is drawn) and writes the PNG atomically.
// Cost: loading the map, two query walks, the pixels; see map_render.hpp.
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/png_writer.hpp"

namespace umbra::cli {
namespace {

struct RenderCommandOptions {
  std::string map_path;
  std::string output;
  std::string view;   // empty: iso, or the slice's own view
  std::string color;  // empty: height for a view, state for a slice
  std::string slice;  // "z=1.2"
  int depth = 0;
  int width = 1024;
  std::optional<double> min_z;
  std::optional<double> max_z;
};

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
  for (const RenderColor color : {RenderColor::height, RenderColor::rgb, RenderColor::state}) {
    if (name == to_string(color)) return color;
  }
  throw std::invalid_argument("unknown colour mode '" + name + "'");
}

RenderOptions render_options(const RenderCommandOptions& command) {
  RenderOptions options;
  options.depth = command.depth;
  options.width = command.width;
  options.min_z = command.min_z;
  options.max_z = command.max_z;
  if (!command.slice.empty()) options.slice = parse_slice(command.slice);  // CLI11 checked the form
  if (!command.view.empty()) {
    options.view = view_named(command.view);
  } else if (options.slice) {
    options.view = slice_view(options.slice->axis);
  }
  if (!command.color.empty()) {
    options.color = color_named(command.color);
  } else if (options.slice) {
    options.color = RenderColor::state;
  }
  return options;
}

int usage_error(const std::exception& error) {
  std::fprintf(stderr, "umbra render: error: %s\n", error.what());
  return 2;
}

int run_render(const RenderCommandOptions& command) {
  const RenderOptions options = render_options(command);
  try {
    options.validate();
  } catch (const std::invalid_argument& error) {
    return usage_error(error);
  }
  const OccupancyMap map = load_any_map(command.map_path);
  try {
    check_render_options(map, options);
  } catch (const std::invalid_argument& error) {
    return usage_error(error);
  }
  const MapPicture picture = render_map(map, options);
  write_png(picture.image, command.output);

  std::printf("%s: %d x %d pixels, %s %s, %zu nodes of depth %d (%g m) drawn, %g m per pixel", command.output.c_str(),
              picture.image.width, picture.image.height, options.slice ? "slice seen from" : "view from",
              to_string(options.view), picture.nodes_drawn, options.depth, map.grid().node_size(options.depth),
              picture.camera.metres_per_pixel);
  if (options.color == RenderColor::height && picture.ramp_high_z >= picture.ramp_low_z) {
    std::printf(", heights %.3f (blue) to %.3f m (red)", picture.ramp_low_z, picture.ramp_high_z);
  }
  std::printf("\n");
  return 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto options = std::make_shared<RenderCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "render",
      "Draw a map as a PNG: its occupied voxels as shaded cubes seen from a side, or a slice through it showing "
      "occupied (red), free (light grey) and unknown (dark) space");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("-o,--output", options->output, "PNG file to write (replaced atomically)")->required();
  command->add_option("--view", options->view, "top, front (looking north), side (looking west) or iso; default iso")
      ->check(CLI::IsMember({"top", "front", "side", "iso"}));
  command->add_option("--color", options->color,
                      "height (blue low to red high), rgb (the map's colours) or state; default height, for a "
                      "slice state")
      ->check(CLI::IsMember({"height", "rgb", "state"}));
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
  command->add_option("--min-z", options->min_z, "a view draws only nodes reaching above this height (metres)");
  command->add_option("--max-z", options->max_z,
                      "a view draws only nodes reaching below this height (metres), e.g. to cut a ceiling away");
  command->add_option("--width", options->width, "picture width in pixels")
      ->capture_default_str()
      ->check(CLI::Range(17, kMaxRenderPixels));
  add_memory_option(*command);
  return [options] { return run_render(*options); };
}

}  // namespace umbra::cli
