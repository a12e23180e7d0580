// Log-odds arithmetic, the sensor model and the occupancy thresholds.
//
// Occupancy is stored as l = ln(p / (1 - p)) in a float, exactly as OctoMap
// does: the sensor model's probabilities are converted once with logit() and
// rounded to float, so that a hit adds the same float OctoMap adds.
#pragma once

#include <cmath>

namespace umbra {

/// ln(p / (1 - p)), rounded to float like OctoMap's logodds().
inline float logit(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

/// 1 - 1 / (1 + e^l).
inline double probability(double log_odds) { return 1.0 - 1.0 / (1.0 + std::exp(log_odds)); }

/// Probabilities of the inverse sensor model, with OctoMap's defaults.
/// Checked by validate(): 0.5 < p_hit < 1, 0 < p_miss < 0.5,
/// 0 < clamp_min <= 0.5 <= clamp_max < 1.
struct SensorModel {
  double p_hit = 0.7;
  double p_miss = 0.4;
  double clamp_min = 0.1192;
  double clamp_max = 0.971;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;

  [[nodiscard]] float hit_log_odds() const { return logit(p_hit); }
  [[nodiscard]] float miss_log_odds() const { return logit(p_miss); }
  [[nodiscard]] float clamp_min_log_odds() const { return logit(clamp_min); }
  [[nodiscard]] float clamp_max_log_odds() const { return logit(clamp_max); }
  friend bool operator==(const SensorModel&, const SensorModel&) = default;
};

/// Occupied if p > occupied, free if p < free, unknown otherwise.
/// Checked by validate(): 0 < free <= occupied < 1. With the defaults
/// (0.5, 0.5) only never-observed voxels (l = 0) are unknown, as in OctoMap.
struct Thresholds {
  double occupied = 0.5;
  double free = 0.5;

  /// Throws std::invalid_argument naming the bad value.
  void validate() const;
  friend bool operator==(const Thresholds&, const Thresholds&) = default;
};

enum class OccupancyState : unsigned char { unknown = 0, free = 1, occupied = 2 };

const char* to_string(OccupancyState state);

/// Thresholds in log-odds, the form the tree compares against.
struct LogOddsThresholds {
  float occupied = 0.0f;
  float free = 0.0f;

  static LogOddsThresholds from(const Thresholds& t) { return {logit(t.occupied), logit(t.free)}; }

  [[nodiscard]] OccupancyState classify(float log_odds) const {
    if (log_odds > occupied) return OccupancyState::occupied;
    if (log_odds < free) return OccupancyState::free;
    return OccupancyState::unknown;
  }
  [[nodiscard]] bool is_free(float log_odds) const { return log_odds < free; }
  [[nodiscard]] bool is_unknown(float log_odds) const {
    return log_odds >= free && log_odds <= occupied;
  }
  [[nodiscard]] bool is_occupied(float log_odds) const { return log_odds > occupied; }
};

/// Clamping range in log-odds: every stored value lies in [min, max].
struct LogOddsRange {
  float min = -2.0f;
  float max = 3.5f;

  static LogOddsRange from(const SensorModel& m) {
    return {m.clamp_min_log_odds(), m.clamp_max_log_odds()};
  }
  /// OctoMap's update rule: add, then clamp.
  [[nodiscard]] float add(float value, float delta) const {
    const float sum = value + delta;
    return sum < min ? min : (sum > max ? max : sum);
  }
  [[nodiscard]] float clamp(float value) const {
    return value < min ? min : (value > max ? max : value);
  }
};

}  // namespace umbra
