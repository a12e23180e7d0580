// A last log line on a fatal signal: see crash_log.hpp.
#include "crash_log.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace umbra::ros_io {
namespace {

constexpr std::size_t kActivityBytes = 512;
char g_activity[kActivityBytes] = {};         // NUL-terminated; written only while g_active is false
std::atomic<bool> g_active{false};

void write_text(const char* text) {
  const std::size_t length = std::strlen(text);
  std::size_t done = 0;
  while (done < length) {
    const ::ssize_t n = ::write(STDERR_FILENO, text + done, length - done);
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

const char* signal_name(int signal) {
  switch (signal) {
    case SIGSEGV: return "SIGSEGV (segmentation fault)";
    case SIGBUS: return "SIGBUS (bus error)";
    case SIGFPE: return "SIGFPE (arithmetic error)";
    case SIGILL: return "SIGILL (illegal instruction)";
    case SIGABRT: return "SIGABRT (abort)";
    default: return "a fatal signal";
  }
}

void on_fatal_signal(int signal) {
  write_text("[FATAL] umbra_server: stopped by ");
  write_text(signal_name(signal));
  if (g_active.load()) {
    write_text(" while ");
    write_text(g_activity);
  }
  write_text("\n");
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

}  // namespace

void install_crash_log() {
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) ::signal(signal, on_fatal_signal);
}

void set_crash_context(const std::string& activity) {
  g_active.store(false);
  if (activity.empty()) return;
  const std::size_t length = std::min(activity.size(), kActivityBytes - 1);
  std::memcpy(g_activity, activity.data(), length);
  g_activity[length] = '\0';
  g_active.store(true);
}

}  // namespace umbra::ros_io
