// ThreadPool (thread_pool.hpp): workers sleep on a condition variable until
// run() publishes a job, take task numbers from an atomic counter, and the
// last one to finish wakes the caller. Cost: one atomic increment per task
// (a lock per task, contended by two workers, was 1.5 us a task: a tenth of
// a TUM frame's parallel apply at 2 cm, whose ~500 tasks take 10 us each);
// run() itself allocates nothing.
#include "core/thread_pool.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <system_error>

#include "umbra/core/job_cpu_times.hpp"
#include "umbra/core/threads.hpp"

namespace umbra {

unsigned hardware_threads() { return ThreadPool::hardware_threads(); }
unsigned max_threads() { return ThreadPool::max_threads(); }

namespace {

/// A hint to the core that this thread is spinning (x86: pause).
inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

std::atomic<bool> g_accounting{false};
std::mutex g_totals_mutex;
JobCpuTimes g_totals;

double thread_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// What one thread_cpu_seconds() costs (a system call: about 1.3 us on the
/// 2-core test machine), measured once.
double clock_seconds() {
  static const double cost = [] {
    constexpr int kReads = 1000;
    const double start = thread_cpu_seconds();
    for (int i = 0; i < kReads; ++i) (void)thread_cpu_seconds();
    return (thread_cpu_seconds() - start) / (kReads + 1);
  }();
  return cost;
}

/// The time `costs` take on `workers` side by side, handed out in order, each
/// to the first worker free (JobCpuTimes::scheduled_seconds).
double list_schedule(const std::vector<double>& costs, unsigned workers) {
  std::vector<double> finish(workers, 0.0);
  for (const double cost : costs) *std::min_element(finish.begin(), finish.end()) += cost;
  return *std::max_element(finish.begin(), finish.end());
}

}  // namespace

void set_job_cpu_accounting(bool on) {
  if (on) (void)clock_seconds();  // measured now, not inside a job
  g_accounting.store(on, std::memory_order_relaxed);
}

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

ThreadPool::ThreadPool(unsigned threads)
    : requested_(threads == 0 ? hardware_threads() : threads), spins_(requested_ <= hardware_threads()) {
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
    stopping_.store(true, std::memory_order_release);
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::run(std::size_t tasks, const std::function<void(std::size_t, unsigned)>& work) {
  if (tasks == 0) return;
  // Job CPU accounting (job_cpu_times.hpp): each worker's CPU time from
  // entering the job to leaving it, so that all of the pool's own work
  // counts as the job's (timed per task only, the clock's cost of ~650
  // tasks a TUM frame at 2 cm, 1.3 ms, counted as serial work); and each
  // task's own time, for the schedule.
  std::vector<WorkerSeconds> per_worker;
  std::vector<double> task_seconds;
  std::function<void(std::size_t, unsigned)> timed;
  const bool accounting = g_accounting.load(std::memory_order_relaxed);
  if (accounting) {
    per_worker.resize(size());
    task_seconds.resize(tasks);
    timed = [&](std::size_t task, unsigned worker) {
      const double start = thread_cpu_seconds();
      work(task, worker);
      task_seconds[task] = std::max(0.0, thread_cpu_seconds() - start - clock_seconds());
    };
  }
  {
    std::lock_guard lock(mutex_);
    job_ = accounting ? &timed : &work;
    job_seconds_ = accounting ? per_worker.data() : nullptr;
    tasks_ = tasks;
    next_task_.store(0, std::memory_order_relaxed);
    failed_.store(false, std::memory_order_relaxed);
    busy_.store(static_cast<unsigned>(workers_.size()), std::memory_order_relaxed);
    failure_ = nullptr;
    // Release: a worker that sees the new generation sees the job above.
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  work_on_job(0);
  (void)spin_until([this] { return busy_.load(std::memory_order_acquire) == 0; });
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return busy_.load(std::memory_order_relaxed) == 0; });
  job_ = nullptr;
  job_seconds_ = nullptr;
  if (accounting) {
    std::lock_guard totals(g_totals_mutex);
    double busiest = 0.0;
    for (const WorkerSeconds& w : per_worker) {
      g_totals.all_seconds += w.seconds;
      busiest = std::max(busiest, w.seconds);
    }
    g_totals.busiest_seconds += busiest;
    g_totals.scheduled_seconds += list_schedule(task_seconds, size());
    ++g_totals.jobs;
  }
  if (failure_) std::rethrow_exception(failure_);
}

void ThreadPool::work_on_job(unsigned worker) {
  WorkerSeconds* const seconds = job_seconds_ == nullptr ? nullptr : job_seconds_ + worker;
  const double start = seconds != nullptr ? thread_cpu_seconds() : 0.0;
  // job_ and tasks_ were published under mutex_ before this worker saw the
  // job's generation (or, for the caller, by itself): plain reads are safe.
  for (;;) {
    if (failed_.load(std::memory_order_relaxed)) break;  // skip the rest after an exception
    const std::size_t task = next_task_.fetch_add(1, std::memory_order_relaxed);
    if (task >= tasks_) break;
    try {
      (*job_)(task, worker);
    } catch (...) {
      std::lock_guard lock(mutex_);
      if (!failure_) failure_ = std::current_exception();
      failed_.store(true, std::memory_order_relaxed);
    }
  }
  if (seconds != nullptr) seconds->seconds = thread_cpu_seconds() - start;
}

template <typename Done>
bool ThreadPool::spin_until(const Done& done) const {
  if (!spins_ || done()) return done();
  // Job CPU accounting: the spin's CPU time, apart from the serial work.
  struct Waiting {
    double start = g_accounting.load(std::memory_order_relaxed) ? thread_cpu_seconds() : -1.0;
    ~Waiting() {
      if (start < 0.0) return;
      const double seconds = thread_cpu_seconds() - start;
      std::lock_guard lock(g_totals_mutex);
      g_totals.waiting_seconds += seconds;
    }
  } waiting;
  using Clock = std::chrono::steady_clock;
  const Clock::time_point stop = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                    std::chrono::duration<double>(kSpinSeconds));
  const Clock::time_point yield_from = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                          std::chrono::duration<double>(kPureSpinSeconds));
  for (;;) {
    // The clock now and then only: a read is a few tens of nanoseconds.
    for (int i = 0; i < 64; ++i) {
      if (done()) return true;
      cpu_relax();
    }
    const Clock::time_point now = Clock::now();
    // Past the first few microseconds, hand the core to any other thread
    // that wants it (on an idle core this returns at once, without a halt).
    if (now >= yield_from) std::this_thread::yield();
    if (now >= stop) return done();
  }
}

void ThreadPool::worker_loop(unsigned worker) {
  std::size_t seen = 0;
  const auto news = [&] {
    return stopping_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen;
  };
  for (;;) {
    if (!spin_until(news)) {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, news);
    }
    if (stopping_.load(std::memory_order_acquire)) return;
    seen = generation_.load(std::memory_order_acquire);
    work_on_job(worker);
    {
      // Under the lock, so that a caller about to sleep on done_ cannot miss it.
      std::lock_guard lock(mutex_);
      busy_.fetch_sub(1, std::memory_order_release);
    }
    done_.notify_one();
  }
}

}  // namespace umbra
