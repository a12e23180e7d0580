#include "umbra/core/log_odds.hpp"

#include <stdexcept>
#include <string>

namespace umbra {
namespace {

void require_probability(const char* name, double value, double low, double high, bool low_open,
                         bool high_open) {
  const bool low_ok = low_open ? value > low : value >= low;
  const bool high_ok = high_open ? value < high : value <= high;
  if (!(low_ok && high_ok)) {  // also rejects NaN
    throw std::invalid_argument(std::string(name) + " = " + std::to_string(value) +
                                " is outside " + (low_open ? "(" : "[") + std::to_string(low) +
                                ", " + std::to_string(high) + (high_open ? ")" : "]"));
  }
}

}  // namespace

void SensorModel::validate() const {
  require_probability("sensor model p_hit", p_hit, 0.5, 1.0, true, true);
  require_probability("sensor model p_miss", p_miss, 0.0, 0.5, true, true);
  require_probability("sensor model clamp_min", clamp_min, 0.0, 0.5, true, false);
  require_probability("sensor model clamp_max", clamp_max, 0.5, 1.0, false, true);
}

void Thresholds::validate() const {
  require_probability("occupied threshold", occupied, 0.0, 1.0, true, true);
  require_probability("free threshold", free, 0.0, 1.0, true, true);
  if (free > occupied) {
    throw std::invalid_argument("free threshold " + std::to_string(free) +
                                " is above the occupied threshold " + std::to_string(occupied));
  }
}

const char* to_string(OccupancyState state) {
  switch (state) {
    case OccupancyState::unknown: return "unknown";
    case OccupancyState::free: return "free";
    case OccupancyState::occupied: return "occupied";
  }
  return "invalid";
}

}  // namespace umbra
