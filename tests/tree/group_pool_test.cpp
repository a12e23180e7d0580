// GroupPool: indices stay unique and addressable across sequential and
// concurrent phases, memory_bytes() follows what is in use, a parallel
// update of a small pool does not cost whole blocks per worker, and
// attached records stay with their groups through growth, phases and copies,
// and so do marks attached to a pool that already holds groups.
#include <algorithm>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tree/group_pool.hpp"

namespace umbra {
namespace {

struct Group {
  std::uint32_t owner;
  std::uint32_t index;  // the index it was handed out under
};
using Pool = GroupPool<Group>;

/// Allocates `count` groups and writes a mark into each.
std::vector<std::uint32_t> take(Pool& pool, std::uint32_t count, std::uint32_t owner) {
  std::vector<std::uint32_t> taken;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint32_t index = pool.allocate();
    pool[index] = {owner, index};
    taken.push_back(index);
  }
  return taken;
}

/// Every live group still holds its mark, and no index is handed out twice.
void expect_marks(const Pool& pool, const std::vector<std::vector<std::uint32_t>>& live) {
  std::vector<bool> seen;
  std::size_t count = 0;
  for (std::uint32_t owner = 0; owner < live.size(); ++owner) {
    for (const std::uint32_t index : live[owner]) {
      if (index >= seen.size()) seen.resize(std::size_t{index} * 2 + 1);
      ASSERT_FALSE(seen[index]) << "index " << index << " handed out twice";
      seen[index] = true;
      ++count;
      ASSERT_EQ(pool[index].owner, owner);
      ASSERT_EQ(pool[index].index, index);
    }
  }
  EXPECT_EQ(pool.size(), count);
}

TEST(GroupPool, SequentialAllocationReusesReleasedGroupsAndGrowsInBlocks) {
  Pool pool;
  EXPECT_EQ(pool.memory_bytes(), 0u);
  std::vector<std::vector<std::uint32_t>> live{take(pool, 3000, 0)};
  expect_marks(pool, live);
  // Three full blocks: the first grown by doubling, the others full sized from the start.
  EXPECT_GE(pool.memory_bytes(), 3000 * sizeof(Group));
  EXPECT_LE(pool.memory_bytes(), (2 * Pool::kBlockGroups + Pool::kBlockGroups) * sizeof(Group) + 256);

  for (std::size_t i = 0; i < 1000; ++i) pool.release(live[0][i]);
  live[0].erase(live[0].begin(), live[0].begin() + 1000);
  const std::size_t before = pool.memory_bytes();
  live.push_back(take(pool, 1000, 1));
  expect_marks(pool, live);
  EXPECT_EQ(pool.memory_bytes(), before) << "released groups are handed out before the pool grows";
}

TEST(GroupPool, LargePoolsGrowInHugePageChunks) {
  // Past kHugePageAfterBytes new blocks are carved from 2 MiB chunks: the
  // groups keep their marks through growth, a concurrent phase, recycling
  // and a copy, and the pool counts whole chunks, at most one of them unused.
  Pool pool;
  const std::uint32_t count = static_cast<std::uint32_t>(5 * Pool::kHugePageAfterBytes / 4 / sizeof(Group));
  std::vector<std::vector<std::uint32_t>> live{take(pool, count, 0), {}, {}};
  expect_marks(pool, live);
  const std::size_t chunk = detail::HugePageChunks::kChunkBytes;
  EXPECT_GE(pool.huge_page_bytes(), std::size_t{count} * sizeof(Group) - Pool::kHugePageAfterBytes - chunk);
  EXPECT_GE(pool.memory_bytes(), std::size_t{count} * sizeof(Group));
  EXPECT_LE(pool.memory_bytes(), std::size_t{count} * sizeof(Group) + chunk + Pool::kBlockGroups * sizeof(Group) + 4096 +
                                     (count / Pool::kBlockGroups + 1) * 16);
  pool.begin_concurrent(2, 2 * Pool::kBlockGroups * 40);
  std::thread first([&] {
    for (std::uint32_t i = 0; i < Pool::kBlockGroups * 40; ++i) {
      const std::uint32_t index = pool.allocate(0u);
      pool[index] = {1, index};
      live[1].push_back(index);
    }
  });
  for (std::uint32_t i = 0; i < Pool::kBlockGroups * 40; ++i) {
    const std::uint32_t index = pool.allocate(1u);
    pool[index] = {2, index};
    live[2].push_back(index);
  }
  first.join();
  pool.end_concurrent();
  expect_marks(pool, live);
  const Pool copy = pool;
  expect_marks(copy, live);
  const std::size_t before = pool.memory_bytes();
  pool.recycle();
  EXPECT_EQ(pool.size(), 0u);
  const std::vector<std::vector<std::uint32_t>> again{take(pool, count, 5)};
  std::set<std::uint32_t> indices(again[0].begin(), again[0].end());
  EXPECT_EQ(indices.size(), again[0].size());
  for (const std::uint32_t index : again[0]) ASSERT_EQ(pool[index].owner, 5u);
  EXPECT_EQ(pool.memory_bytes(), before) << "recycled groups reuse the memory";
}

TEST(GroupPool, ConcurrentWorkersGetDistinctGroups) {
  Pool pool;
  std::vector<std::vector<std::uint32_t>> live{take(pool, 500, 0), {}, {}};
  for (std::size_t i = 0; i < 100; ++i) pool.release(live[0][i]);
  live[0].erase(live[0].begin(), live[0].begin() + 100);

  constexpr std::uint32_t kPerWorker = 2500;
  pool.begin_concurrent(2, 2 * kPerWorker);
  auto work = [&](unsigned worker) {
    std::vector<std::uint32_t>& mine = live[worker + 1];
    for (std::uint32_t i = 0; i < kPerWorker; ++i) {
      const std::uint32_t index = pool.allocate(worker);
      pool[index] = {worker + 1, index};
      mine.push_back(index);
      if (i % 7 == 3) {  // give one back now and then, as pruning does
        pool.release(worker, mine.back());
        mine.pop_back();
      }
    }
  };
  std::thread first(work, 0u);
  std::thread second(work, 1u);
  first.join();
  second.join();
  pool.end_concurrent();
  expect_marks(pool, live);

  // Sequential allocation after the phase goes on from where it stopped.
  live.push_back(take(pool, 2000, 3));
  expect_marks(pool, live);
  const std::size_t in_use = pool.size();
  EXPECT_LE(pool.memory_bytes(), (in_use + 2 * Pool::kChunkGroups + Pool::kBlockGroups) * sizeof(Group) + 1024);
}

TEST(GroupPool, ParallelPhaseOnASmallPoolDoesNotTakeWholeBlocks) {
  Pool pool;
  std::vector<std::vector<std::uint32_t>> live{take(pool, 5, 0), {}};
  pool.begin_concurrent(2, 4);
  for (std::uint32_t i = 0; i < 4; ++i) {
    const std::uint32_t index = pool.allocate(i % 2);
    pool[index] = {1, index};
    live[1].push_back(index);
  }
  pool.end_concurrent();
  expect_marks(pool, live);
  // 9 groups in use; room for the bound plus one chunk per worker at most.
  EXPECT_LT(pool.memory_bytes(), Pool::kBlockGroups * sizeof(Group) / 2);
  Pool copy = pool;
  expect_marks(copy, live);
  EXPECT_LE(copy.memory_bytes(), pool.memory_bytes()) << "a copy holds no more than the original";
}

TEST(GroupPool, ExceedingTheBoundOfAParallelPhaseIsReported) {
  Pool pool;
  take(pool, 5, 0);
  pool.begin_concurrent(1, 2);
  EXPECT_THROW(
      {
        for (int i = 0; i < 10000; ++i) pool.allocate(0u);
      },
      std::logic_error);
  pool.end_concurrent();
}

/// The side-record tests' middle part: releases the first 300 groups of
/// `live`, then two workers take 1500 groups each in one concurrent phase
/// and `fill(index, worker)` each (its group and its record); the new groups
/// join `live`.
template <typename TestPool, typename Fill>
void release_then_fill_concurrently(TestPool& pool, std::vector<std::uint32_t>& live, Fill fill) {
  for (std::size_t i = 0; i < 300; ++i) pool.release(live[i]);
  live.erase(live.begin(), live.begin() + 300);
  pool.begin_concurrent(2, 3000);
  std::vector<std::vector<std::uint32_t>> taken(2);
  auto work = [&](unsigned worker) {
    for (std::uint32_t i = 0; i < 1500; ++i) {
      const std::uint32_t index = pool.allocate(worker);
      fill(index, worker);
      taken[worker].push_back(index);
    }
  };
  std::thread first(work, 0u);
  std::thread second(work, 1u);
  first.join();
  second.join();
  pool.end_concurrent();
  for (const auto& t : taken) live.insert(live.end(), t.begin(), t.end());
}

TEST(GroupPool, AttachedRecordsStayWithTheirGroups) {
  struct Tag {
    std::uint64_t index;
    std::uint64_t check;
  };
  using TaggedPool = GroupPool<Group, Tag>;
  TaggedPool pool(true);
  Pool plain;
  ASSERT_TRUE(pool.has_attached());
  ASSERT_FALSE(plain.has_attached());
  std::vector<std::uint32_t> live;
  const auto mark = [&](std::uint32_t index, std::uint32_t owner) {
    pool[index] = {owner, index};
    pool.attached(index) = {index, ~std::uint64_t{index}};
    live.push_back(index);
  };
  // Across the doubling of the first block and into a second block.
  for (std::uint32_t i = 0; i < 1500; ++i) {
    mark(pool.allocate(), 0);
    plain.allocate();
  }
  // The same blocks as a plain pool, each with its records: the first block
  // doubled from 8 groups to full size, and a second block full sized from
  // the start for the other 476.
  EXPECT_EQ(pool.memory_bytes() - plain.memory_bytes(),
            2 * TaggedPool::kBlockGroups * sizeof(Tag) + 2 * sizeof(std::unique_ptr<Tag[], detail::BlockDeleter<Tag>>))
      << "two blocks of records and their two table entries";
  release_then_fill_concurrently(pool, live, [&](std::uint32_t index, unsigned worker) {
    pool[index] = {worker + 1, index};
    pool.attached(index) = {index, ~std::uint64_t{index}};
  });
  const auto expect_tags = [&](const TaggedPool& p) {
    for (const std::uint32_t index : live) {
      ASSERT_EQ(p[index].index, index);
      ASSERT_EQ(p.attached(index).index, index);
      ASSERT_EQ(p.attached(index).check, ~std::uint64_t{index});
    }
  };
  expect_tags(pool);
  const TaggedPool copy = pool;
  expect_tags(copy);
  EXPECT_TRUE(copy.has_attached());
}

TEST(GroupPool, MarksAttachedLaterStayWithTheirGroups) {
  // Attached while the first block is still small (so it must grow with the
  // groups' block), then across a second block, a concurrent phase, a
  // release and a copy; a pool without marks pays nothing for them.
  using MarkedPool = GroupPool<Group, NoAttachment, std::uint64_t>;
  MarkedPool pool;
  Pool plain;
  std::vector<std::uint32_t> live;
  for (std::uint32_t i = 0; i < 5; ++i) {
    const std::uint32_t index = pool.allocate();
    pool[index] = {0, index};
    live.push_back(index);
    plain.allocate();
  }
  EXPECT_EQ(pool.memory_bytes(), plain.memory_bytes()) << "no marks before attach_marks()";
  EXPECT_FALSE(pool.has_marks());
  pool.attach_marks(7);
  ASSERT_TRUE(pool.has_marks());
  for (const std::uint32_t index : live) ASSERT_EQ(pool.mark(index), 7u) << "the initial mark of group " << index;
  const auto tag = [&](std::uint32_t index) { pool.mark(index) = ~std::uint64_t{index}; };
  for (const std::uint32_t index : live) tag(index);
  for (std::uint32_t i = 0; i < 1500; ++i) {
    const std::uint32_t index = pool.allocate();
    pool[index] = {0, index};
    tag(index);
    live.push_back(index);
  }
  release_then_fill_concurrently(pool, live, [&](std::uint32_t index, unsigned worker) {
    pool[index] = {worker + 1, index};
    pool.mark(index) = ~std::uint64_t{index};
  });
  const auto expect_tags = [&](const MarkedPool& p) {
    for (const std::uint32_t index : live) {
      ASSERT_EQ(p[index].index, index);
      ASSERT_EQ(p.mark(index), ~std::uint64_t{index}) << "the mark of group " << index;
    }
  };
  expect_tags(pool);
  const MarkedPool copy = pool;
  expect_tags(copy);
  EXPECT_TRUE(copy.has_marks());
}

}  // namespace
}  // namespace umbra
