// ProgressBar: how far a long command is, on stderr.
//
// On a terminal: one line redrawn in place (at most ~10 times a second)
// with a bar, the per cent done, a detail and, once a second has passed,
// the time left estimated from the rate so far. Anywhere else (a log file,
// a pipe, a CI job): one plain line for the first update and then at most
// one every kLogInterval, each flushed, so a log shows the work going on
// instead of staying silent until the end; stdout stays clean either way.
#pragma once

#include <chrono>
#include <string>

namespace umbra::cli {

/// How often a non-terminal gets a progress line: often enough that a
/// watcher sees the work go on, rarely enough that a run of thousands of
/// small scans does not flood its log.
inline constexpr std::chrono::seconds kLogInterval{2};

/// "about 1 min 05 s left" from the fraction done and the seconds so far;
/// empty when nothing can be said yet (under 1 s, or nothing done).
std::string time_left_text(double fraction, double elapsed_seconds);

/// The text of one update, without the line's start or end: on a terminal
/// "LABEL [####......]  40% DETAIL, about 12 s left"; in a log
/// "umbra: LABEL:  40% DETAIL, 8.1 s so far, about 12 s left".
std::string progress_text(const std::string& label, bool terminal, double fraction, double elapsed_seconds,
                          const std::string& detail);

class ProgressBar {
 public:
  /// `terminal`: whether stderr is a terminal (isatty) unless told.
  explicit ProgressBar(std::string label);
  ProgressBar(std::string label, bool terminal);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// fraction in [0, 1]; `detail` is shown after the per cent.
  void update(double fraction, const std::string& detail = {});
  /// The work is done: a log gets a last line (100%, `detail` and the time
  /// taken), a terminal's line is cleared.
  void complete(const std::string& detail = {});
  /// Clears the terminal's line (also done by the destructor).
  void finish();

 private:
  std::string label_;
  bool terminal_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace umbra::cli
