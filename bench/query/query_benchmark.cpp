// Query benchmark: umbra's queries against liboctomap on the same maps, in
// one run (issue 8; results and commands in docs/benchmarks.md).
//
// Datasets (each map built once, then written as .bt and read back by
// liboctomap, so that both libraries answer on the same voxels):
//   3dtk-20cm, 3dtk-5cm  the three 3DTK scans (3dtk/3dtk_registered.graph),
//                        umbra's discrete integrator, max range 30 m
//   tum-2cm              the ten TUM RGB-D frames, discrete, max range 5 m
//   geb079-8cm           octomap/geb079.bt read as it is
// Sections, one per kind of query (--sections picks them; code in
// gain_section.cpp and collision_section.cpp, which say what each compares):
//   gain  information gain of 100 poses (hfov 115, vfov 60 deg, 0 to 6.5 m;
//         positions uniform in the free voxels, yaw uniform, pitch in
//         [-15, 15] deg, fixed seed): umbra exact and fast, and the
//         OctoMap-style baseline of receding-horizon explorers (a voxel by
//         voxel loop over the frustum's bounding box, search() for unknown,
//         then computeRayKeys and search() per key for visibility) on the
//         first --octomap-poses poses of each dataset (it takes seconds per
//         pose at 5 cm and minutes at 2 cm). Every count is compared: umbra
//         exact must equal OctoMap-style; fast is reported with its error.
//   spheres   --checks sphere checks (r = --radius) at free points, unknown
//             blocking and occupied only; OctoMap on the first
//             --octomap-checks of each dataset
//   segments  --checks segments between free points (cut to --max-length if > 0)
// One thread throughout; times are the thread's CPU time (the machines are
// shared), for umbra the median of --repeat runs.
//
// Usage: umbra_query_benchmark [--data DIR] [--datasets 3dtk-20cm,3dtk-5cm,tum-2cm,geb079-8cm]
//          [--sections gain,spheres,segments] [--poses 100] [--octomap-poses 3dtk-20cm=100,...]
//          [--checks 1000000] [--octomap-checks 3dtk-20cm=100000,...] [--radius 0.25]
//          [--max-length 0] [--repeat 3] [--seed 1] [--exact-only] [--markdown FILE]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

#include "../common/argument_cursor.hpp"
#include "collision_section.hpp"
#include "datasets.hpp"
#include "gain_section.hpp"

using namespace umbra_bench;

