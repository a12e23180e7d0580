// ReadGate: many readers, one writer's short exclusive phases.
//
// The concurrency contract of OccupancyMap (see its header): while one thread
// inserts, any number of threads query; each query sees the map after some
// whole scan. Inserting a scan is tracing (reads the tree: most of the time)
// then applying (writes it). Only applying, and the operations that
// restructure the map, close the gate; readers wait at most that long.
//
// Why not std::shared_mutex: glibc's rwlock prefers readers, so two threads
// querying back to back can starve the writer for ever; and every reader
// would increment one shared counter, a cache line bouncing between cores on
// every query. Here each reader increments the counter of its own slot (a
// cache line per slot, threads spread round robin) and then checks the
// gate; the writer closes the gate and then waits until every slot is zero.
// Both sides use sequentially consistent operations, so either the reader
// sees the gate closed (and backs off) or the writer sees the reader's count
// (and waits). Measured in docs/benchmarks.md ("Readers during insertion").
//
// Nesting: a thread that already holds the gate (a query range is open)
// enters again without waiting, so nested queries cannot deadlock against a
// waiting writer. A thread that holds the gate and tries to close it gets
// std::logic_error instead of a deadlock.
//
// Cost of a read: the increment and decrement of the slot (two locked
// instructions); the thread's own bookkeeping is a thread-local reached
// without a call (read_gate.cpp says why and how).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace umbra::detail {

class ReadGate {
 public:
  ReadGate() = default;
  ReadGate(const ReadGate&) = delete;
  ReadGate& operator=(const ReadGate&) = delete;

  /// Blocks while the gate is closed (at most one exclusive phase).
  void enter() const;
  void leave() const;
  /// Closes the gate and waits for the readers inside to leave. Throws
  /// std::logic_error when the calling thread itself is inside.
  void close();
  void open();
  /// The calling thread is inside (holds a read).
  [[nodiscard]] bool held_by_this_thread() const;

 private:
  static constexpr unsigned kSlots = 16;
  struct alignas(64) Slot {
    std::atomic<std::uint32_t> readers{0};
  };
  mutable std::array<Slot, kSlots> slots_{};
  alignas(64) std::atomic<bool> closed_{false};
};

/// Holds a read of a gate for its lifetime. Movable; it must be destroyed on
/// the thread that made it.
class ReadLock {
 public:
  ReadLock() = default;
  explicit ReadLock(const ReadGate& gate) : gate_(&gate) { gate.enter(); }
  ~ReadLock() { release(); }
  ReadLock(ReadLock&& other) noexcept : gate_(other.gate_) { other.gate_ = nullptr; }
  ReadLock& operator=(ReadLock&& other) noexcept {
    if (this != &other) {
      release();
      gate_ = other.gate_;
      other.gate_ = nullptr;
    }
    return *this;
  }
  ReadLock(const ReadLock&) = delete;
  ReadLock& operator=(const ReadLock&) = delete;
  void release() {
    if (gate_ != nullptr) gate_->leave();
    gate_ = nullptr;
  }

 private:
  const ReadGate* gate_ = nullptr;
};

/// Keeps the gate closed for its lifetime (an exclusive phase).
class ClosedGate {
 public:
  explicit ClosedGate(ReadGate& gate) : gate_(gate) { gate_.close(); }
  ~ClosedGate() { gate_.open(); }
  ClosedGate(const ClosedGate&) = delete;
  ClosedGate& operator=(const ClosedGate&) = delete;

 private:
  ReadGate& gate_;
};

}  // namespace umbra::detail
