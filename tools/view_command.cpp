// `umbra view MAP -o map.html [--budget N] [--serve [--port P]]`: one HTML
// file that shows a map in 3D in any browser, offline.
//
// The page is viewer_page.hpp's (three.js pinned in
// tools/viewer/package-lock.json, bundled at build time, so nothing is
// fetched when the page opens). A build without node and npm has no page to
// write: the command then says so. Cost: the layers (see viewer_data.hpp),
// then one write of the page (about 2.3 base64 bytes per colored occupied
// node, 1-2 per free or unknown node; viewer_data.hpp).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/file_saving.hpp"
#include "local_http_server.hpp"
#include "report.hpp"
#include "umbra/io/map_formats.hpp"
#include "viewer_data.hpp"
#include "viewer_page.hpp"

namespace umbra::cli {
namespace {

struct ViewOptions {
  std::string map_path;
  std::string output;
  std::size_t budget = kDefaultViewerBudget;
  bool serve = false;
  int port = 8000;
};

void print_summary(const OccupancyMap& map, const ViewerData& data) {
  if (!data.stats.has_known_space) {
    std::printf("the map is empty: the page shows its numbers only\n");
    return;
  }
  const int last = data.layers.back().depth;
  std::printf("depths %d to %d (nodes of %g to %g m); %zu occupied nodes at depth %d", data.finest_depth, last,
              map.grid().node_size(data.finest_depth), map.grid().node_size(last), data.layers.front().count,
              data.finest_depth);
  if (data.finest_depth > 0 && data.finest_depth_zero_count > data.budget) {
    std::printf(" (depth 0 has %zu, more than the budget of %zu)", data.finest_depth_zero_count, data.budget);
  } else if (data.finest_depth > 0) {
    std::printf(" (a map of %d depth levels starts at depth %d: the page's codes hold %d levels)", map.depth_levels(),
                data.finest_depth, kViewerCodeBitsPerAxis);
  }
  std::printf("\n");
  if (data.ceiling_cut) {
    std::printf("the page starts cut at z = %.3f m, below the ceiling it finds (its \"cut above\" slider)\n",
                *data.ceiling_cut);
  }
  for (const ViewerLayer& layer : data.layers) {
    if (!layer.embedded) {
      std::printf("  left out: %zu %s nodes at depth %d (more than the budget of %zu)\n", layer.count,
                  to_string(layer.state), layer.depth, data.budget);
    }
  }
}

int write_and_serve(const ViewOptions& options) {
  const OccupancyMap map = load_any_map(options.map_path);
  const ViewerData data = collect_viewer_data(map, options.budget);
  const std::string page = viewer_page(map, data, std::filesystem::path(options.map_path).filename().string());
  print_summary(map, data);
  if (!options.output.empty()) {
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(page.data());
    write_file_atomically(options.output, {std::span<const std::uint8_t>(bytes, page.size())}, "page");
    std::printf("wrote %s (%s, three.js %s)\n", options.output.c_str(), human_bytes(page.size()).c_str(),
                viewer_three_version().c_str());
  }
  std::fflush(stdout);
  if (options.serve) serve_page(page, options.port, stdout);
  return 0;
}

int explain_missing_page() {
  std::fprintf(stderr,
               "umbra view: this umbra was built without the browser viewer: node and npm were missing when it was "
               "configured, `npm ci` failed, or UMBRA_BUILD_VIEWER was OFF (the configure messages say which). "
               "Install them (Debian: apt-get install nodejs npm), then configure and build again.\n");
  return 1;
}

int run_view(const ViewOptions& options) {
  if (options.output.empty() && !options.serve) {
    std::fprintf(stderr, "umbra view: error: say where the page goes: -o FILE.html, --serve, or both\n");
    return 2;
  }
  return viewer_page_available() ? write_and_serve(options) : explain_missing_page();
}

}  // namespace

Command add_view_command(CLI::App& app) {
  auto options = std::make_shared<ViewOptions>();
  CLI::App* command = app.add_subcommand(
      "view", "Write one HTML file that shows a map in 3D in a browser (offline: three.js is inside the file)");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required();  // a missing file is an input failure (exit code 1), named when it is loaded
  command->add_option("-o,--output", options->output, "HTML file to write (replaced atomically)");
  command
      ->add_option("--budget", options->budget,
                   "most nodes drawn at once: the finest depth shown is the finest whose occupied nodes fit; free "
                   "and unknown layers above it are left out")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 31));
  command->add_flag("--serve", options->serve, "also serve the page on http://127.0.0.1:PORT/ until Ctrl-C");
  command->add_option("--port", options->port, "port for --serve (0: any free port)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  add_memory_option(*command);
  return [options] { return run_view(*options); };
}

}  // namespace umbra::cli
