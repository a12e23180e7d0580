// The eight-lane group arithmetic (SSE2 where the CPU has it) against the
// scalar loops it replaces, value for value and bit for bit, on random
// groups whose values sit on and around the thresholds and clamping limits.
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "tree/group_lanes.hpp"

namespace umbra::detail {
namespace {

const LogOddsThresholds kThresholds{0.4f, -0.2f};  // occupied, free
const LogOddsRange kRange{-2.0f, 3.5f};

/// Values a group really holds and the ones where a compare can go wrong.
std::vector<float> interesting_values() {
  std::vector<float> values = {0.0f, kThresholds.free, kThresholds.occupied, kRange.min, kRange.max, 0.85f, -0.4f};
  const std::size_t base = values.size();
  for (std::size_t i = 0; i < base; ++i) {
    values.push_back(std::nextafter(values[i], -10.0f));
    values.push_back(std::nextafter(values[i], 10.0f));
  }
  return values;
}

std::array<float, 8> random_group(std::mt19937& rng, const std::vector<float>& pool) {
  std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
  std::uniform_real_distribution<float> any(kRange.min, kRange.max);
  std::bernoulli_distribution from_pool(0.7);
  std::bernoulli_distribution all_same(0.1);
  std::array<float, 8> group{};
  for (float& v : group) v = from_pool(rng) ? pool[pick(rng)] : any(rng);
  if (all_same(rng)) group.fill(group[0]);
  return group;
}

TEST(GroupLanes, SummaryEqualsTheScalarLoop) {
  std::mt19937 rng(7);
  const std::vector<float> pool = interesting_values();
  int same_groups = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::array<float, 8> group = random_group(rng, pool);
    const LaneSummary lanes = summarize_lanes(group, kThresholds);
    const LaneSummary scalar = summarize_lanes_scalar(group, kThresholds);
    ASSERT_EQ(std::bit_cast<std::uint32_t>(lanes.max), std::bit_cast<std::uint32_t>(scalar.max)) << trial;
    ASSERT_EQ(lanes.free, scalar.free) << trial;
    ASSERT_EQ(lanes.unknown, scalar.unknown) << trial;
    ASSERT_EQ(lanes.same, scalar.same) << trial;
    same_groups += scalar.same ? 1 : 0;
  }
  EXPECT_GT(same_groups, 1000);  // the all-equal branch was exercised
}

TEST(GroupLanes, ScalarSummaryFollowsTheThresholds) {
  const std::array<float, 8> group = {kThresholds.free, std::nextafter(kThresholds.free, -1.0f), kThresholds.occupied,
                                      std::nextafter(kThresholds.occupied, 1.0f), 0.0f, kRange.min, kRange.max, 0.0f};
  const LaneSummary s = summarize_lanes(group, kThresholds);
  EXPECT_EQ(s.max, kRange.max);
  EXPECT_EQ(s.free, 0b0010'0010);     // below free: the value just under it and the minimum
  EXPECT_EQ(s.unknown, 0b1001'0101);  // both thresholds count as unknown
  EXPECT_FALSE(s.same);
}

TEST(GroupLanes, UpdateEqualsTheScalarLoopBitForBit) {
  std::mt19937 rng(11);
  const std::vector<float> pool = interesting_values();
  std::uniform_int_distribution<int> byte(0, 255);
  const float hit = 0.85f;
  const float miss = -0.4f;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<float, 8> lanes = random_group(rng, pool);
    std::array<float, 8> scalar = lanes;
    const auto hits = static_cast<std::uint8_t>(byte(rng));
    const auto misses = static_cast<std::uint8_t>(byte(rng));
    const LaneSummary from_lanes = update_lanes(lanes, hits, misses, hit, miss, kRange, kThresholds);
    const LaneSummary from_scalar = update_lanes_scalar(scalar, hits, misses, hit, miss, kRange, kThresholds);
    for (unsigned i = 0; i < 8; ++i) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(lanes[i]), std::bit_cast<std::uint32_t>(scalar[i]))
          << "trial " << trial << " lane " << i << " hits " << int(hits) << " misses " << int(misses);
    }
    // The summary returned is that of the new values.
    const LaneSummary fresh = summarize_lanes_scalar(scalar, kThresholds);
    ASSERT_EQ(std::bit_cast<std::uint32_t>(from_lanes.max), std::bit_cast<std::uint32_t>(fresh.max)) << trial;
    ASSERT_EQ(from_lanes.free, fresh.free) << trial;
    ASSERT_EQ(from_lanes.unknown, fresh.unknown) << trial;
    ASSERT_EQ(from_lanes.same, fresh.same) << trial;
    ASSERT_EQ(from_scalar.max, fresh.max) << trial;
  }
}

TEST(GroupLanes, ScalarUpdateIsOctoMapsRule) {
  std::array<float, 8> v = {0.0f, 0.0f, 3.4f, -1.9f, 1.0f, 1.0f, 1.0f, 1.0f};
  // hit on 0, 2 and 6 (6 also has a miss: the hit wins), miss on 1, 3 and 6.
  update_lanes(v, 0b0100'0101, 0b0100'1010, 0.85f, -0.4f, kRange, kThresholds);
  EXPECT_EQ(v[0], 0.85f);
  EXPECT_EQ(v[1], -0.4f);
  EXPECT_EQ(v[2], kRange.max);  // clamped
  EXPECT_EQ(v[3], kRange.min);  // clamped
  EXPECT_EQ(v[4], 1.0f);        // untouched
  EXPECT_EQ(v[6], 1.0f + 0.85f);
}

}  // namespace
}  // namespace umbra::detail
