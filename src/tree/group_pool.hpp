// GroupPool: blocked storage for sibling groups, addressed by 32-bit index.
//
// Every node group of one depth lives in one pool. Groups are addressed by a
// uint32 index (half the size of a pointer), stored in blocks of
// kBlockGroups so that growing never moves a group (no reallocation copy, no
// peak of twice the size as with std::vector) and the unused tail is at most
// one block. The first block starts small and doubles until it is full
// sized, so a pool for the few groups near the root costs a few hundred
// bytes, not a whole block; later blocks are full sized from the start. Released groups go to a free list and are handed out again.
//
// Side records: optional records kept one per group beside the groups, in
// blocks parallel to the groups' blocks (SideRecords): grown, copied,
// reserved for a parallel phase and freed with them, so record i belongs to
// group i by construction. There is no second allocation order or free list
// that could drift from the groups' (the OccupancyTree's colors were once a
// pool of their own, allocated in lockstep, which a parallel phase cannot
// keep). A pool has two kinds, the same mechanism used twice:
// - attached records (a node group's colors), chosen at construction
//   (with_attached);
// - marks (a node group's decay mark), switched on later by attach_marks()
//   (a map starts decaying), so a pool whose tree never decays pays nothing
//   for them.
// A kind that is off holds an empty block table and nothing else.
//
// Large pools on huge pages. Once a pool holds kHugePageAfterBytes, its
// new blocks are carved from 2 MiB chunks that the kernel is asked to back
// with a huge page each (madvise; where transparent huge pages are off this
// changes nothing). A millimetre map's pools reach hundreds of MiB, touched
// in random order: with 4 KiB pages, faulting them in and the TLB misses
// cost a fifth of inserting TUM frames at 2 mm. The rest of a chunk a pool
// has not used is at most 2 MiB, an eighth of such a pool.
//
// memory_bytes() is what the pool really allocated (block capacity, whole
// chunks, free list capacity, block tables), never an estimate from a count
// of groups.
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
#include <type_traits>
#include <vector>

#include "core/assert.hpp"

namespace umbra {

inline constexpr std::uint32_t kNoGroup = 0xFFFFFFFFu;

namespace detail {

/// 2 MiB chunks on huge pages where the kernel gives them (GroupPool's file
/// comment); blocks are carved from the last chunk and live as long as it.
class HugePageChunks {
 public:
  static constexpr std::size_t kChunkBytes = std::size_t{2} << 20;

  /// `bytes` (at most kChunkBytes), aligned to 64, from the last chunk or a new one.
  void* carve(std::size_t bytes);
  [[nodiscard]] std::size_t memory_bytes() const { return chunks_.size() * kChunkBytes; }
  void clear() {
    chunks_.clear();
    used_ = kChunkBytes;
  }

 private:
  struct Free {
    void operator()(void* chunk) const;
  };
  std::vector<std::unique_ptr<void, Free>> chunks_;
  std::size_t used_ = kChunkBytes;  // bytes carved from the last chunk
};

/// Asks the kernel to back the whole pages inside [memory, memory + bytes)
/// now, in one call (MADV_POPULATE_WRITE, Linux 5.14; elsewhere nothing
/// happens). A full block is filled group by group as the map grows: on the
/// test machine (a virtual machine) the first write to a page cost 16 us
/// through a page fault and 10 us populated, and a fresh map's page faults
/// were a tenth of inserting ten TUM frames at 2 cm.
void populate(void* memory, std::size_t bytes);

/// Deletes a block allocated with new[]; leaves one carved from a chunk.
template <typename T>
struct BlockDeleter {
  bool owned = true;
  void operator()(T* block) const {
    if (owned) delete[] block;
  }
};

}  // namespace detail

/// The Attached type of a pool whose groups carry nothing else.
struct NoAttachment {};

template <typename Group, typename Attached = NoAttachment, typename Mark = NoAttachment>
class GroupPool {
 public:
  static constexpr std::uint32_t kBlockBits = 10;
  // 1024 groups per block: at most 68 KiB, below glibc's 128 KiB mmap threshold,
  // so a block costs malloc 16 bytes of header instead of a page of rounding.
  static constexpr std::uint32_t kBlockGroups = 1u << kBlockBits;
  static constexpr std::uint32_t kFirstBlockGroups = 8;
  /// From this size on, new blocks come from huge-page chunks (file comment).
  static constexpr std::size_t kHugePageAfterBytes = std::size_t{16} << 20;
  // Carved blocks are never destroyed, only their chunk freed.
  static_assert(std::is_trivially_destructible_v<Group> && std::is_trivially_destructible_v<Attached> &&
                std::is_trivially_destructible_v<Mark>);

