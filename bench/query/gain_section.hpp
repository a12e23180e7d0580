// The information-gain section of the query benchmark: umbra's exact and
// fast gain against the OctoMap-style loop of receding-horizon explorers
// (every voxel of the frustum's bounding box, computeRayKeys per unknown
// voxel), on the same poses; every count compared.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "datasets.hpp"

namespace umbra_bench {

struct GainRow {
  std::string dataset;
  std::size_t poses = 0;
  double exact_us = 0.0;
  double fast_us = 0.0;
  double exact_batch_us = 0.0;  // per pose, the poses as one batch (scratch memory reused)
  double fast_batch_us = 0.0;
  std::size_t octomap_poses = 0;
  double octomap_us = 0.0;
  double exact_us_on_octomap_poses = 0.0;
  double fast_us_on_octomap_poses = 0.0;
  std::size_t octomap_mismatches = 0;
  double mean_unknown = 0.0;
  double fast_mean_error = 0.0;  // relative to exact, over poses with a non-zero exact gain
  double fast_max_error = 0.0;
  double fast_total_error = 0.0;  // sum of |fast - exact| over the sum of exact
  std::uint64_t worst_exact = 0;  // the pose with the largest relative error
  std::uint64_t worst_fast = 0;
};

GainRow run_gain(const Dataset& data, std::size_t pose_count, std::size_t octomap_pose_count, int repeat,
                 std::uint64_t seed, bool run_fast);
std::string gain_table(const std::vector<GainRow>& rows);

}  // namespace umbra_bench
