// radix_sort: a stable LSD radix sort of records by an unsigned key.
//
// Sorting the Morton codes of a scan's end points with std::sort costs about
// 20 ms for the 307,200 points of a Kinect frame; three 16-bit passes over
// the 48 bits of a 16-level code take a few. `key_bits` bounds the key (bits
// above it must be zero); records with equal keys keep their order.
//
// Digits of 16 bits for many records, of 8 bits for few: a pass costs about
// the records plus the buckets, and clearing and summing 65,536 buckets
// (a 256 KB histogram) for a scan of a few dozen points cost more than the
// rest of its insertion (umbra_fuzz_insert's small scans spent a fifth of
// their time there).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace umbra {

/// Fewer records than this are sorted with 8-bit digits, more with 16-bit
/// ones (48-bit keys, g++ -O2 on the test machine: 8-bit digits were 90
/// times faster for 100 records, 1.6 times for 65,536, even at 300,000).
inline constexpr std::size_t kRadixSortFewRecords = 65536;

template <typename Record, typename KeyOf>
void radix_sort(std::vector<Record>& records, int key_bits, KeyOf key_of) {
  if (records.size() < 2) return;
  const int digit_bits = records.size() < kRadixSortFewRecords ? 8 : 16;
  const std::size_t buckets = std::size_t{1} << digit_bits;
  std::vector<Record> scratch(records.size());
  std::vector<std::uint32_t> counts(buckets);
  for (int shift = 0; shift < key_bits; shift += digit_bits) {
    std::fill(counts.begin(), counts.end(), 0u);
    for (const Record& r : records) ++counts[(key_of(r) >> shift) & (buckets - 1)];
    std::uint32_t offset = 0;
    for (std::uint32_t& c : counts) {
      const std::uint32_t n = c;
      c = offset;
      offset += n;
    }
    for (const Record& r : records) scratch[counts[(key_of(r) >> shift) & (buckets - 1)]++] = r;
    records.swap(scratch);
  }
}

}  // namespace umbra
