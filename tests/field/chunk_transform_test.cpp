// ChunkTransform (src/field/distance_transform.*) on random sites, against
// itself with every brick of the chunk wanted and the field's full window:
//   - a few wanted bricks give the same offsets as all of them (the passes
//     skip what no wanted brick reads, ChunkReach), also when the same
//     transform ran on another chunk before (skipped rows hold stale data);
//   - a narrower window gives the same offsets wherever it answers, and
//     "none" only where the nearest site is at least as far as a site
//     outside that window can be (reach_cap()).
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <vector>

#include "field/distance_transform.hpp"
#include "field/field_layout.hpp"

namespace umbra::detail {
namespace {

using Offsets = std::map<std::uint64_t, BrickOffsets>;

/// Random sites over the bricks near the chunks the tests run (unknown
/// sites in clusters, so that some cells find one only far away).
class RandomSites {
 public:
  explicit RandomSites(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> percent(0, 99);
    for (std::uint32_t z = 0; z < 24; ++z) {
      for (std::uint32_t y = 0; y < 24; ++y) {
        for (std::uint32_t x = 0; x < 24; ++x) {
          BrickBits bits;
          const bool unknown_cluster = percent(rng) < 15;
          for (int i = 0; i < kBrickVolume; ++i) {
            const int r = percent(rng);
            if (r < 1) bits.occupied[std::size_t(i >> 6)] |= std::uint64_t{1} << (i & 63);
            if (unknown_cluster && r > 60) bits.unknown[std::size_t(i >> 6)] |= std::uint64_t{1} << (i & 63);
          }
          bricks_.emplace(BrickIndex{x, y, z}.packed(), bits);
        }
      }
    }
  }
  [[nodiscard]] const BrickBits* at(BrickIndex b) const {
    const auto it = bricks_.find(b.packed());
    return it != bricks_.end() ? &it->second : &empty_;
  }

 private:
  std::map<std::uint64_t, BrickBits> bricks_;
  BrickBits empty_;
};

Offsets run(ChunkTransform& transform, BrickIndex first, const RandomSites& sites,
            const std::set<std::uint64_t>* wanted) {
  Offsets out;
  transform.run(
      first, [&](BrickIndex b) { return sites.at(b); },
      [&](BrickIndex b) { return wanted == nullptr || wanted->contains(b.packed()); },
      [&](BrickIndex b, const BrickOffsets& offsets) { out[b.packed()] = offsets; });
  return out;
}

bool same(SiteOffset a, SiteOffset b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

TEST(ChunkTransform, FewWantedBricksAnswerAsAllOfThem) {
  const FieldLayout layout(0.1, 16, 0, 1.0);  // a window of 10 cells, chunks of 4^3 bricks
  const RandomSites sites(7);
  ChunkTransform all_wanted(layout, layout.window());
  ChunkTransform few_wanted(layout, layout.window());
  const int n = all_wanted.bricks_per_axis();
  std::mt19937 rng(8);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(n) - 1);
  for (const std::uint32_t c : {1u, 2u, 3u}) {
    const BrickIndex first{c * std::uint32_t(n), std::uint32_t(n), c * std::uint32_t(n)};
    const Offsets reference = run(all_wanted, first, sites, nullptr);
    ASSERT_EQ(reference.size(), std::size_t(n * n * n));
    std::set<std::uint64_t> wanted;
    for (int i = 0; i < 3; ++i) wanted.insert(BrickIndex{first.x + pick(rng), first.y + pick(rng), first.z + pick(rng)}.packed());
    const Offsets got = run(few_wanted, first, sites, &wanted);
    ASSERT_EQ(got.size(), wanted.size());
    for (const auto& [key, offsets] : got) {
      const BrickOffsets& expected = reference.at(key);
      for (int i = 0; i < kBrickVolume; ++i) {
        ASSERT_TRUE(same(offsets[std::size_t(i)].occupied, expected[std::size_t(i)].occupied)) << "chunk " << c << " cell " << i;
        ASSERT_TRUE(same(offsets[std::size_t(i)].unknown, expected[std::size_t(i)].unknown)) << "chunk " << c << " cell " << i;
      }
    }
  }
}

TEST(ChunkTransform, NarrowWindowAnswersExactlyOrNotAtAll) {
  const FieldLayout layout(0.1, 16, 0, 1.0);
  const RandomSites sites(9);
  const int narrow_window = 3;
  const std::uint64_t bound = layout.squared_gap(narrow_window + 1);  // the least S of a site outside it
  ChunkTransform full(layout, layout.window());
  ChunkTransform narrow(layout, narrow_window);
  ASSERT_EQ(reach_cap(layout, narrow_window), bound - 1);
  ASSERT_EQ(reach_cap(layout, layout.window()), layout.cap_squared());
  std::size_t answered = 0, unanswered = 0;
  // Narrow chunks are smaller: run each of them inside one full chunk.
  const std::uint32_t n = std::uint32_t(full.bricks_per_axis());
  const std::uint32_t m = std::uint32_t(narrow.bricks_per_axis());
  const BrickIndex first{n, n, n};
  const Offsets reference = run(full, first, sites, nullptr);
  for (std::uint32_t z = 0; z < n; z += m) {
    for (std::uint32_t y = 0; y < n; y += m) {
      for (std::uint32_t x = 0; x < n; x += m) {
        const Offsets got = run(narrow, BrickIndex{first.x + x, first.y + y, first.z + z}, sites, nullptr);
        for (const auto& [key, offsets] : got) {
          const BrickOffsets& expected = reference.at(key);
          for (int i = 0; i < kBrickVolume; ++i) {
            for (int kind = 0; kind < 2; ++kind) {
              const SiteOffset g = kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown;
              const SiteOffset e = kind == 0 ? expected[std::size_t(i)].occupied : expected[std::size_t(i)].unknown;
              if (!g.none()) {
                ++answered;
                ASSERT_TRUE(same(g, e)) << "cell " << i << " kind " << kind;
              } else {
                ++unanswered;
                ASSERT_TRUE(e.none() || layout.squared(e) >= bound) << "cell " << i << " kind " << kind;
              }
            }
          }
        }
      }
    }
  }
  // Both cases occur (the test would prove little otherwise).
  EXPECT_GT(answered, 1000u);
  EXPECT_GT(unanswered, 1000u);
}

}  // namespace
}  // namespace umbra::detail
