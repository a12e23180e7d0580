// ProgressBar (progress_bar.hpp).
#include "progress_bar.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace umbra::cli {

std::string time_left_text(double fraction, double elapsed_seconds) {
  // Before a second has passed, or with almost nothing done, the rate says
  // too little to be worth a number.
  if (!(fraction > 0.0) || fraction >= 1.0 || !(elapsed_seconds >= 1.0)) return {};
  const double left = elapsed_seconds * (1.0 - fraction) / fraction;
  const long seconds = std::lround(left);
  char text[64];
  if (seconds < 1) {
    std::snprintf(text, sizeof text, "under 1 s left");
  } else if (seconds < 60) {
    std::snprintf(text, sizeof text, "about %ld s left", seconds);
  } else if (seconds < 3600) {
    std::snprintf(text, sizeof text, "about %ld min %02ld s left", seconds / 60, seconds % 60);
  } else {
    std::snprintf(text, sizeof text, "about %ld h %02ld min left", seconds / 3600, seconds / 60 % 60);
  }
  return text;
}

std::string progress_text(const std::string& label, bool terminal, double fraction, double elapsed_seconds,
                          const std::string& detail) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  const int percent = static_cast<int>(fraction * 100.0);
  const std::string left = time_left_text(fraction, elapsed_seconds);
  char head[64];
  std::string text;
  if (terminal) {
    constexpr int kWidth = 30;
    std::string bar(static_cast<std::size_t>(fraction * kWidth), '#');
    bar.resize(kWidth, '.');
    std::snprintf(head, sizeof head, " %3d%%", percent);
    text = label + " [" + bar + "]" + head;
    if (!detail.empty()) text += " " + detail;
  } else {
    std::snprintf(head, sizeof head, ": %3d%%", percent);
    text = "umbra: " + label + head;
    if (!detail.empty()) text += " " + detail;
    char elapsed[32];
    std::snprintf(elapsed, sizeof elapsed, ", %.1f s so far", elapsed_seconds);
    text += elapsed;
  }
  if (!left.empty()) text += ", " + left;
  return text;
}

ProgressBar::ProgressBar(std::string label) : ProgressBar(std::move(label), ::isatty(2) == 1) {}

ProgressBar::ProgressBar(std::string label, bool terminal)
    : label_(std::move(label)), terminal_(terminal), start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction, const std::string& detail) {
  const auto now = std::chrono::steady_clock::now();
  const auto interval = terminal_ ? std::chrono::steady_clock::duration(std::chrono::milliseconds(100))
                                  : std::chrono::steady_clock::duration(kLogInterval);
  // A terminal shows the full bar at once; a log gets its last line from complete().
  if (drawn_ && now - last_draw_ < interval && (!terminal_ || fraction < 1.0)) return;
  last_draw_ = now;
  drawn_ = true;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const std::string text = progress_text(label_, terminal_, fraction, elapsed, detail);
  if (terminal_) {
    std::fprintf(stderr, "\r%s\033[K", text.c_str());
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
  std::fflush(stderr);
}

void ProgressBar::complete(const std::string& detail) {
  if (!terminal_) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "%s\n", progress_text(label_, false, 1.0, elapsed, detail).c_str());
    std::fflush(stderr);
  }
  finish();
}

void ProgressBar::finish() {
  if (terminal_ && drawn_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  drawn_ = false;
}

}  // namespace umbra::cli
