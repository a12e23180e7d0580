// ThreadPool: a fixed set of worker threads that run the tasks of one job.
//
// run(tasks, work) calls work(task, worker) for task = 0 .. tasks-1, spread
// over the workers (the calling thread is worker 0 and takes part), and
// returns when all are done. Tasks are handed out one at a time, in order,
// from an atomic counter, so uneven tasks balance themselves. An exception thrown by
// a task is rethrown from run() (the first one; remaining tasks are skipped).
// One job at a time: run() is not reentrant and not for concurrent callers.
//
// Waiting: a worker that finishes a job, and the caller waiting for the
// workers, spin for up to kSpinSeconds before they sleep on the condition
// variable, when the pool has no more threads than the machine has
// hardware threads. A thread that sleeps gives its core away (to other
// processes, or on the 2-core test machine, a Firecracker VM whose guest
// halt polling is off, to the host) and finds its caches cold when it
// wakes: there, 256 KiB of random reads cost 1.4x the CPU time right after
// a 0.2 ms sleep than after a 0.2 ms spin. A TUM frame at 2 cm runs three
// jobs with serial gaps of 0.1 to 0.3 ms between them, so with sleeping
// waits each worker paid that, and a wake-up, several times a frame. After
// the first kPureSpinSeconds the spinning thread yields its core between
// looks, so that on a loaded machine it does not take the core from the
// thread doing the serial work. With more threads than cores spinning would
// only take the cores from the workers, so they sleep at once.
//
// Threads the system refuses to start (std::thread throws, e.g. under a low
// process limit) are not an error: the pool keeps the workers that did
// start, size() says how many there are with the caller, and started_all()
// is false. The jobs run on those, so a pool never waits for a worker that
// does not exist.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace umbra {

class ThreadPool {
 public:
  /// `threads` workers including the caller (0 means hardware_threads()), or
  /// as many of them as the system lets start.
  explicit ThreadPool(unsigned threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Workers that run jobs, the caller included.
  [[nodiscard]] unsigned size() const { return static_cast<unsigned>(workers_.size()) + 1; }
  /// The number asked for (0 resolved).
  [[nodiscard]] unsigned requested() const { return requested_; }
  [[nodiscard]] bool started_all() const { return size() == requested_; }
  void run(std::size_t tasks, const std::function<void(std::size_t task, unsigned worker)>& work);

  /// hardware_concurrency(), at least 1.
  static unsigned hardware_threads();
  /// The most threads a pool may be asked for: kThreadsPerCore per hardware
  /// thread, at least kMinThreadLimit (more only oversubscribe the cores).
  static unsigned max_threads();
  static constexpr unsigned kThreadsPerCore = 4;
  static constexpr unsigned kMinThreadLimit = 16;
  /// How long a waiting thread spins before it sleeps (the file comment):
  /// longer than the serial gaps between a frame's jobs at 2 cm (0.1 to
  /// 0.3 ms of CPU; at load 11 to 14 on the 2-core machine every wait of the
  /// ten TUM frames ended within 1 ms, while with 0.2 ms nearly all timed
  /// out), short enough to cost little between a camera's frames.
  static constexpr double kSpinSeconds = 1e-3;
  /// The first part of it, in which the waiting thread keeps its core; after
  /// it, the thread yields the core between looks (others may need it: the
  /// caller's serial work on a loaded machine).
  static constexpr double kPureSpinSeconds = 20e-6;

 private:
  void worker_loop(unsigned worker);
  void work_on_job(unsigned worker);
  /// Spins until `done()` or kSpinSeconds passed (at once when the pool
  /// does not spin); whether `done()` came true.
  template <typename Done>
  bool spin_until(const Done& done) const;

  unsigned requested_ = 1;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(std::size_t, unsigned)>* job_ = nullptr;
  /// Job CPU accounting (job_cpu_times.hpp): a worker's CPU time in the current job, a cache line each.
  struct alignas(64) WorkerSeconds {
    double seconds = 0.0;
  };
  WorkerSeconds* job_seconds_ = nullptr;  // one per worker while accounting, else null
  std::size_t tasks_ = 0;
  std::atomic<std::size_t> next_task_{0};  // the next task to hand out (past tasks_: none left)
  std::atomic<bool> failed_{false};        // a task threw: hand out no more
  bool spins_ = false;  // no more threads than hardware threads: wait by spinning first
  // Written under mutex_, also read without it by spinning threads. Each on
  // a cache line of its own: a spinning thread reads it in a loop while the
  // others write next_task_.
  alignas(64) std::atomic<unsigned> busy_{0};  // workers still in the current job
  alignas(64) std::atomic<std::size_t> generation_{0};  // a new job: the caller published it
  std::atomic<bool> stopping_{false};
  std::exception_ptr failure_;
};

/// Runs work(part) for part in [0, parts): on `pool`'s workers when there is
/// a pool (null: one thread) and more than one part, else in order here.
template <typename Work>
void for_each_part(ThreadPool* pool, std::size_t parts, const Work& work) {
  if (pool == nullptr || parts < 2) {
    for (std::size_t p = 0; p < parts; ++p) work(p);
    return;
  }
  pool->run(parts, [&](std::size_t p, unsigned) { work(p); });
}

}  // namespace umbra
