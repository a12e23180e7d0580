#include "bench_data.hpp"

#include <algorithm>
#include <sstream>

#include "umbra/sim/depth_camera.hpp"

namespace umbra::bench {

std::string dataset_path(const std::string& name, const DatasetOptions& options) {
  if (name == "scan.dat") return options.data_dir + "/octomap/scan.dat.bz2";
  if (name == "3dtk") return options.data_dir + "/3dtk/3dtk_registered.graph";
  if (name == "tum") return options.data_dir + "/tum_fr2_pioneer_slam2";
  if (name == "sim-camera") return "";
  return name;
}

std::vector<Scan> simulated_camera_frames() {
  const std::vector<sim::DepthFrame> frames = sim::demo_depth_sequence();
  std::vector<Scan> scans(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    scans[i].origin = frames[i].origin;
    scans[i].points = frames[i].points;
    scans[i].name = "sim-camera frame " + std::to_string(i);
  }
  return scans;
}

Dataset load_dataset(const std::string& name, const DatasetOptions& options) {
  Dataset data;
  data.name = name;
  data.path = dataset_path(name, options);
  data.max_range = name == "tum" ? options.tum_max_range
                   : name == "sim-camera" ? options.camera_max_range
                                          : options.max_range;
  if (name == "sim-camera") {
    data.scans = simulated_camera_frames();
    return data;
  }
  const auto source = open_scan_source(data.path);
  Scan scan;
  while (source->next(scan)) data.scans.push_back(scan);
  return data;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) parts.push_back(part);
  return parts;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return 0.0;
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace umbra::bench
