#!/usr/bin/env bash
# The concurrency checks under ThreadSanitizer: builds, in a folder of its
# own, the library with -fsanitize=thread and the tests that run threads
# (the reader/writer contract, insertion with several threads and the
# parallel apply, the node pools' concurrent phase), and runs them. Any
# report fails the run (halt_on_error).
#
#   tests/map/run_tsan_stress.sh SOURCE_DIR BUILD_DIR
#
# Exit codes: 0 clean, 1 a report or a failed test, 77 the compiler cannot
# build with ThreadSanitizer (CTest counts that as skipped).
set -euo pipefail
source_dir="$1"
build_dir="$2"
cxx="${CXX:-c++}"

probe_dir="$(mktemp -d)"
trap 'rm -rf "$probe_dir"' EXIT
printf '#include <thread>\nint main() { std::thread t([] {}); t.join(); }\n' > "$probe_dir/probe.cpp"
if ! "$cxx" -fsanitize=thread -pthread "$probe_dir/probe.cpp" -o "$probe_dir/probe" > "$probe_dir/log" 2>&1 ||
   ! "$probe_dir/probe" >> "$probe_dir/log" 2>&1; then
  echo "SKIPPED: $cxx cannot build or run a ThreadSanitizer program:"
  cat "$probe_dir/log"
  exit 77
fi

echo "== building the threaded tests with ThreadSanitizer in $build_dir"
cmake -S "$source_dir" -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DUMBRA_SANITIZE_THREAD=ON \
  -DUMBRA_ENABLE_ASSERTS=ON -DUMBRA_BUILD_BENCHMARKS=OFF -DUMBRA_BUILD_EXAMPLES=OFF > "$build_dir.configure.log" 2>&1 ||
  { cat "$build_dir.configure.log"; exit 1; }
cmake --build "$build_dir" -j "$(nproc 2>/dev/null || echo 2)" \
  --target umbra_concurrency_tests umbra_integrate_tests umbra_tree_tests

export UMBRA_TSAN=1
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 ${TSAN_OPTIONS:-}"
status=0
run() {
  echo "== $*"
  "$@" || status=1
}
run "$build_dir/tests/map/umbra_concurrency_tests"
run "$build_dir/tests/integrate/umbra_integrate_tests" --gtest_filter='Threads.*'
run "$build_dir/tests/tree/umbra_tree_tests" --gtest_filter='GroupPool*'
exit "$status"
