// How many threads umbra's parallel work may use: the bounds of every
// `threads` option (InsertOptions::threads, the threads a map file is
// written with).
#pragma once

namespace umbra {

/// The threads such an option of 0 stands for: the hardware's (at least 1).
unsigned hardware_threads();
/// The most such an option may ask for: 4 per hardware thread, at least 16.
unsigned max_threads();

}  // namespace umbra
