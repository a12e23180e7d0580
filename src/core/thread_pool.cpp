// ThreadPool (thread_pool.hpp): workers sleep on a condition variable until
// run() publishes a job, take task numbers from a counter under the pool's
// mutex, and the last one to finish wakes the caller. Cost: one lock per
// task; run() itself allocates nothing.
#include "core/thread_pool.hpp"

#include <algorithm>
#include <atomic>
#include <ctime>
#include <system_error>

#include "umbra/core/job_cpu_times.hpp"
#include "umbra/core/threads.hpp"

namespace umbra {

unsigned hardware_threads() { return ThreadPool::hardware_threads(); }
unsigned max_threads() { return ThreadPool::max_threads(); }

namespace {

std::atomic<bool> g_accounting{false};
std::mutex g_totals_mutex;
JobCpuTimes g_totals;

double thread_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

void set_job_cpu_accounting(bool on) { g_accounting.store(on, std::memory_order_relaxed); }

JobCpuTimes job_cpu_times() {
  std::lock_guard lock(g_totals_mutex);
  return g_totals;
}

unsigned ThreadPool::hardware_threads() {
  // Read once: glibc reads it from sysfs on every call (an open, a read and
  // a close), and every insertion asks (InsertOptions::validate).
  static const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

unsigned ThreadPool::max_threads() { return std::max(kMinThreadLimit, kThreadsPerCore * hardware_threads()); }

ThreadPool::ThreadPool(unsigned threads) : requested_(threads == 0 ? hardware_threads() : threads) {
  workers_.reserve(requested_ - 1);
  for (unsigned w = 1; w < requested_; ++w) {
    try {
      workers_.emplace_back([this, w] { worker_loop(w); });
    } catch (const std::system_error&) {
      break;  // the system refused (EAGAIN: a process limit): keep the workers that started
    }
  }
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::run(std::size_t tasks, const std::function<void(std::size_t, unsigned)>& work) {
  if (tasks == 0) return;
  // Job CPU accounting (job_cpu_times.hpp): each task's CPU time added to
  // its worker's (a cache line each); the job's busiest worker is its
  // critical path.
  struct alignas(64) WorkerSeconds {
    double seconds = 0.0;
  };
  std::vector<WorkerSeconds> per_worker;
  std::function<void(std::size_t, unsigned)> timed;
  const bool accounting = g_accounting.load(std::memory_order_relaxed);
  if (accounting) {
    per_worker.resize(size());
    timed = [&](std::size_t task, unsigned worker) {
      const double start = thread_cpu_seconds();
      work(task, worker);
      per_worker[worker].seconds += thread_cpu_seconds() - start;
    };
  }
  {
    std::lock_guard lock(mutex_);
    job_ = accounting ? &timed : &work;
    tasks_ = tasks;
    next_task_ = 0;
    busy_ = static_cast<unsigned>(workers_.size());
    failure_ = nullptr;
    ++generation_;
  }
  wake_.notify_all();
  work_on_job(0);
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return busy_ == 0; });
  job_ = nullptr;
  if (accounting) {
    std::lock_guard totals(g_totals_mutex);
    double busiest = 0.0;
    for (const WorkerSeconds& w : per_worker) {
      g_totals.all_seconds += w.seconds;
      busiest = std::max(busiest, w.seconds);
    }
    g_totals.busiest_seconds += busiest;
    ++g_totals.jobs;
  }
  if (failure_) std::rethrow_exception(failure_);
}

void ThreadPool::work_on_job(unsigned worker) {
  for (;;) {
    std::size_t task;
    {
      std::lock_guard lock(mutex_);
      if (next_task_ >= tasks_ || failure_) return;
      task = next_task_++;
    }
    try {
      (*job_)(task, worker);
    } catch (...) {
      std::lock_guard lock(mutex_);
      if (!failure_) failure_ = std::current_exception();
    }
  }
}

void ThreadPool::worker_loop(unsigned worker) {
  std::size_t seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    work_on_job(worker);
    {
      std::lock_guard lock(mutex_);
      --busy_;
    }
    done_.notify_one();
  }
}

}  // namespace umbra
