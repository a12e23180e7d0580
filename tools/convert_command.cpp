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
#include "map_output.hpp"
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

int run_convert(const ConvertOptions& options) {
  const MapFileFormat input = map_file_format_for(options.input);
  const MapFileFormat output = map_file_format_for(options.output);
  check_can_save(options.output);  // before the (maybe long) load
  const OccupancyMap map = load_any_map(options.input);
  print_format_notes(map, input, output);
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
      ->check(map_extension());  // a missing file is an input failure (exit code 1), named when it is read
  command->add_option("output", options->output, "map to write (.umb, .bt, .ot); replaced atomically")
      ->required()
      ->check(map_extension());
  add_memory_option(*command);
  return [options] { return run_convert(*options); };
}

}  // namespace umbra::cli
