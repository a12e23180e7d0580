// Wait cost benchmark: what a thread pays for sleeping between two pieces of
// work instead of spinning (docs/benchmarks.md, "Threads: round nine").
//
// A thread alternates: pause (sleep, or spin on the clock, for --pause-us),
// then a fixed piece of work (--steps dependent random reads in a working
// set of --kib KiB), timed with the thread's CPU clock. It prints the
// median CPU time of the work after a sleep and after a spin. A sleeping
// thread gives its core away (to other processes, or to the host when the
// core of a virtual machine halts) and may find its caches cold when it
// wakes; a spinning one keeps them. ThreadPool's waits spin first for this
// reason (src/core/thread_pool.hpp). Nothing of umbra is used.
//
// Usage: umbra_wait_cost_benchmark [--kib 256] [--pause-us 200] [--steps 20000] [--rounds 400]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/argument_cursor.hpp"

namespace {

double thread_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

volatile std::uint64_t g_sink = 0;  // keeps the reads from being optimised away

}  // namespace

int main(int argc, char** argv) {
  try {
    std::size_t kib = 256;
    double pause_us = 200.0;
    int steps = 20000;
    int rounds = 400;
    umbra_bench::ArgumentCursor args{argc, argv};
    while (args.next()) {
      const std::string flag = args.flag();
      if (flag == "--kib") kib = std::stoul(args.value());
      else if (flag == "--pause-us") pause_us = std::stod(args.value());
      else if (flag == "--steps") steps = std::stoi(args.value());
      else if (flag == "--rounds") rounds = std::stoi(args.value());
      else throw std::invalid_argument("unknown flag " + flag + " (usage: umbra_wait_cost_benchmark [--kib 256] "
                                       "[--pause-us 200] [--steps 20000] [--rounds 400])");
    }
    if (kib == 0 || steps <= 0 || rounds < 2 || pause_us < 0.0) throw std::invalid_argument("sizes must be positive");
    // A random cycle through the working set: each read depends on the last.
    std::vector<std::uint64_t> next(kib * 1024 / sizeof(std::uint64_t));
    for (std::size_t i = 0; i < next.size(); ++i) next[i] = (i * 2654435761u + 12345u) % next.size();
    using Clock = std::chrono::steady_clock;
    const auto pause = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::micro>(pause_us));
    std::vector<double> after_sleep;
    std::vector<double> after_spin;
    for (int round = 0; round < rounds; ++round) {
      const bool sleep = round % 2 == 0;
      if (sleep) {
        std::this_thread::sleep_for(pause);
      } else {
        const Clock::time_point end = Clock::now() + pause;
        while (Clock::now() < end) {
        }
      }
      const double start = thread_cpu_seconds();
      std::uint64_t at = static_cast<std::uint64_t>(round);
      std::uint64_t sum = 0;
      for (int i = 0; i < steps; ++i) {
        at = next[(at + static_cast<std::uint64_t>(i)) % next.size()];
        sum += at;
      }
      g_sink = sum;
      (sleep ? after_sleep : after_spin).push_back(thread_cpu_seconds() - start);
    }
    const double slept = median(after_sleep);
    const double spun = median(after_spin);
    std::printf("working set %zu KiB, pause %.0f us: the work's CPU time after a sleep %.1f us, after a spin %.1f us "
                "(%.2fx)\n",
                kib, pause_us, 1e6 * slept, 1e6 * spun, slept / spun);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_wait_cost_benchmark: %s\n", e.what());
    return 1;
  }
}
