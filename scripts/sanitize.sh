#!/usr/bin/env bash
# Builds umbra with a sanitizer, in a build folder of its own, and runs the
# whole test suite there (every label but fuzz, install and sanitize).
#
#   scripts/sanitize.sh address|thread [BUILD_DIR] [ctest arguments...]
#
# address: AddressSanitizer + UndefinedBehaviorSanitizer (-DUMBRA_SANITIZE=ON),
#          build-asan by default; thread: ThreadSanitizer
#          (-DUMBRA_SANITIZE_THREAD=ON), build-tsan by default. Debug build,
#          asserts on. A UBSan report stops the test that made it
#          (halt_on_error), like an ASan or TSan report does. Exit code: ctest's.
# The CTest tests sanitize_address and sanitize_thread (label sanitize) run
# this script; they exist when the main build is configured with
# -DUMBRA_SANITIZER_TESTS=ON (docs/testing.md).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"

kind="${1:-}"
case "$kind" in
  address) option=-DUMBRA_SANITIZE=ON; default_dir="$root/build-asan" ;;
  thread) option=-DUMBRA_SANITIZE_THREAD=ON; default_dir="$root/build-tsan" ;;
  *) sed -n '2,16p' "$0"; exit 2 ;;
esac
shift
build_dir="${1:-$default_dir}"
[[ $# -gt 0 ]] && shift

umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Debug -DUMBRA_ENABLE_ASSERTS=ON "$option" \
  -DUMBRA_BUILD_BENCHMARKS=OFF -DUMBRA_SANITIZER_TESTS=OFF
cmake --build "$build_dir" -j "$(umbra_jobs)"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export TSAN_OPTIONS="halt_on_error=1${TSAN_OPTIONS:+:$TSAN_OPTIONS}"
ctest --test-dir "$build_dir" --output-on-failure -j "$(umbra_jobs)" -LE "fuzz|install|sanitize" "$@"
