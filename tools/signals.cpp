// The signal handlers of signals.hpp. The handler only calls async-signal-
// safe functions: unlink(2) through umbra::remove_unfinished_saves, then
// signal(2) and raise(3) to die of the same signal.
#include "signals.hpp"

#include <signal.h>
#include <unistd.h>

#include <cstdlib>

#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_file.hpp"

namespace umbra::cli {
namespace {

void on_fatal_signal(int signal_number) {
  umbra::remove_unfinished_saves();
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);  // delivered when the handler returns: the default action ends the process
}

}  // namespace

void remove_unfinished_saves_on_signals() {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(signal_number, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;  // e.g. under nohup
    struct sigaction action {};
    action.sa_handler = on_fatal_signal;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal_number, &action, nullptr);
  }
  // For the tests only (docs/testing.md): every save waits, its temporary file
  // written up to the header, until a signal arrives.
  if (std::getenv("UMBRA_TEST_PAUSE_IN_SAVE") != nullptr) {
    detail::set_map_file_fault_for_testing([] { ::pause(); });
  }
}

}  // namespace umbra::cli
