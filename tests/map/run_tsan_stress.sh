#!/usr/bin/env bash
# The concurrency checks under ThreadSanitizer (CTest tsan_stress, label
# tsan, in the default suite): the TSan tree is built by scripts/sanitize.sh
# thread, the one way to build it, but only the executables with threads
# (the reader/writer contract, decay steps included, insertion with several threads and the
# parallel apply and color walk, the node pools' concurrent phase, the
# thread pool, the parallel color samples and radix sort, the read gate), and only their
# threaded tests run. Any report fails the run (halt_on_error).
#
#   tests/map/run_tsan_stress.sh SOURCE_DIR BUILD_DIR
#
# Exit codes: 0 clean, 1 a report or a failed test (ctest's 8 is passed on),
# 77 the compiler cannot build with ThreadSanitizer (CTest counts that as
# skipped).
set -euo pipefail
source_dir="$1"
build_dir="$2"
exec "$source_dir/scripts/sanitize.sh" thread --build "$build_dir" \
  --targets "umbra_concurrency_tests umbra_integrate_tests umbra_tree_tests umbra_core_tests" \
  -R '^(Concurrency|Threads|GroupPool|ThreadPool|ColorSamples|RadixSort|ReadGate)\.' --no-tests=error
