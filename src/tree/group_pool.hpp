// GroupPool: blocked storage for sibling groups, addressed by 32-bit index.
//
// Every node group of one depth lives in one pool. Groups are addressed by a
// uint32 index (half the size of a pointer), stored in blocks of
// kBlockGroups so that growing never moves a group (no reallocation copy, no
// peak of twice the size as with std::vector) and the unused tail is at most
// one block. The last block starts small and doubles until it is full sized,
// so a pool for the few groups near the root costs a few hundred bytes, not
// a whole block. Released groups go to a free list and are handed out again.
//
// memory_bytes() is what the pool really allocated (block capacity, free
// list capacity, block table), never an estimate from a count of groups.
//
// Concurrent allocation, for a parallel phase (OccupancyTree::apply with a
// thread pool): begin_concurrent() grows the last block just enough for the
// groups the phase can take and reserves the block table, so that no block
// and no table entry moves until end_concurrent(); meanwhile worker w
// allocates and releases only through allocate(w) / release(w, index). Each
// worker takes chunks of kChunkGroups from the shared tail (under a lock,
// once per chunk) and keeps its own free list; at the end the unused rest of
// every chunk and the released groups join the free list. Chunks rather
// than whole blocks per worker: with 16 depths and 2 workers, whole blocks
// made a 0.1 MiB map cost 1.3 MiB (TUM at 16 cm).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "core/assert.hpp"

namespace umbra {

inline constexpr std::uint32_t kNoGroup = 0xFFFFFFFFu;

template <typename Group>
class GroupPool {
 public:
  static constexpr std::uint32_t kBlockBits = 10;
  // 1024 groups per block: at most 68 KiB, below glibc's 128 KiB mmap threshold,
  // so a block costs malloc 16 bytes of header instead of a page of rounding.
  static constexpr std::uint32_t kBlockGroups = 1u << kBlockBits;
  static constexpr std::uint32_t kFirstBlockGroups = 8;

  GroupPool() = default;
  GroupPool(GroupPool&&) noexcept = default;
  GroupPool& operator=(GroupPool&&) noexcept = default;
  GroupPool(const GroupPool& other) { *this = other; }
  GroupPool& operator=(const GroupPool& other) {
    if (this == &other) return *this;
    UMBRA_ASSERT(other.slabs_.empty());
    blocks_.clear();
    blocks_.reserve(other.blocks_.size());
    for (std::size_t b = 0; b < other.blocks_.size(); ++b) {
      const std::uint32_t capacity = other.block_capacity(b);
      blocks_.emplace_back(new Group[capacity]);
      std::copy(other.blocks_[b].get(), other.blocks_[b].get() + capacity, blocks_.back().get());
    }
    last_capacity_ = other.last_capacity_;
    high_water_ = other.high_water_;
    free_ = other.free_;
    return *this;
  }

  // Only the block pointer is read: safe while other workers add blocks
  // during a concurrent phase (the table never reallocates then).
  Group& operator[](std::uint32_t index) {
    UMBRA_ASSERT(!slabs_.empty() || index < high_water_);
    return blocks_.data()[index >> kBlockBits][index & (kBlockGroups - 1)];
  }
  const Group& operator[](std::uint32_t index) const {
    UMBRA_ASSERT(!slabs_.empty() || index < high_water_);
    return blocks_.data()[index >> kBlockBits][index & (kBlockGroups - 1)];
  }

  /// Index of a group whose contents are unspecified; the caller fills it.
  std::uint32_t allocate() {
    UMBRA_ASSERT(slabs_.empty());
    if (!free_.empty()) {
      const std::uint32_t index = free_.back();
      free_.pop_back();
      return index;
    }
    if (high_water_ == kNoGroup) throw std::length_error("umbra: more than 2^32 - 1 node groups at one depth");
    if (high_water_ == capacity()) extend();
    return high_water_++;
  }

  void release(std::uint32_t index) {
    UMBRA_ASSERT(slabs_.empty() && index < high_water_);
    free_.push_back(index);
  }

  // --- concurrent allocation (see the file comment) -------------------------
  static constexpr std::uint32_t kChunkGroups = 64;

  /// `workers` threads will allocate; together at most `max_new_groups` more.
  void begin_concurrent(unsigned workers, std::size_t max_new_groups) {
    UMBRA_ASSERT(slabs_.empty() && workers >= 1);
    if (max_new_groups > 0) {
      // Taken from the tail at most: the new groups plus one unused chunk per worker.
      const std::size_t wanted = high_water_ + max_new_groups + std::size_t{workers} * kChunkGroups;
      if (high_water_ == capacity()) extend();
      while (last_capacity_ < kBlockGroups && capacity() < wanted) grow_last_block();
    }
    blocks_.reserve(blocks_.size() + max_new_groups / kBlockGroups + workers + 1);
    table_limit_ = blocks_.capacity();
    slabs_.resize(workers);
    tail_ = high_water_;
    for (std::size_t i = 0; i < free_.size(); ++i) slabs_[i % workers].released.push_back(free_[i]);
    free_.clear();
    lock_ = std::make_unique<std::mutex>();
  }

