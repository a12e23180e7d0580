// BrickTable: the distance field's bricks by packed brick index, in one
// flat open-addressing table (linear probing, power-of-two capacity, at
// most half full). A query's lookup is one multiply and usually one cache
// line, where std::unordered_map costs a division and a node per lookup
// (the profile of bench/field_benchmark.cpp showed its find() as the
// largest part of a query).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace umbra::detail {

template <typename T>
class BrickTable {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // packed indices use 63 bits

  [[nodiscard]] T* find(std::uint64_t key) const {
    if (slots_.empty()) return nullptr;
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      const Slot& s = slots_[i];
      if (s.key == key) return s.value.get();
      if (s.key == kEmpty) return nullptr;
    }
  }
  [[nodiscard]] bool contains(std::uint64_t key) const { return find(key) != nullptr; }
  /// Asks the CPU to load the key's first slot (batch queries).
  void prefetch(std::uint64_t key) const {
    if (!slots_.empty()) __builtin_prefetch(&slots_[home(key)]);
  }

  void insert_or_assign(std::uint64_t key, std::unique_ptr<T> value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.key == key) {
        s.value = std::move(value);
        return;
      }
      if (s.key == kEmpty) {
        s.key = key;
        s.value = std::move(value);
        ++size_;
        return;
      }
    }
  }

  /// Removes the key if present (backward-shift deletion: no tombstones).
  void erase(std::uint64_t key) {
    if (slots_.empty()) return;
    std::size_t i = home(key);
    while (slots_[i].key != key) {
      if (slots_[i].key == kEmpty) return;
      i = (i + 1) & mask_;
    }
    slots_[i] = Slot{};
    --size_;
    for (std::size_t j = (i + 1) & mask_; slots_[j].key != kEmpty; j = (j + 1) & mask_) {
      const std::size_t h = home(slots_[j].key);
      // Move slot j into the hole at i when its home does not lie in (i, j].
      const bool stays = i <= j ? (h > i && h <= j) : (h > i || h <= j);
      if (!stays) {
        slots_[i] = std::move(slots_[j]);
        slots_[j] = Slot{};
        i = j;
      }
    }
  }

  template <typename Visit>
  void for_each(Visit&& visit) const {
    for (const Slot& s : slots_) {
      if (s.key != kEmpty) visit(s.key, *s.value);
    }
  }
  [[nodiscard]] std::size_t size() const { return size_; }
  /// The table and its values, each `value_bytes` (more than sizeof(T)
  /// where a value's allocation holds more than the T).
  [[nodiscard]] std::size_t memory_bytes(std::size_t value_bytes = sizeof(T)) const {
    return slots_.capacity() * sizeof(Slot) + size_ * value_bytes;
  }
  void clear() { *this = BrickTable(); }
  void swap(BrickTable& other) noexcept {
    slots_.swap(other.slots_);
    std::swap(mask_, other.mask_);
    std::swap(shift_, other.shift_);
    std::swap(size_, other.size_);
  }

 private:
  struct Slot {
    std::uint64_t key = kEmpty;
    std::unique_ptr<T> value;
  };

  [[nodiscard]] std::size_t home(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ULL) >> shift_);  // Fibonacci hashing: the high bits
  }

  void grow() {
    std::vector<Slot> old = std::move(slots_);
    const std::size_t capacity = old.empty() ? 64 : 2 * old.size();
    slots_ = std::vector<Slot>(capacity);
    mask_ = capacity - 1;
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
    for (Slot& s : old) {
      if (s.key != kEmpty) insert_or_assign(s.key, std::move(s.value));
    }
  }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

/// A set of packed brick indices in the same flat layout (an update's
/// candidate bricks: millions of inserts per scan, most of them repeats).
class BrickKeySet {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

  /// Adds the key; true if it was not there.
  bool insert(std::uint64_t key) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      if (slots_[i] == key) return false;
      if (slots_[i] == kEmpty) {
        slots_[i] = key;
        ++size_;
        return true;
      }
    }
  }
  [[nodiscard]] bool contains(std::uint64_t key) const {
    if (slots_.empty()) return false;
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      if (slots_[i] == key) return true;
      if (slots_[i] == kEmpty) return false;
    }
  }
  [[nodiscard]] std::size_t size() const { return size_; }

 private:
  [[nodiscard]] std::size_t home(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ULL) >> shift_);
  }
  void grow() {
    std::vector<std::uint64_t> old = std::move(slots_);
    const std::size_t capacity = old.empty() ? 1024 : 2 * old.size();
    slots_.assign(capacity, kEmpty);
    mask_ = capacity - 1;
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
    for (const std::uint64_t key : old) {
      if (key != kEmpty) insert(key);
    }
  }

  std::vector<std::uint64_t> slots_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

/// A set of bricks within a box of brick indices [lo, hi] (an update's
/// candidates: the bricks within reach of its changes, a few million
/// inserts per scan, most of them repeats): one bit per brick of the box
/// when the box is small enough, else a BrickKeySet. The bitmap turns each
/// repeat into one memory access near the last one.
class BrickMarks {
 public:
  BrickMarks(const std::uint32_t lo[3], const std::uint32_t hi[3]) {
    std::uint64_t volume = 1;
    for (int a = 0; a < 3; ++a) {
      lo_[a] = lo[a];
      size_[a] = std::uint64_t(hi[a]) - lo[a] + 1;
      volume *= size_[a];
    }
    if (volume <= kMostBits) bits_.assign(std::size_t((volume + 63) / 64), 0);
    dense_ = volume <= kMostBits;
  }
  /// Adds the brick (inside the box); true if it was not there.
  bool insert(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint64_t key) {
    if (!dense_) return sparse_.insert(key);
    const std::uint64_t i = index(x, y, z);
    std::uint64_t& word = bits_[std::size_t(i >> 6)];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    if ((word & bit) != 0) return false;
    word |= bit;
    return true;
  }
  [[nodiscard]] bool contains(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint64_t key) const {
    if (!dense_) return sparse_.contains(key);
    const std::uint64_t i = index(x, y, z);
    return (bits_[std::size_t(i >> 6)] >> (i & 63) & 1u) != 0;
  }

 private:
  static constexpr std::uint64_t kMostBits = std::uint64_t{1} << 27;  // 16 MB
  [[nodiscard]] std::uint64_t index(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
    return (std::uint64_t(z - lo_[2]) * size_[1] + (y - lo_[1])) * size_[0] + (x - lo_[0]);
  }
  std::uint32_t lo_[3] = {0, 0, 0};
  std::uint64_t size_[3] = {0, 0, 0};
  bool dense_ = false;
  std::vector<std::uint64_t> bits_;
  BrickKeySet sparse_;
};

}  // namespace umbra::detail
