// radix_sort gives the order of std::stable_sort by the same key, with
// 8-bit digits (few records) and 16-bit digits (many), for keys whose width
// is and is not a multiple of the digit; parallel_radix_sort gives the order
// std::stable_sort gives the concatenation of its parts (equal keys keep the
// order of the parts, then of the records within a part), for any split
// into parts, any pool size, and keys narrower or wider than one 16-bit
// digit.
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/radix_sort.hpp"
#include "core/thread_pool.hpp"

namespace umbra {
namespace {

struct Record {
  std::uint64_t key;
  std::uint32_t order;  // position in the concatenation
  friend bool operator==(const Record&, const Record&) = default;
};

/// `count` records with random keys of `key_bits` bits, at most `distinct`
/// different ones (so that many keys repeat), sorted both ways.
void expect_stable_sort_order(std::size_t count, int key_bits, std::uint64_t distinct) {
  std::mt19937_64 rng(count * 131 + static_cast<std::uint64_t>(key_bits));
  const std::uint64_t mask = key_bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << key_bits) - 1;
  std::vector<std::uint64_t> keys(distinct);
  for (std::uint64_t& k : keys) k = rng() & mask;
  keys.back() = mask;  // the highest key too: its top bits must be sorted
  std::vector<Record> records(count);
  for (std::size_t i = 0; i < count; ++i) records[i] = {keys[rng() % distinct], static_cast<std::uint32_t>(i)};
  std::vector<Record> expected = records;
  std::stable_sort(expected.begin(), expected.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
  radix_sort(records, key_bits, [](const Record& r) { return r.key; });
  ASSERT_EQ(records.size(), expected.size());
  for (std::size_t i = 0; i < count; ++i) {
    ASSERT_EQ(records[i], expected[i]) << "record " << i << " of " << count << ", key bits " << key_bits;
  }
}

TEST(RadixSort, FewRecordsSortLikeStableSort) {
  for (int key_bits : {1, 8, 15, 30, 45, 48, 63}) {
    for (std::size_t count : {0u, 1u, 2u, 3u, 24u, 1000u}) {
      expect_stable_sort_order(count, key_bits, std::max<std::uint64_t>(1, count / 4));
    }
  }
}

TEST(RadixSort, ManyRecordsSortLikeStableSort) {
  for (int key_bits : {16, 30, 48}) {
    expect_stable_sort_order(kRadixSortFewRecords, key_bits, 20000);
    expect_stable_sort_order(kRadixSortFewRecords + 1000, key_bits, kRadixSortFewRecords / 2);
  }
}

TEST(RadixSort, BoundaryBetweenDigitWidthsSortsLikeStableSort) {
  expect_stable_sort_order(kRadixSortFewRecords - 1, 48, 1000);
}

TEST(RadixSort, ParallelSortIsTheStableSortOfTheConcatenation) {
  std::mt19937_64 rng(11);
  ThreadPool two(2);
  ThreadPool three(3);
  for (const int key_bits : {3, 16, 20, 48}) {
    // Few distinct keys: most records tie with others in other parts.
    for (const std::uint64_t distinct : {std::uint64_t{5}, std::uint64_t{1} << 40}) {
      for (const std::vector<std::size_t>& sizes :
           {std::vector<std::size_t>{1000}, {700, 0, 1300}, {1, 2, 3, 4000, 17}, {0, 0}, {2500, 2500}}) {
        SCOPED_TRACE("key bits " + std::to_string(key_bits) + ", parts " + std::to_string(sizes.size()));
        const std::uint64_t mask = (std::uint64_t{1} << key_bits) - 1;
        std::vector<std::vector<Record>> parts;
        std::vector<Record> all;
        for (const std::size_t size : sizes) {
          parts.emplace_back();
          for (std::size_t i = 0; i < size; ++i) {
            const Record r{(rng() % distinct * 0x9E3779B97F4A7C15ull) & mask, static_cast<std::uint32_t>(all.size())};
            parts.back().push_back(r);
            all.push_back(r);
          }
        }
        std::stable_sort(all.begin(), all.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
        for (ThreadPool* pool : {static_cast<ThreadPool*>(nullptr), &two, &three}) {
          std::vector<std::vector<Record>> copy = parts;
          const std::vector<Record> sorted =
              parallel_radix_sort(copy, key_bits, [](const Record& r) { return r.key; }, pool);
          EXPECT_TRUE(sorted == all);
          for (const auto& part : copy) EXPECT_TRUE(part.empty());
        }
        // The serial sort of the concatenation agrees too.
        std::vector<Record> serial;
        for (const auto& part : parts) serial.insert(serial.end(), part.begin(), part.end());
        radix_sort(serial, key_bits, [](const Record& r) { return r.key; });
        EXPECT_TRUE(serial == all);
      }
    }
  }
}

}  // namespace
}  // namespace umbra
