// `umbra convert IN OUT`: a map from one file format to another.
//
// Formats by extension (.umb umbra, .bt OctoMap binary, .ot OctoMap full);
// the reading and writing are the library's (umbra/io/map_formats.hpp), so
// the command only checks names, says what a format will not keep, and
// reports what it wrote. Cost: one load and one save of the map.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/octomap_files.hpp"

namespace umbra::cli {
namespace {

struct ConvertOptions {
  std::string input;
  std::string output;
};

/// CLI11 check: the name has a map file extension (an error here is a usage error, exit code 2).
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

/// What the output format cannot hold, said before writing.
void print_notes(const OccupancyMap& map, MapFileFormat input, MapFileFormat output) {
  if (output == MapFileFormat::umb) return;
  if (output == MapFileFormat::bt && input != MapFileFormat::bt) {
    std::fprintf(stderr, "note: .bt keeps only free / occupied per leaf (OctoMap's maximum likelihood): every value "
                         "becomes the clamping minimum or maximum when read back%s\n",
                 map.has_color() ? ", and colours are dropped" : "");
  }
  if (input == MapFileFormat::umb && (!(map.sensor_model() == SensorModel{}) || !(map.thresholds() == Thresholds{}))) {
    std::fprintf(stderr, "note: OctoMap files store no sensor model or thresholds; reading the file back gives "
                         "OctoMap's defaults\n");
  }
}

int run_convert(const ConvertOptions& options) {
  const MapFileFormat input = map_file_format_for(options.input);
  const MapFileFormat output = map_file_format_for(options.output);
  check_can_save(options.output);  // before the (maybe long) load
  const OccupancyMap map = load_any_map(options.input);
  print_notes(map, input, output);
  save_any_map(map, options.output);
  std::uintmax_t bytes = std::filesystem::file_size(options.output);
  std::printf("%s (%s) -> %s (%s, %ju bytes)\n", options.input.c_str(), to_string(input), options.output.c_str(),
              to_string(output), bytes);
  return 0;
}

}  // namespace

Command add_convert_command(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* command = app.add_subcommand(
      "convert", "Convert a map between formats: .umb (umbra), .bt and .ot (OctoMap; 16 depth levels only)");
  command->add_option("input", options->input, "map to read (.umb, .bt, .ot)")
      ->required()
      ->check(CLI::ExistingFile & map_extension());
  command->add_option("output", options->output, "map to write (.umb, .bt, .ot); replaced atomically")
      ->required()
      ->check(map_extension());
  add_memory_option(*command);
  return [options] { return run_convert(*options); };
}

}  // namespace umbra::cli