  GroupPool() = default;
  /// with_attached: keep an Attached record per group (see the file comment).
  explicit GroupPool(bool with_attached) { attached_.on = with_attached; }
  GroupPool(GroupPool&&) noexcept = default;
  GroupPool& operator=(GroupPool&&) noexcept = default;
  GroupPool(const GroupPool& other) { *this = other; }
  GroupPool& operator=(const GroupPool& other) {
    if (this == &other) return *this;
    UMBRA_ASSERT(other.slabs_.empty());
    blocks_.clear();
    attached_.blocks.clear();
    marks_.blocks.clear();
    chunks_.clear();
    block_bytes_ = 0;
    copy_blocks(other.blocks_, other, blocks_);
    copy_side(other.attached_, other, attached_);
    copy_side(other.marks_, other, marks_);
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
  /// The record attached to group `index` (only for a pool with_attached).
  Attached& attached(std::uint32_t index) { return side_record(attached_, index); }
  const Attached& attached(std::uint32_t index) const { return side_record(attached_, index); }
  [[nodiscard]] bool has_attached() const { return attached_.on; }

  /// The mark of group `index` (only once attach_marks() was called).
  Mark& mark(std::uint32_t index) { return side_record(marks_, index); }
  const Mark& mark(std::uint32_t index) const { return side_record(marks_, index); }
  [[nodiscard]] bool has_marks() const { return marks_.on; }
  /// From now on every group has a mark: `initial` for each one there is
  /// (in use or free), unspecified for the groups allocated later (the
  /// caller fills them, as it fills the groups). Nothing when it has them.
  void attach_marks(const Mark& initial) {
    UMBRA_ASSERT(slabs_.empty());
    if (marks_.on) return;
    std::vector<Block<Mark>> marks;
    marks.reserve(blocks_.size());
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      marks.push_back(new_block<Mark>(block_capacity(b), false));
      std::fill_n(marks.back().get(), block_capacity(b), initial);
    }
    marks_.blocks = std::move(marks);
    marks_.on = true;
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
    const std::size_t table = blocks_.size() + max_new_groups / kBlockGroups + workers + 1;
    blocks_.reserve(table);
    table_limit_ = blocks_.capacity();
    for_each_side([&](auto& side) {
      if (!side.on) return;
      side.blocks.reserve(table);
      table_limit_ = std::min(table_limit_, side.blocks.capacity());
    });
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

  /// Releases every group but keeps the memory, for a pool refilled over and
  /// over (an update batch per scan: freeing and touching its blocks anew
  /// each time cost a page fault per 4 KiB, 10% of a TUM frame at 2 mm).
  void recycle() {
    UMBRA_ASSERT(slabs_.empty());
    free_.clear();
    high_water_ = 0;
  }

  /// Releases every group and all memory.
  void clear() {
    std::vector<Block<Group>>().swap(blocks_);
    for_each_side([](auto& side) { decltype(side.blocks)().swap(side.blocks); });  // `on` stays: new blocks get records
    chunks_.clear();
    block_bytes_ = 0;
    std::vector<std::uint32_t>().swap(free_);
    last_capacity_ = 0;
    high_water_ = 0;
  }

  /// Groups in use (handed out and not released).
  [[nodiscard]] std::size_t size() const { return high_water_ - free_.size(); }

  /// Of memory_bytes(), the huge-page chunks'.
  [[nodiscard]] std::size_t huge_page_bytes() const { return chunks_.memory_bytes(); }

  [[nodiscard]] std::size_t memory_bytes() const {
    std::size_t tables = blocks_.capacity() * sizeof(blocks_[0]);
    for_each_side([&](const auto& side) { tables += side.blocks.capacity() * sizeof(side.blocks[0]); });
    return block_bytes_ + chunks_.memory_bytes() + tables + free_.capacity() * sizeof(std::uint32_t);
  }

 private:
  [[nodiscard]] std::uint32_t block_capacity(std::size_t b) const {
    return b + 1 == blocks_.size() ? last_capacity_ : kBlockGroups;
  }

  /// Groups the blocks can hold: every block is full sized but the last.
  [[nodiscard]] std::uint64_t capacity() const {
    return blocks_.empty() ? 0 : (blocks_.size() - 1) * std::uint64_t{kBlockGroups} + last_capacity_;
  }

  /// Room for one more group: a small first block, doubled until full
  /// sized, then full-sized blocks. (Starting every block small copied each
  /// group once more while it grew: 7% of inserting TUM frames at 2 mm.)
  void extend() {
    if (blocks_.empty()) {
      add_block(kFirstBlockGroups);
    } else if (last_capacity_ == kBlockGroups) {
      add_block(kBlockGroups);
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
    add_block(kBlockGroups);
    tail_ = static_cast<std::uint32_t>(first);
  }

  template <typename T>
  using Block = std::unique_ptr<T[], detail::BlockDeleter<T>>;

  /// A block of `capacity` records: from a huge-page chunk when `carved`.
  template <typename T>
  Block<T> new_block(std::uint32_t capacity, bool carved) {
    const std::size_t bytes = std::size_t{capacity} * sizeof(T);
    if (!carved) {
      Block<T> block(new T[capacity]);
      block_bytes_ += bytes;
      if (capacity == kBlockGroups) detail::populate(block.get(), bytes);  // full blocks fill up (the last one per pool aside)
      return block;
    }
    T* records = static_cast<T*>(chunks_.carve(bytes));
    std::uninitialized_default_construct_n(records, capacity);
    return Block<T>(records, detail::BlockDeleter<T>{false});
  }

  // All blocks are allocated and the tables reserved before any table
  // changes, so running out of memory leaves the groups, their attached
  // records and their marks in step.
  void add_block(std::uint32_t capacity) {
    const bool carved = capacity == kBlockGroups && block_bytes_ + chunks_.memory_bytes() >= kHugePageAfterBytes;
    Block<Group> groups = new_block<Group>(capacity, carved);
    Block<Attached> attached = new_side_block(attached_, capacity, carved);
    Block<Mark> marks = new_side_block(marks_, capacity, carved);
    reserve_one_more(blocks_);
    for_each_side([](auto& side) {
      if (side.on) reserve_one_more(side.blocks);
    });
    blocks_.push_back(std::move(groups));
    attached_.add(std::move(attached));
    marks_.add(std::move(marks));
    last_capacity_ = capacity;
  }

  /// Room for one more entry, doubling as push_back would (memory_bytes() counts the tables).
  template <typename T>
  static void reserve_one_more(std::vector<T>& table) {
    if (table.size() == table.capacity()) table.reserve(table.empty() ? 1 : table.size() * 2);
  }

  // Only the first block grows (extend), and it comes from new[].
  void grow_last_block() {
    const std::uint32_t grown = last_capacity_ * 2;
    Block<Group> groups = grown_copy(blocks_.back(), last_capacity_, grown);
    Block<Attached> attached = grown_side_block(attached_, grown);
    Block<Mark> marks = grown_side_block(marks_, grown);
    attached_.replace_last(std::move(attached));
    marks_.replace_last(std::move(marks));
    blocks_.back() = std::move(groups);
    last_capacity_ = grown;
  }

  template <typename T>
  Block<T> grown_copy(const Block<T>& block, std::uint32_t capacity, std::uint32_t grown) {
    UMBRA_ASSERT(block.get_deleter().owned);
    Block<T> bigger = new_block<T>(grown, false);
    std::copy(block.get(), block.get() + capacity, bigger.get());
    block_bytes_ -= std::size_t{capacity} * sizeof(T);  // `block` is freed by the caller's assignment
    return bigger;
  }

  /// Copies `from` (blocks of `other`, shaped as its group blocks) into `to`, all from new[].
  template <typename T>
  void copy_blocks(const std::vector<Block<T>>& from, const GroupPool& other, std::vector<Block<T>>& to) {
    to.clear();
    to.reserve(from.size());
    for (std::size_t b = 0; b < from.size(); ++b) {
      const std::uint32_t capacity = other.block_capacity(b);
      to.push_back(new_block<T>(capacity, false));
      std::copy(from[b].get(), from[b].get() + capacity, to.back().get());
    }
  }

  /// One kind of side record (the file comment): while `on`, one block of
  /// records per block of groups, of the same capacity.
  template <typename T>
  struct SideRecords {
    bool on = false;
    std::vector<Block<T>> blocks;  // parallel to blocks_ while on, else empty

    void add(Block<T> block) {
      if (on) blocks.push_back(std::move(block));
    }
    void replace_last(Block<T> block) {
      if (on) blocks.back() = std::move(block);
    }
  };

  /// The record of group `index` in `side` (the public accessors make it const where the pool is).
  template <typename T>
  T& side_record(const SideRecords<T>& side, std::uint32_t index) const {
    // Only the block pointer is read, as in operator[].
    UMBRA_ASSERT(side.on && (!slabs_.empty() || (index < high_water_ && index >> kBlockBits < side.blocks.size())));
    return side.blocks.data()[index >> kBlockBits][index & (kBlockGroups - 1)];
  }

  /// `f` on each kind of side record, the attached ones then the marks.
  template <typename F>
  void for_each_side(F&& f) {
    f(attached_);
    f(marks_);
  }
  template <typename F>
  void for_each_side(F&& f) const {
    f(attached_);
    f(marks_);
  }

  /// A new block of `side`'s records for a new block of groups (none while it is off).
  template <typename T>
  Block<T> new_side_block(const SideRecords<T>& side, std::uint32_t capacity, bool carved) {
    return side.on ? new_block<T>(capacity, carved) : Block<T>();
  }
  /// The last block of `side` grown with the groups' (none while it is off).
  template <typename T>
  Block<T> grown_side_block(const SideRecords<T>& side, std::uint32_t grown) {
    return side.on ? grown_copy(side.blocks.back(), last_capacity_, grown) : Block<T>();
  }
  /// `from` (a side of `other`) copied into `to`.
  template <typename T>
  void copy_side(const SideRecords<T>& from, const GroupPool& other, SideRecords<T>& to) {
    to.on = from.on;
    copy_blocks(from.blocks, other, to.blocks);
  }

  /// One worker's share of a concurrent phase: the chunk it hands out from.
  /// A cache line each: the workers' slabs lie side by side and are written
  /// on every allocation.
  struct alignas(64) Slab {
    std::uint32_t next = 0;
    std::uint32_t end = 0;
    std::vector<std::uint32_t> released;
  };

  std::vector<Block<Group>> blocks_;
  SideRecords<Attached> attached_;  // colors, chosen at construction
  SideRecords<Mark> marks_;         // decay marks, from attach_marks() on
  detail::HugePageChunks chunks_;  // holds the carved blocks (their deleters never touch it)
  std::size_t block_bytes_ = 0;    // bytes of the blocks from new[]
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
