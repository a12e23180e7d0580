#include "core/read_gate.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace umbra::detail {
namespace {

/// A gate this thread is inside, with how often (nested reads).
struct Held {
  const ReadGate* gate;
  unsigned count;
};

/// What a reading thread keeps: its slot and the gates it is inside. The
/// common case (no more than kInlineHeld maps read at once) lives in one
/// trivially destructible, constant-initialised thread-local, reached with
/// the initial-exec TLS model: one instruction from the thread pointer, no
/// __tls_get_addr call and no initialisation guard (the general-dynamic
/// lookups of a shared library's thread_locals were half the cost of a
/// read; docs/benchmarks.md, "Single queries"). Initial-exec takes a few
/// dozen bytes of the static TLS block, which glibc keeps spare for
/// libraries loaded later (the Python module's dlopen) too.
constexpr unsigned kInlineHeld = 4;
struct ReaderState {
  unsigned slot = 0;       ///< 1 + this thread's slot; 0 until its first read
  unsigned inline_used = 0;
  bool overflowing = false;  ///< t_overflow is in use
  Held held[kInlineHeld] = {};
};
[[gnu::tls_model("initial-exec")]] constinit thread_local ReaderState t_reader;
/// The gates beyond kInlineHeld held at once (rare: many maps read together).
thread_local std::vector<Held> t_overflow;

Held* find_held(ReaderState& reader, const ReadGate* gate) {
  for (unsigned i = 0; i < reader.inline_used; ++i) {
    if (reader.held[i].gate == gate) return &reader.held[i];
  }
  if (reader.overflowing) {
    for (Held& h : t_overflow) {
      if (h.gate == gate) return &h;
    }
  }
  return nullptr;
}

void add_held(ReaderState& reader, const ReadGate* gate) {
  if (reader.inline_used < kInlineHeld) {
    reader.held[reader.inline_used++] = {gate, 1};
    return;
  }
  t_overflow.push_back({gate, 1});
  reader.overflowing = true;
}

void remove_held(ReaderState& reader, Held* held) {
  if (held >= reader.held && held < reader.held + kInlineHeld) {
    *held = reader.held[--reader.inline_used];
  } else {
    *held = t_overflow.back();
    t_overflow.pop_back();
    reader.overflowing = !t_overflow.empty();
  }
}

/// This thread's slot: threads are spread round robin.
unsigned my_slot(ReaderState& reader, unsigned slots) {
  if (reader.slot == 0) {
    static std::atomic<unsigned> next{0};
    reader.slot = next.fetch_add(1, std::memory_order_relaxed) % slots + 1;
  }
  return reader.slot - 1;
}

}  // namespace

void ReadGate::enter() const {
  ReaderState& reader = t_reader;
  if (Held* held = find_held(reader, this)) {
    ++held->count;  // nested: already counted in a slot, never wait
    return;
  }
  std::atomic<std::uint32_t>& readers = slots_[my_slot(reader, kSlots)].readers;
  for (;;) {
    readers.fetch_add(1, std::memory_order_seq_cst);
    if (!closed_.load(std::memory_order_seq_cst)) break;
    readers.fetch_sub(1, std::memory_order_seq_cst);
    closed_.wait(true, std::memory_order_seq_cst);
  }
  add_held(reader, this);
}

void ReadGate::leave() const {
  ReaderState& reader = t_reader;
  Held* held = find_held(reader, this);
  if (held == nullptr) return;  // not inside (a lock released on another thread): nothing to undo here
  if (--held->count > 0) return;
  remove_held(reader, held);
  // Release: the reads made inside happen before the writer, whose wait
  // loads the count, changes anything.
  slots_[my_slot(reader, kSlots)].readers.fetch_sub(1, std::memory_order_release);
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

bool ReadGate::held_by_this_thread() const { return find_held(t_reader, this) != nullptr; }

}  // namespace umbra::detail
