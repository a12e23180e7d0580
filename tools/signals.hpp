// SIGINT, SIGTERM and SIGHUP during a save: the program removes the
// temporary file of the save (umbra::remove_unfinished_saves) and then dies
// of the signal as it would have anyway, so a shell reports 128 + the
// signal's number (130 for Ctrl-C, 143 for SIGTERM) and the target keeps its
// old contents. SIGKILL cannot be caught: the next save to the same target
// removes what it left (umbra/io/file_saving.hpp).
#pragma once

namespace umbra::cli {

/// Installs the handlers (leaving alone a signal the program was started
/// with ignored, as under nohup); call once, first thing in main().
void remove_unfinished_saves_on_signals();

}  // namespace umbra::cli
