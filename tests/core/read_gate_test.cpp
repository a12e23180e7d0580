// Tests of the ReadGate (src/core/read_gate.hpp): nested reads of one gate
// never wait, a thread may read many gates at once (more than the few kept
// in its thread-local list inline, so the overflow list is used too), a
// reader closing a gate it holds is refused, and a writer waits for every
// reader inside, the last-entered one of many gates included. Under
// ThreadSanitizer (label tsan, tests/map/run_tsan_stress.sh) the writer's
// changes and the readers' reads are checked for races as well.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <latch>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/read_gate.hpp"

namespace umbra::detail {
namespace {

TEST(ReadGate, ManyGatesHeldAtOnceAndNestedReadsAreTracked) {
  std::array<ReadGate, 9> gates;  // more than the thread keeps inline
  std::vector<ReadLock> locks;
  for (const ReadGate& gate : gates) {
    EXPECT_FALSE(gate.held_by_this_thread());
    locks.emplace_back(gate);
    locks.emplace_back(gate);  // nested: does not wait
    // ASSERT: a gate this thread holds but does not know of would make close() below wait for ever.
    ASSERT_TRUE(gate.held_by_this_thread());
  }
  for (ReadGate& gate : gates) EXPECT_THROW(gate.close(), std::logic_error);
  // Release one read of each gate: still held (nested), then the other: free.
  for (std::size_t i = 0; i < gates.size(); ++i) {
    locks[2 * i + 1].release();
    EXPECT_TRUE(gates[i].held_by_this_thread()) << "gate " << i;
  }
  // Released in an order other than taken (inline and overflow entries mixed).
  for (std::size_t k = 0; k < gates.size(); ++k) {
    const std::size_t i = (k * 4) % gates.size();
    locks[2 * i].release();
    EXPECT_FALSE(gates[i].held_by_this_thread()) << "gate " << i;
    for (std::size_t j = 0; j < gates.size(); ++j) {
      bool released = false;
      for (std::size_t m = 0; m <= k; ++m) released = released || j == (m * 4) % gates.size();
      EXPECT_EQ(gates[j].held_by_this_thread(), !released) << "gate " << j << " after releasing " << k + 1;
    }
  }
  for (ReadGate& gate : gates) {
    gate.close();  // nobody inside: returns
    gate.open();
  }
}

TEST(ReadGate, AWriterWaitsForTheReaderInsideEvenOfItsLastGate) {
  std::array<ReadGate, 7> gates;
  ReadGate& last = gates.back();  // the reader's overflow entry
  int shared = 0;                 // written by the writer, read by the reader (TSan checks the order)
  std::atomic<bool> reader_done{false};
  std::latch inside(1);
  std::thread reader([&] {
    std::vector<ReadLock> locks;
    for (const ReadGate& gate : gates) locks.emplace_back(gate);
    inside.count_down();
    for (int i = 0; i < 1000; ++i) EXPECT_EQ(shared, 0);  // the writer cannot change it while we are inside
    std::this_thread::yield();
    reader_done.store(true);
  });
  inside.wait();
  last.close();  // returns only once the reader has left
  EXPECT_TRUE(reader_done.load());
  shared = 1;
  last.open();
  reader.join();
  // A new reader sees the write.
  const ReadLock again(last);
  EXPECT_EQ(shared, 1);
}

}  // namespace
}  // namespace umbra::detail
