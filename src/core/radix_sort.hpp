// radix_sort: a stable LSD radix sort of records by an unsigned key.
//
// Sorting the Morton codes of a scan's end points with std::sort costs about
// 20 ms for the 307,200 points of a Kinect frame; three 16-bit passes over
// the 48 bits of a 16-level code take a few. `key_bits` bounds the key (bits
// above it must be zero); records with equal keys keep their order.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace umbra {

template <typename Record, typename KeyOf>
void radix_sort(std::vector<Record>& records, int key_bits, KeyOf key_of) {
  constexpr int kDigitBits = 16;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  if (records.size() < 2) return;
  std::vector<Record> scratch(records.size());
  std::vector<std::uint32_t> counts(kBuckets);
  for (int shift = 0; shift < key_bits; shift += kDigitBits) {
    std::fill(counts.begin(), counts.end(), 0u);
    for (const Record& r : records) ++counts[(key_of(r) >> shift) & (kBuckets - 1)];
    std::uint32_t offset = 0;
    for (std::uint32_t& c : counts) {
      const std::uint32_t n = c;
      c = offset;
      offset += n;
    }
    for (const Record& r : records) scratch[counts[(key_of(r) >> shift) & (kBuckets - 1)]++] = r;
    records.swap(scratch);
  }
}

}  // namespace umbra
