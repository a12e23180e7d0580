#include "core/thread_pool.hpp"

namespace umbra {

unsigned ThreadPool::hardware_threads() {
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

ThreadPool::ThreadPool(unsigned threads) {
  const unsigned total = threads == 0 ? hardware_threads() : threads;
  workers_.reserve(total - 1);
  for (unsigned w = 1; w < total; ++w) workers_.emplace_back([this, w] { worker_loop(w); });
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
  {
    std::lock_guard lock(mutex_);
    job_ = &work;
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
