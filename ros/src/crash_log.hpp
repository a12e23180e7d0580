// A last log line when umbra_server dies of a signal (a segmentation fault,
// an abort): what the node was doing then, e.g. "inserting the cloud in
// frame 'lidar' at 12.300000". Exceptions are caught and logged where they
// happen (map_server.cpp); this covers what no catch can: a crash inside a
// library, which would otherwise end the node without a word.
//
// The handler only write()s a message prepared beforehand (async-signal-safe),
// then re-raises the signal with its default action, so the exit status and
// any core dump stay what they would have been.
#pragma once

#include <string>

namespace umbra::ros_io {

/// Installs the handler for SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT.
void install_crash_log();

/// Sets what the node is doing, for the crash line ("" while idle). Call from one thread at a time.
void set_crash_context(const std::string& activity);

}  // namespace umbra::ros_io
