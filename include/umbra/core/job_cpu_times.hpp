// CPU time spent in the jobs of umbra's thread pools, for measuring how much
// of a workload runs in parallel (umbra_insert_benchmark --serial-share).
#pragma once

namespace umbra {

struct JobCpuTimes {
  double all_seconds = 0.0;      ///< every worker's CPU time in jobs, summed
  double busiest_seconds = 0.0;  ///< per job the busiest worker's CPU time, summed over the jobs
  unsigned long long jobs = 0;
};

/// Counts from now on (off by default: the accounting reads the worker's
/// CPU clock twice per task).
void set_job_cpu_accounting(bool on);
/// The totals counted so far (differences give a stretch's share).
JobCpuTimes job_cpu_times();

}  // namespace umbra
