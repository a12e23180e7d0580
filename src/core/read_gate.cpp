#include "core/read_gate.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace umbra::detail {
namespace {

/// The gates this thread is inside, with how often (nested reads).
struct Held {
  const ReadGate* gate;
  unsigned count;
};
thread_local std::vector<Held> t_held;

Held* find_held(const ReadGate* gate) {
  for (Held& h : t_held) {
    if (h.gate == gate) return &h;
  }
  return nullptr;
}

/// This thread's slot: threads are spread round robin.
unsigned my_slot(unsigned slots) {
  static std::atomic<unsigned> next{0};
  thread_local const unsigned slot = next.fetch_add(1, std::memory_order_relaxed);
  return slot % slots;
}

}  // namespace

void ReadGate::enter() const {
  if (Held* held = find_held(this)) {
    ++held->count;  // nested: already counted in a slot, never wait
    return;
  }
  std::atomic<std::uint32_t>& readers = slots_[my_slot(kSlots)].readers;
  for (;;) {
    readers.fetch_add(1, std::memory_order_seq_cst);
    if (!closed_.load(std::memory_order_seq_cst)) break;
    readers.fetch_sub(1, std::memory_order_seq_cst);
    closed_.wait(true, std::memory_order_seq_cst);
  }
  t_held.push_back({this, 1});
}

void ReadGate::leave() const {
  Held* held = find_held(this);
  if (held == nullptr) return;  // not inside (a lock released on another thread): nothing to undo here
  if (--held->count > 0) return;
  *held = t_held.back();
  t_held.pop_back();
  slots_[my_slot(kSlots)].readers.fetch_sub(1, std::memory_order_seq_cst);
}

void ReadGate::close() {
  if (held_by_this_thread()) {
    throw std::logic_error(
        "umbra: this thread is reading the map (a query range is still open) and tries to change it; "
        "finish or destroy the range first");
  }
  closed_.store(true, std::memory_order_seq_cst);
  // Readers inside finish one query or one iteration: spin briefly, then
  // back off with growing sleeps so that a long iteration costs no core.
  for (Slot& slot : slots_) {
    auto pause = std::chrono::microseconds(1);
    for (int spins = 0; slot.readers.load(std::memory_order_seq_cst) != 0; ++spins) {
      if (spins < 64) {
        std::this_thread::yield();
      } else {
        std::this_thread::sleep_for(pause);
        pause = std::min(pause * 2, std::chrono::microseconds(1000));
      }
    }
  }
}

void ReadGate::open() {
  closed_.store(false, std::memory_order_seq_cst);
  closed_.notify_all();
}

bool ReadGate::held_by_this_thread() const { return find_held(this) != nullptr; }

}  // namespace umbra::detail
