// ThreadPool: a fixed set of worker threads that run the tasks of one job.
//
// run(tasks, work) calls work(task, worker) for task = 0 .. tasks-1, spread
// over the workers (the calling thread is worker 0 and takes part), and
// returns when all are done. Tasks are handed out one at a time, in order,
// from an atomic counter, so uneven tasks balance themselves. An exception thrown by
// a task is rethrown from run() (the first one; remaining tasks are skipped).
// One job at a time: run() is not reentrant and not for concurrent callers.
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

 private:
  void worker_loop(unsigned worker);
  void work_on_job(unsigned worker);

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
  unsigned busy_ = 0;  // workers still in the current job
  std::size_t generation_ = 0;
  bool stopping_ = false;
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
