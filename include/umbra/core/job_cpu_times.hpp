// CPU time spent in the jobs of umbra's thread pools, for measuring how much
// of a workload runs in parallel (umbra_insert_benchmark --serial-share).
#pragma once

namespace umbra {

struct JobCpuTimes {
  double all_seconds = 0.0;      ///< every worker's CPU time in jobs, summed
  double busiest_seconds = 0.0;  ///< per job the busiest worker's CPU time, summed over the jobs
  /// Per job the time its tasks would take on the pool's workers running
  /// side by side without interruption: the tasks' CPU times handed out in
  /// order, each to the first worker free (as the pool does), the last
  /// worker's finish; summed over the jobs. Unlike busiest_seconds it does
  /// not grow when other processes preempt a worker (the pool then hands
  /// the running worker more tasks).
  double scheduled_seconds = 0.0;
  /// CPU time the pools' threads spent spinning while they waited, for the
  /// next job or for the others to finish a job (ThreadPool::kSpinSeconds
  /// at most a wait): outside the jobs, but no serial work either.
  double waiting_seconds = 0.0;
  unsigned long long jobs = 0;
};

/// Counts from now on (off by default: the accounting reads each worker's
/// CPU clock when it enters a job and when it leaves it, and around each
/// task; a worker's time in a job includes the pool's own work between its
/// tasks, and the clock's own cost, measured once, is taken off each task's
/// time for scheduled_seconds).
void set_job_cpu_accounting(bool on);
/// The totals counted so far (differences give a stretch's share).
JobCpuTimes job_cpu_times();

}  // namespace umbra