namespace {

/// "NAME=N,..." as a map, or exits with a message.
std::map<std::string, std::size_t> per_dataset(const std::string& option, const std::string& text) {
  std::map<std::string, std::size_t> counts;
  for (const std::string& item : split(text)) {
    const std::vector<std::string> parts = split(item, '=');
    if (parts.size() != 2) {
      std::fprintf(stderr, "%s wants NAME=N items, got %s\n", option.c_str(), item.c_str());
      std::exit(2);
    }
    counts[parts[0]] = std::stoul(parts[1]);
  }
  return counts;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data_dir = "../shared/data";
  std::string dataset_names = "3dtk-20cm,3dtk-5cm,tum-2cm,geb079-8cm";
  std::string sections = "gain,spheres,segments";
  std::string octomap_poses_text = "3dtk-20cm=100,3dtk-5cm=10,tum-2cm=2,geb079-8cm=20";
  std::string octomap_checks_text = "3dtk-20cm=100000,3dtk-5cm=20000,tum-2cm=2000,geb079-8cm=20000";
  CollisionSettings collision;
  std::string markdown_path;
  std::size_t poses = 100;
  int repeat = 3;
  bool run_fast = true;
  std::uint64_t seed = 1;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    auto value = [&] { return args.value(); };
    if (arg == "--data") data_dir = value();
    else if (arg == "--datasets") dataset_names = value();
    else if (arg == "--sections") sections = value();
    else if (arg == "--poses") poses = std::stoul(value());
    else if (arg == "--octomap-poses") octomap_poses_text = value();
    else if (arg == "--checks") collision.checks = std::stoul(value());
    else if (arg == "--octomap-checks") octomap_checks_text = value();
    else if (arg == "--radius") collision.radius = std::stod(value());
    else if (arg == "--max-length") collision.max_length = std::stod(value());
    else if (arg == "--repeat") repeat = std::stoi(value());
    else if (arg == "--exact-only") run_fast = false;
    else if (arg == "--seed") seed = std::stoull(value());
    else if (arg == "--markdown") markdown_path = value();
    else if (arg == "--help" || arg == "-h") {
      std::printf(
          "usage: umbra_query_benchmark [--data DIR] [--datasets LIST] [--sections gain,spheres,segments]\n"
          "         [--poses 100] [--octomap-poses NAME=N,...] [--checks 1000000] [--octomap-checks NAME=N,...]\n"
          "         [--radius 0.25] [--max-length 0] [--repeat 3] [--seed 1] [--exact-only] [--markdown FILE]\n"
          "datasets:");
      for (const DatasetSpec& d : kDatasets) std::printf(" %s", d.name.c_str());
      std::printf("\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/query_benchmark.cpp)\n",
                   arg.c_str());
      return 2;
    }
  }
  std::map<std::string, std::size_t> octomap_poses = per_dataset("--octomap-poses", octomap_poses_text);
  const std::map<std::string, std::size_t> octomap_checks = per_dataset("--octomap-checks", octomap_checks_text);
  collision.repeat = repeat;
  collision.seed = seed;
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() / ("umbra_query_benchmark_" + std::to_string(::getpid()));
  std::filesystem::create_directories(scratch);

  std::string report;
  std::vector<GainRow> gain_rows;
  std::vector<CollisionRow> collision_rows;
  for (const std::string& name : split(dataset_names)) {
    const auto spec = std::find_if(kDatasets.begin(), kDatasets.end(), [&](const DatasetSpec& d) { return d.name == name; });
    if (spec == kDatasets.end()) {
      std::fprintf(stderr, "unknown dataset %s (see --help)\n", name.c_str());
      return 2;
    }
    Dataset data;
    try {
      data = load_dataset(*spec, data_dir, scratch);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cannot load %s: %s\n", name.c_str(), e.what());
      return 1;
    }
    for (const std::string& section : split(sections)) {
      if (section == "gain") {
        gain_rows.push_back(
            run_gain(data, poses, octomap_poses.count(name) ? octomap_poses[name] : 0, repeat, seed, run_fast));
        std::fputs(gain_table({gain_rows.back()}).c_str(), stderr);
        std::fprintf(stderr, "batch: exact %.0f us/pose, fast %.0f us/pose\n", gain_rows.back().exact_batch_us,
                     gain_rows.back().fast_batch_us);
      } else if (section == "spheres" || section == "segments") {
        CollisionSettings settings = collision;
        settings.octomap_checks = octomap_checks.count(name) ? octomap_checks.at(name) : 0;
        std::vector<CollisionRow> rows;
        if (section == "spheres") rows = run_sphere_checks(data, settings);
        else rows.push_back(run_segment_checks(data, settings));
        std::fputs(collision_table(rows).c_str(), stderr);
        collision_rows.insert(collision_rows.end(), rows.begin(), rows.end());
      } else {
        std::fprintf(stderr, "unknown section %s\n", section.c_str());
        return 2;
      }
    }
  }
  std::filesystem::remove_all(scratch);
  if (!gain_rows.empty()) report += "### Information gain\n\n" + gain_table(gain_rows) + "\n";
  if (!collision_rows.empty()) report += "### Collision and segment checks\n\n" + collision_table(collision_rows) + "\n";
  std::printf("%s", report.c_str());
  if (!markdown_path.empty()) std::ofstream(markdown_path) << report;
  return 0;
}
