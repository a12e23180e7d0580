// What the distance-field benchmarks (field_benchmark.cpp, field_floor.cpp)
// share: the box their fields cover per dataset and the thread CPU clock.
#pragma once

#include <ctime>
#include <string>

#include "umbra/core/aabb.hpp"

namespace umbra::bench {

/// CPU seconds of the calling thread (a one-thread update runs there
/// entirely; on a shared machine this is steadier than the wall clock).
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// The box the benchmark's fields cover for a scanned dataset (around the
/// first sensor position; dynamicEDT3D is dense, so it must fit there).
inline Aabb field_dataset_box(const std::string& name, const Vec3d& o) {
  return name == "tum" ? Aabb{o - Vec3d{3.0, 3.0, 1.5}, o + Vec3d{3.0, 3.0, 1.5}}
                       : Aabb{o - Vec3d{10.0, 10.0, 2.0}, o + Vec3d{10.0, 10.0, 3.0}};
}

}  // namespace umbra::bench
