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
//
// parallel_radix_sort sorts the concatenation of several parts the same
// way, bit for bit, with a part per worker of a thread pool: each pass
// counts every part's digits on its own worker, the offsets are laid out
// digit by digit and, within a digit, part by part (so equal keys keep the
// order of the concatenation), and each worker moves its part's records to
// them. Only that layout is serial: 2^16 entries per part and pass.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/thread_pool.hpp"

namespace umbra {

/// Fewer records than this are sorted with 8-bit digits, more with 16-bit
/// ones (48-bit keys, g++ -O2 on the test machine: 8-bit digits were 90
/// times faster for 100 records, 1.6 times for 65,536, even at 300,000).
inline constexpr std::size_t kRadixSortFewRecords = 65536;

/// The buffers a sort works in, kept by a caller that sorts every scan so
/// that no pass allocates (a fresh buffer costs a page fault per 4 KiB).
template <typename Record>
struct RadixSortScratch {
  std::vector<Record> records;
  std::vector<std::uint32_t> counts;
};

template <typename Record, typename KeyOf>
void radix_sort(std::vector<Record>& records, int key_bits, KeyOf key_of, RadixSortScratch<Record>& scratch) {
  if (records.size() < 2) return;
  const int digit_bits = records.size() < kRadixSortFewRecords ? 8 : 16;
  const std::size_t buckets = std::size_t{1} << digit_bits;
  scratch.records.resize(records.size());
  std::vector<std::uint32_t>& counts = scratch.counts;
  counts.resize(buckets);
  for (int shift = 0; shift < key_bits; shift += digit_bits) {
    std::fill(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(buckets), 0u);
    for (const Record& r : records) ++counts[(key_of(r) >> shift) & (buckets - 1)];
    std::uint32_t offset = 0;
    for (std::size_t b = 0; b < buckets; ++b) {
      const std::uint32_t n = counts[b];
      counts[b] = offset;
      offset += n;
    }
    for (const Record& r : records) scratch.records[counts[(key_of(r) >> shift) & (buckets - 1)]++] = r;
    records.swap(scratch.records);  // both buffers stay with their owners for the next sort
  }
}

template <typename Record, typename KeyOf>
void radix_sort(std::vector<Record>& records, int key_bits, KeyOf key_of) {
  RadixSortScratch<Record> scratch;
  radix_sort(records, key_bits, key_of, scratch);
}

/// The records of parts[0], parts[1], ... in one vector, stably sorted by
/// key as radix_sort would sort their concatenation; with a pool, a worker
/// per part. Empties the parts.
template <typename Record, typename KeyOf>
std::vector<Record> parallel_radix_sort(std::vector<std::vector<Record>>& parts, int key_bits, KeyOf key_of,
                                        ThreadPool* pool) {
  constexpr int kDigitBits = 16;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  const std::size_t part_count = parts.size();
  std::vector<std::size_t> first(part_count + 1, 0);  // where part p begins in the concatenation
  for (std::size_t p = 0; p < part_count; ++p) first[p + 1] = first[p] + parts[p].size();
  const std::size_t total = first[part_count];
  if (total > UINT32_MAX) throw std::length_error("parallel_radix_sort: more than 2^32 - 1 records");
  std::vector<Record> sorted;
  if (pool == nullptr || pool->size() < 2 || part_count < 2) {
    // One thread: the concatenation sorted in place (one scratch buffer, as radix_sort).
    sorted = part_count == 0 ? std::vector<Record>() : std::move(parts[0]);
    sorted.reserve(total);
    for (std::size_t p = 1; p < part_count; ++p) sorted.insert(sorted.end(), parts[p].begin(), parts[p].end());
    radix_sort(sorted, key_bits, key_of);
  } else if (total < 2 || key_bits <= 0) {
    for (std::vector<Record>& part : parts) sorted.insert(sorted.end(), part.begin(), part.end());
  } else {
    const auto for_each_part = [&](const auto& work) {
      pool->run(part_count, [&](std::size_t p, unsigned) { work(p); });
    };
    std::vector<Record> from(total);
    std::vector<Record> to(total);
    std::vector<std::uint32_t> offsets(part_count * kBuckets);  // [p * kBuckets + digit]
    for (int shift = 0; shift < key_bits; shift += kDigitBits) {
      // The first pass reads the parts; the later ones part p's range of `from`.
      const auto part_records = [&](std::size_t p) {
        const Record* begin = shift == 0 ? parts[p].data() : from.data() + first[p];
        return std::pair{begin, begin + (first[p + 1] - first[p])};
      };
      for_each_part([&](std::size_t p) {
        std::uint32_t* counts = offsets.data() + p * kBuckets;
        std::fill(counts, counts + kBuckets, 0u);
        const auto [begin, end] = part_records(p);
        for (const Record* r = begin; r != end; ++r) ++counts[(key_of(*r) >> shift) & (kBuckets - 1)];
      });
      std::uint32_t offset = 0;
      for (std::size_t digit = 0; digit < kBuckets; ++digit) {
        for (std::size_t p = 0; p < part_count; ++p) {
          std::uint32_t& c = offsets[p * kBuckets + digit];
          const std::uint32_t n = c;
          c = offset;
          offset += n;
        }
      }
      for_each_part([&](std::size_t p) {
        std::uint32_t* next = offsets.data() + p * kBuckets;
        const auto [begin, end] = part_records(p);
        for (const Record* r = begin; r != end; ++r) to[next[(key_of(*r) >> shift) & (kBuckets - 1)]++] = *r;
      });
      from.swap(to);
    }
    sorted = std::move(from);
  }
  for (std::vector<Record>& part : parts) std::vector<Record>().swap(part);
  return sorted;
}

}  // namespace umbra
