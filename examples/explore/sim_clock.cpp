#include "sim_clock.hpp"

#include <pthread.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <thread>

namespace umbra::explore {

namespace {

thread_local SimClock::Actor* t_current = nullptr;

constexpr auto kPoll = std::chrono::microseconds(200);

double seconds_of(clockid_t clock) {
  timespec ts{};
  if (clock_gettime(clock, &ts) != 0) throw std::runtime_error("SimClock: cannot read a thread's CPU clock");
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace

SimClock::SimClock(Mode mode) : mode_(mode), start_(std::chrono::steady_clock::now()) {}

double SimClock::wall_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

SimClock::Actor::Actor(SimClock& clock) : clock_(clock) {
  if (t_current != nullptr) throw std::logic_error("SimClock::Actor: this thread already is an actor");
  if (pthread_getcpuclockid(pthread_self(), &cpu_clock_) != 0) {
    throw std::runtime_error("SimClock::Actor: no CPU clock for this thread");
  }
  base_cpu_ = cpu_seconds();
  const std::lock_guard lock(clock_.mutex_);
  clock_.actors_.push_back(this);
  t_current = this;
}

SimClock::Actor::~Actor() {
  const std::lock_guard lock(clock_.mutex_);
  std::erase(clock_.actors_, this);
  t_current = nullptr;
  clock_.changed_.notify_all();
}

SimClock::Actor* SimClock::Actor::current() { return t_current; }

double SimClock::Actor::cpu_seconds() const { return seconds_of(cpu_clock_); }

double SimClock::Actor::now() const {
  if (clock_.mode_ == Mode::real_time) return clock_.wall_seconds();
  if (state_ == State::working) return base_time_ + (cpu_seconds() - base_cpu_);
  return base_time_;
}

double SimClock::Actor::frontier() const {
  switch (state_) {
    case State::working:
      return base_time_ + (cpu_seconds() - base_cpu_);
    case State::waiting:
      return wait_target_;
    case State::paused:
      return base_time_;
    case State::finished:
      break;
  }
  return std::numeric_limits<double>::infinity();
}

void SimClock::Actor::wait_until(double time) {
  if (clock_.mode_ == Mode::real_time) {
    std::this_thread::sleep_until(clock_.start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                      std::chrono::duration<double>(time)));
    return;
  }
  std::unique_lock lock(clock_.mutex_);
  if (now() >= time) return;
  state_ = State::waiting;
  wait_target_ = time;
  clock_.changed_.notify_all();
  for (;;) {
    double others = std::numeric_limits<double>::infinity();
    for (const Actor* actor : clock_.actors_) {
      if (actor != this) others = std::min(others, actor->frontier());
    }
    if (others >= time) break;
    clock_.changed_.wait_for(lock, kPoll);
  }
  state_ = State::working;
  base_time_ = time;
  base_cpu_ = cpu_seconds();
  clock_.changed_.notify_all();
}

void SimClock::Actor::pause() {
  const std::lock_guard lock(clock_.mutex_);
  if (state_ != State::working) return;
  base_time_ = now();
  state_ = State::paused;
}

void SimClock::Actor::resume() {
  const std::lock_guard lock(clock_.mutex_);
  if (state_ != State::paused) return;
  base_cpu_ = cpu_seconds();
  state_ = State::working;
  clock_.changed_.notify_all();
}

void SimClock::Actor::advance_to(double time) {
  if (clock_.mode_ == Mode::real_time) return;
  const std::lock_guard lock(clock_.mutex_);
  if (state_ == State::working && time > now()) {
    base_time_ = time;
    base_cpu_ = cpu_seconds();
  }
}

void SimClock::Actor::finish() {
  const std::lock_guard lock(clock_.mutex_);
  base_time_ = now();
  state_ = State::finished;
  clock_.changed_.notify_all();
}

void SimMutex::lock() {
  mutex_.lock();
  if (SimClock::Actor* actor = SimClock::Actor::current()) actor->advance_to(released_at_);
}

void SimMutex::unlock() {
  if (const SimClock::Actor* actor = SimClock::Actor::current()) released_at_ = actor->now();
  mutex_.unlock();
}

}  // namespace umbra::explore
