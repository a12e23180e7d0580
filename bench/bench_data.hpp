// The benchmarks' inputs: the real scans of ../shared/data and a simulated
// depth camera in the procedural building, loaded once per run.
//
//   scan.dat    one LiDAR scan, 88,206 points (octomap/scan.dat.bz2)
//   3dtk        three registered LiDAR scans (3dtk/3dtk_registered.graph)
//   tum         ten Kinect frames (tum_fr2_pioneer_slam2), max range --tum-max-range
//   sim-camera  sim::demo_depth_images(): sixteen frames of a simulated
//               depth camera (640 x 240 pixels, hfov 115, vfov 60, 6.5 m,
//               Kinect-like noise) through the procedural building, seed 1,
//               as 16-bit images in millimetres and their points
// Anything else is taken as a path for umbra::open_scan_source.
#pragma once

#include <string>
#include <vector>

#include "common/argument_cursor.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::bench {

struct Dataset {
  std::string name;
  std::string path;         ///< where it was read from ("" for simulated data)
  double max_range = 30.0;  ///< InsertOptions::max_range for it
  std::vector<Scan> scans;
};

struct DatasetOptions {
  std::string data_dir = "../shared/data";
  double max_range = 30.0;      ///< LiDAR datasets
  double tum_max_range = 5.0;   ///< the TUM frames
  double camera_max_range = 6.5;  ///< sim-camera (its own range: every point is within it)
};

/// The file or folder a named dataset is read from ("" for simulated ones).
std::string dataset_path(const std::string& name, const DatasetOptions& options);

/// Loads a dataset by name (see the file comment); throws with a message when it cannot.
Dataset load_dataset(const std::string& name, const DatasetOptions& options);

/// The sim-camera frames.
std::vector<Scan> simulated_camera_frames();

/// "a,b,c" -> {"a", "b", "c"}.
std::vector<std::string> split_list(const std::string& text);

/// The dataset flags the dataset benchmarks share (scripts/bench.sh passes --data to every benchmark): --data (or --data-dir) DIR
/// and --datasets a,b. True when `arg` is one of them (its value read from `args`).
inline bool take_dataset_flag(umbra_bench::ArgumentCursor& args, const std::string& arg, std::string& data_dir,
                              std::vector<std::string>& datasets) {
  if (arg == "--data" || arg == "--data-dir") {
    data_dir = args.value();
  } else if (arg == "--datasets") {
    datasets = split_list(args.value());
  } else {
    return false;
  }
  return true;
}

/// The median of some values (the mean of the middle two for an even count).
double median(std::vector<double> values);

}  // namespace umbra::bench
