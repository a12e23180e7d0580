// `umbra compare A B [--bbox ...] [--json]`: how map B agrees with map A,
// voxel by voxel (OctoMap's compare_octrees and eval_octree_accuracy).
//
// The comparison is the library's compare_maps (umbra/map/map_agreement.hpp),
// the one behind the fidelity benchmark's tables and the integrator tests:
// for every finest voxel (of the whole map, or of the voxels the box meets)
// its state in A and in B, in a 3 x 3 table, and from it B's occupied recall
// and precision against A, the share of A's free voxels that B has free and
// the share it leaves unknown. Each map's states are by its own thresholds.
// Both maps must have the same resolution and depth levels. Cost: two loads
// and one walk over both trees.
#include <cinttypes>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/map/map_agreement.hpp"

namespace umbra::cli {
namespace {

struct CompareOptions {
  std::string reference;
  std::string other;
  std::string bbox;
  bool json = false;
};

constexpr OccupancyState kStates[] = {OccupancyState::occupied, OccupancyState::free, OccupancyState::unknown};

/// A JSON string: the path with quotes, backslashes and control bytes escaped.
std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string agreement_json(const CompareOptions& options, const OccupancyMap& reference,
                           const std::optional<VoxelBox>& region, const MapAgreement& a) {
  std::ostringstream json;
  json.precision(17);
  json << "{\"reference\": " << json_string(options.reference) << ", \"other\": " << json_string(options.other)
       << ", \"resolution\": " << reference.resolution() << ", \"depth_levels\": " << reference.depth_levels();
  if (region) {
    json << ", \"box_keys\": [[" << region->lo.x << ", " << region->lo.y << ", " << region->lo.z << "], ["
         << region->hi.x << ", " << region->hi.y << ", " << region->hi.z << "]]";
  } else {
    json << ", \"box_keys\": null";
  }
  json << ", \"voxels\": {";
  const char* separator = "";
  for (const OccupancyState r : kStates) {
    json << separator << "\"" << to_string(r) << "\": {";
    separator = ", ";
    const char* inner = "";
    for (const OccupancyState o : kStates) {
      json << inner << "\"" << to_string(o) << "\": " << a.count(r, o);
      inner = ", ";
    }
    json << "}";
  }
  json << "}, \"occupied_recall\": " << a.recall() << ", \"occupied_precision\": " << a.precision()
       << ", \"free_agreement\": " << a.free_agreement() << ", \"free_left_unknown\": " << a.free_left_unknown()
       << "}";
  return json.str();
}

void print_agreement(const CompareOptions& options, const OccupancyMap& reference,
                     const std::optional<VoxelBox>& region, const MapAgreement& a) {
  std::printf("A (reference): %s\nB (compared):  %s\n", options.reference.c_str(), options.other.c_str());
  if (region) {
    const Grid& grid = reference.grid();
    const Vec3d low = grid.min_corner(region->lo);
    const Vec3d high = grid.min_corner(region->hi) + Vec3d{grid.resolution(), grid.resolution(), grid.resolution()};
    std::printf("voxels of %g m from (%g, %g, %g) to (%g, %g, %g) m (the --bbox)\n", grid.resolution(), low.x, low.y,
                low.z, high.x, high.y, high.z);
  } else {
    std::printf("every voxel of %g m in the map (%d depth levels)\n", reference.resolution(),
                reference.depth_levels());
  }
  std::printf("%-14s %20s %20s %20s\n", "voxels", "B occupied", "B free", "B unknown");
  for (const OccupancyState r : kStates) {
    std::printf("A %-12s %20" PRIu64 " %20" PRIu64 " %20" PRIu64 "\n", to_string(r), a.count(r, OccupancyState::occupied),
                a.count(r, OccupancyState::free), a.count(r, OccupancyState::unknown));
  }
  std::printf("occupied recall     %8.4f %%  of A's occupied voxels are occupied in B\n", 100.0 * a.recall());
  std::printf("occupied precision  %8.4f %%  of B's occupied voxels are occupied in A\n", 100.0 * a.precision());
  std::printf("free agreement      %8.4f %%  of A's free voxels are free in B\n", 100.0 * a.free_agreement());
  std::printf("free left unknown   %8.4f %%  of A's free voxels are unknown in B\n", 100.0 * a.free_left_unknown());
  std::printf("known in A only     %" PRIu64 " voxels; known in B only %" PRIu64 " voxels\n",
              a.count(OccupancyState::occupied, OccupancyState::unknown) +
                  a.count(OccupancyState::free, OccupancyState::unknown),
              a.count(OccupancyState::unknown, OccupancyState::occupied) +
                  a.count(OccupancyState::unknown, OccupancyState::free));
}

int run_compare(const CompareOptions& options) {
  std::optional<Aabb> box;
  if (!options.bbox.empty()) box = as_usage([&] { return parse_box(options.bbox, "--bbox"); });
  const OccupancyMap reference = load_any_map(options.reference);
  const OccupancyMap other = load_any_map(options.other);
  std::optional<VoxelBox> region;
  if (box) region = voxel_box(reference.grid(), *box);
  const MapAgreement agreement = compare_maps(reference, other, region);
  if (options.json) {
    std::printf("%s\n", agreement_json(options, reference, region, agreement).c_str());
  } else {
    print_agreement(options, reference, region, agreement);
  }
  return kSuccess;
}

}  // namespace

Command add_compare_command(CLI::App& app) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* command = app.add_subcommand(
      "compare",
      "Compare map B with map A voxel by voxel: B's occupied recall and precision against A, free agreement, "
      "unknown counts");
  command->add_option("reference", options->reference, "map A, the reference (.umb, .bt, .ot)")
      ->required()
      ->check(map_extension());
  command->add_option("other", options->other, "map B, compared with A (.umb, .bt, .ot; same resolution and depth)")
      ->required()
      ->check(map_extension());
  command
      ->add_option("--bbox", options->bbox,
                   "only the voxels this box meets: minx,miny,minz,maxx,maxy,maxz in metres (default: the whole map)")
      ->check(box_check());
  command->add_flag("--json", options->json, "print one JSON object instead of text");
  command->footer(
      "Every finest voxel counts once (a pruned node for each voxel it covers), with its state in A and in B by "
      "each map's own thresholds; the whole map's unknown voxels are many (8^depth_levels in all). The figures are "
      "those of the fidelity benchmark (umbra::compare_maps). A .bt map holds only free and occupied leaves.");
  add_memory_option(*command);
  return [options] { return run_compare(*options); };
}

}  // namespace umbra::cli
