// radix_sort: the order of std::stable_sort by the same key, with 8-bit
// digits (few records) and 16-bit digits (many), for keys whose width is
// and is not a multiple of the digit.
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/radix_sort.hpp"

namespace umbra {
namespace {

struct Record {
  std::uint64_t key;
  std::uint32_t order;  // the record's place before sorting: tells whether equal keys kept their order
  bool operator==(const Record&) const = default;
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

}  // namespace
}  // namespace umbra
