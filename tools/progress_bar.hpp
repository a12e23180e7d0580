// ProgressBar: a one-line bar on stderr, drawn only when stderr is a terminal
// (so logs and pipes stay clean). Redraws at most ~10 times a second.
#pragma once

#include <chrono>
#include <string>

namespace umbra::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// fraction in [0, 1]; `detail` is shown after the bar.
  void update(double fraction, const std::string& detail = {});
  /// Clears the line (also done by the destructor).
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace umbra::cli
