#include "bench_data.hpp"

#include <algorithm>
#include <cmath>
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
  // Depth images, as the camera gives them; their points are back_project()'s.
  const std::vector<sim::SimulatedDepthImage> frames = sim::demo_depth_images();
  std::vector<Scan> scans(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const sim::SimulatedDepthImage& frame = frames[i];
    Scan& scan = scans[i];
    scan.origin = frame.pose.translation();
    scan.name = "sim-camera frame " + std::to_string(i);
    // Millimetre steps, as a 16-bit depth camera delivers them.
    ScanImage& image = scan.image.emplace();
    image.width = frame.width;
    image.height = frame.height;
    image.units_per_metre = 1000.0;
    image.raw.resize(frame.depth.size());
    for (std::size_t p = 0; p < frame.depth.size(); ++p) {
      image.raw[p] = static_cast<std::uint16_t>(std::lround(std::min(frame.depth[p], 65.0f) * 1000.0f));
    }
    image.camera = frame.camera;
    image.pose = frame.pose;
    back_project(image.view(), image.camera, image.pose, scan.points);
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
