// Log-odds arithmetic, sensor model and threshold validation, clamping.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "umbra/core/log_odds.hpp"

namespace umbra {
namespace {

TEST(LogOdds, LogitAndProbabilityAreInverse) {
  for (const double p : {0.01, 0.1192, 0.4, 0.5, 0.7, 0.971, 0.99}) {
    EXPECT_NEAR(probability(logit(p)), p, 1e-6) << p;
  }
  EXPECT_EQ(logit(0.5), 0.0f);
}

TEST(LogOdds, DefaultSensorModelMatchesOctoMap) {
  const SensorModel model;
  // OctoMap stores these as float(log(p / (1 - p))).
  EXPECT_EQ(model.hit_log_odds(), static_cast<float>(std::log(0.7 / 0.3)));
  EXPECT_EQ(model.miss_log_odds(), static_cast<float>(std::log(0.4 / 0.6)));
  EXPECT_NEAR(model.hit_log_odds(), 0.8473, 1e-4);
  EXPECT_NEAR(model.miss_log_odds(), -0.4055, 1e-4);
  EXPECT_NEAR(model.clamp_min_log_odds(), -2.00003, 1e-4);
  EXPECT_NEAR(model.clamp_max_log_odds(), 3.51103, 1e-4);
}

TEST(LogOdds, UpdatesClampAtBothEnds) {
  const LogOddsRange range = LogOddsRange::from(SensorModel{});
  const SensorModel model;
  float value = 0.0f;
  for (int i = 0; i < 20; ++i) value = range.add(value, model.hit_log_odds());
  EXPECT_EQ(value, range.max);
  for (int i = 0; i < 40; ++i) value = range.add(value, model.miss_log_odds());
  EXPECT_EQ(value, range.min);
  EXPECT_EQ(range.add(0.0f, model.hit_log_odds()), model.hit_log_odds());
  EXPECT_EQ(range.clamp(100.0f), range.max);
  EXPECT_EQ(range.clamp(-100.0f), range.min);
}

TEST(LogOdds, ThresholdsClassify) {
  const LogOddsThresholds defaults = LogOddsThresholds::from(Thresholds{});
  EXPECT_EQ(defaults.classify(0.0f), OccupancyState::unknown);
  EXPECT_EQ(defaults.classify(0.01f), OccupancyState::occupied);
  EXPECT_EQ(defaults.classify(-0.01f), OccupancyState::free);

  const LogOddsThresholds wide = LogOddsThresholds::from(Thresholds{0.7, 0.3});
  EXPECT_EQ(wide.classify(logit(0.69)), OccupancyState::unknown);
  EXPECT_EQ(wide.classify(logit(0.71)), OccupancyState::occupied);
  EXPECT_EQ(wide.classify(logit(0.31)), OccupancyState::unknown);
  EXPECT_EQ(wide.classify(logit(0.29)), OccupancyState::free);
}

TEST(LogOdds, ValidationNamesTheBadField) {
  auto message_of = [](auto&& action) {
    try {
      action();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message_of([] { SensorModel{0.4, 0.4, 0.12, 0.97}.validate(); }).find("p_hit"), std::string::npos);
  EXPECT_NE(message_of([] { SensorModel{0.7, 0.6, 0.12, 0.97}.validate(); }).find("p_miss"), std::string::npos);
  EXPECT_NE(message_of([] { SensorModel{0.7, 0.4, 0.0, 0.97}.validate(); }).find("clamp_min"), std::string::npos);
  EXPECT_NE(message_of([] { SensorModel{0.7, 0.4, 0.1, 1.0}.validate(); }).find("clamp_max"), std::string::npos);
  EXPECT_NE(message_of([] {
              SensorModel{std::numeric_limits<double>::quiet_NaN(), 0.4, 0.1, 0.9}.validate();
            }).find("p_hit"),
            std::string::npos);
  EXPECT_NE(message_of([] { Thresholds{0.4, 0.6}.validate(); }).find("free threshold"), std::string::npos);
  EXPECT_NE(message_of([] { Thresholds{1.0, 0.5}.validate(); }).find("occupied threshold"), std::string::npos);
  EXPECT_NO_THROW(SensorModel{}.validate());
  EXPECT_NO_THROW(Thresholds{}.validate());
}

}  // namespace
}  // namespace umbra