  std::uint32_t allocate(unsigned worker) {
    Slab& slab = slabs_[worker];
    if (!slab.released.empty()) {
      const std::uint32_t index = slab.released.back();
      slab.released.pop_back();
      return index;
    }
    if (slab.next == slab.end) {
      std::lock_guard guard(*lock_);
      if (tail_ == capacity()) add_full_block_concurrently();
      slab.next = tail_;
      slab.end = static_cast<std::uint32_t>(std::min<std::uint64_t>(capacity(), std::uint64_t{tail_} + kChunkGroups));
      tail_ = slab.end;
    }
    return slab.next++;
  }

  void release(unsigned worker, std::uint32_t index) { slabs_[worker].released.push_back(index); }

  void end_concurrent() {
    UMBRA_ASSERT(!slabs_.empty());
    for (Slab& slab : slabs_) {
      for (std::uint32_t i = slab.next; i < slab.end; ++i) free_.push_back(i);
      free_.insert(free_.end(), slab.released.begin(), slab.released.end());
    }
    std::vector<Slab>().swap(slabs_);
    lock_.reset();
    high_water_ = tail_;  // the tail never leaves the last block
  }

  /// Releases every group and all memory.
  void clear() {
    std::vector<std::unique_ptr<Group[]>>().swap(blocks_);
    std::vector<std::uint32_t>().swap(free_);
    last_capacity_ = 0;
    high_water_ = 0;
  }

  /// Groups in use (handed out and not released).
  [[nodiscard]] std::size_t size() const { return high_water_ - free_.size(); }

  [[nodiscard]] std::size_t memory_bytes() const {
    std::size_t groups = 0;
    for (std::size_t b = 0; b < blocks_.size(); ++b) groups += block_capacity(b);
    return groups * sizeof(Group) + blocks_.capacity() * sizeof(blocks_[0]) +
           free_.capacity() * sizeof(std::uint32_t);
  }

 private:
  [[nodiscard]] std::uint32_t block_capacity(std::size_t b) const {
    return b + 1 == blocks_.size() ? last_capacity_ : kBlockGroups;
  }

  /// Groups the blocks can hold: every block is full sized but the last.
  [[nodiscard]] std::uint64_t capacity() const {
    return blocks_.empty() ? 0 : (blocks_.size() - 1) * std::uint64_t{kBlockGroups} + last_capacity_;
  }

  /// Room for one more group: a new small block after a full one, else a doubled last block.
  void extend() {
    if (blocks_.empty() || last_capacity_ == kBlockGroups) {
      blocks_.emplace_back(new Group[kFirstBlockGroups]);
      last_capacity_ = kFirstBlockGroups;
    } else {
      grow_last_block();
    }
  }

  void add_full_block_concurrently() {
    // A partial last block was grown for every group the phase may take, so
    // reaching its end means the caller's bound was wrong.
    if (!blocks_.empty() && last_capacity_ != kBlockGroups) {
      throw std::logic_error("umbra: more new groups than reserved for a parallel update");
    }
    if (blocks_.size() == table_limit_) throw std::length_error("umbra: more new groups than reserved for a parallel update");
    const std::uint64_t first = std::uint64_t{blocks_.size()} * kBlockGroups;
    if (first + kBlockGroups > kNoGroup) throw std::length_error("umbra: more than 2^32 - 1 node groups at one depth");
    blocks_.emplace_back(new Group[kBlockGroups]);
    last_capacity_ = kBlockGroups;
    tail_ = static_cast<std::uint32_t>(first);
  }

  void grow_last_block() {
    const std::uint32_t grown = last_capacity_ * 2;
    std::unique_ptr<Group[]> block(new Group[grown]);
    std::copy(blocks_.back().get(), blocks_.back().get() + last_capacity_, block.get());
    blocks_.back() = std::move(block);
    last_capacity_ = grown;
  }

  /// One worker's share of a concurrent phase: the chunk it hands out from.
  /// A cache line each: the workers' slabs lie side by side and are written
  /// on every allocation.
  struct alignas(64) Slab {
    std::uint32_t next = 0;
    std::uint32_t end = 0;
    std::vector<std::uint32_t> released;
  };

  std::vector<std::unique_ptr<Group[]>> blocks_;
  std::uint32_t last_capacity_ = 0;  // groups in the last block
  std::uint32_t high_water_ = 0;     // groups ever handed out
  std::vector<std::uint32_t> free_;  // released groups, reused first
  // Concurrent phase only:
  std::uint32_t tail_ = 0;  // next group no chunk has taken yet (in the last block)
  std::vector<Slab> slabs_;
  std::unique_ptr<std::mutex> lock_;
  std::size_t table_limit_ = 0;
};

}  // namespace umbra
