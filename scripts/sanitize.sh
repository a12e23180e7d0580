#!/usr/bin/env bash
# The one way to build and test umbra under a sanitizer: configures a build
# folder of its own, builds, and runs the test suite there (every label but
# fuzz, install, sanitize and tsan), or the part of it asked for.
#
#   scripts/sanitize.sh address|thread [--build DIR] [--targets "T1 T2..."] [ctest arguments...]
#
# address: AddressSanitizer + UndefinedBehaviorSanitizer (-DUMBRA_SANITIZE=ON),
#          Debug, build-asan by default.
# thread:  ThreadSanitizer (-DUMBRA_SANITIZE_THREAD=ON), RelWithDebInfo (the
#          threaded tests are slow enough under TSan), build-tsan by default;
#          UMBRA_TSAN=1 is set for the tests (threads_test.cpp runs fewer
#          thread counts).
# Asserts on. Any sanitizer report stops the test that made it
# (halt_on_error). --targets builds only those targets (ctest arguments then
# usually pick their tests with -R). Exit code: ctest's, or 77 when the
# compiler cannot build and run a program with that sanitizer (CTest counts
# it as skipped). Callers: the CTest tests sanitize_address and
# sanitize_thread (label sanitize, -DUMBRA_SANITIZER_TESTS=ON) and tsan_stress
# (label tsan, tests/map/run_tsan_stress.sh); docs/testing.md.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"

kind="${1:-}"
case "$kind" in
  address) flags=address,undefined; options=(-DUMBRA_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug); build_dir="$root/build-asan" ;;
  thread) flags=thread; options=(-DUMBRA_SANITIZE_THREAD=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo); build_dir="$root/build-tsan" ;;
  *) sed -n '2,20p' "$0"; exit 2 ;;
esac
shift
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --targets) read -r -a targets <<< "$2"; shift 2 ;;
    *) break ;;
  esac
done

cxx="${CXX:-c++}"
probe_dir="$(mktemp -d)"
trap 'rm -rf "$probe_dir"' EXIT
printf '#include <thread>\nint main() { std::thread t([] {}); t.join(); }\n' > "$probe_dir/probe.cpp"
if ! "$cxx" -fsanitize="$flags" -pthread "$probe_dir/probe.cpp" -o "$probe_dir/probe" > "$probe_dir/log" 2>&1 ||
   ! "$probe_dir/probe" >> "$probe_dir/log" 2>&1; then
  echo "SKIPPED: $cxx cannot build or run a program with -fsanitize=$flags:"
  cat "$probe_dir/log"
  exit 77
fi

echo "== $kind sanitizer build in $build_dir"
umbra_configure "$build_dir" "${options[@]}" -DUMBRA_ENABLE_ASSERTS=ON -DUMBRA_BUILD_BENCHMARKS=OFF \
  -DUMBRA_SANITIZER_TESTS=OFF > "$probe_dir/configure.log" 2>&1 || { cat "$probe_dir/configure.log"; exit 1; }
build=(cmake --build "$build_dir" -j "$(umbra_jobs)")
[[ ${#targets[@]} -gt 0 ]] && build+=(--target "${targets[@]}")
"${build[@]}"

export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1${TSAN_OPTIONS:+ $TSAN_OPTIONS}"
[[ "$kind" == thread ]] && export UMBRA_TSAN=1
ctest --test-dir "$build_dir" --output-on-failure -j "$(umbra_jobs)" -LE "fuzz|install|sanitize|tsan" "$@"
