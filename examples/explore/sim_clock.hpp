// SimClock: simulated time for the exploration study, shared by the threads
// that map and plan, either in real time or as fast as the machine allows.
//
// Each thread that takes part is an Actor. Real time: an actor's time is the
// wall clock since the clock started, and waiting is sleeping. Accelerated:
// idle time is skipped but work is not. An actor's time advances with the CPU
// time its thread spends working (so a planner that computes for 2 s of CPU
// keeps the robot hovering 2 s of simulated time, whatever else the machine
// runs), and an actor that waits until time t goes on only when every other
// actor has reached t: a working actor is at its own time, a waiting one at
// the time it waits for. So the threads keep step in simulated time, run
// truly concurrently, and no thread sees a frame from another's future.
// Time spent blocked on the other actor inside a library cannot be charged
// this way; a lock of one's own can (SimMutex: the taker's time jumps to the
// release time). Bookkeeping that is not part of the simulated system
// (measuring coverage, rendering the sensor's image) runs inside pause() /
// resume() and costs no simulated time.
//
// Cost: an actor's time reads its thread's CPU clock (a system call, about
// 0.3 us); a waiting actor polls the others every 0.2 ms.
#pragma once

#include <chrono>
#include <condition_variable>
#include <ctime>
#include <mutex>
#include <vector>

namespace umbra::explore {

class SimClock {
 public:
  enum class Mode { accelerated, real_time };
  explicit SimClock(Mode mode);
  SimClock(const SimClock&) = delete;
  SimClock& operator=(const SimClock&) = delete;

  [[nodiscard]] Mode mode() const { return mode_; }

  /// One thread's part in the simulation. Made, used and destroyed on that
  /// thread; destroying it (or finish()) stops it holding the others back.
  class Actor {
   public:
    explicit Actor(SimClock& clock);
    ~Actor();
    Actor(const Actor&) = delete;
    Actor& operator=(const Actor&) = delete;

    /// This actor's simulated time, in seconds.
    [[nodiscard]] double now() const;
    /// Returns when this actor's time is at least `time` and every other
    /// actor has reached it; at once if this actor is already past it.
    void wait_until(double time);
    /// Stop and restart charging time (work outside the simulated system).
    void pause();
    void resume();
    /// This actor cannot be earlier than `time` (it waited for someone who
    /// was there): its time jumps forward if it is behind.
    void advance_to(double time);
    /// Leaves the simulation.
    void finish();

    /// The actor of the calling thread, if it has one.
    static Actor* current();

   private:
    friend class SimClock;
    enum class State { working, waiting, paused, finished };
    [[nodiscard]] double cpu_seconds() const;
    /// Time as seen from any thread (caller holds the clock's mutex).
    [[nodiscard]] double frontier() const;

    SimClock& clock_;
    clockid_t cpu_clock_{};
    State state_ = State::working;
    double base_time_ = 0.0;    ///< simulated time when charging (re)started
    double base_cpu_ = 0.0;     ///< thread CPU seconds then
    double wait_target_ = 0.0;  ///< while waiting
  };

 private:
  [[nodiscard]] double wall_seconds() const;

  Mode mode_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Actor*> actors_;
};

/// A mutex for code written as its users write it (a lock between mapping
/// and planning) that keeps simulated time honest: whoever takes it cannot
/// be earlier than whoever last released it. Use with std::lock_guard.
class SimMutex {
 public:
  void lock();
  void unlock();

 private:
  std::mutex mutex_;
  double released_at_ = 0.0;  ///< guarded by mutex_
};

}  // namespace umbra::explore
