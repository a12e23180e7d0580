#!/usr/bin/env bash
# Builds a consumer that embeds umbra with add_subdirectory (see
# subdir_consumer/CMakeLists.txt) and runs it.
# Usage: run_subdir_test.sh SOURCE_DIR
set -euo pipefail
source_dir="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# Debug: the point is that it configures and links, and -O0 compiles twice as fast.
cmake -S "$source_dir/tests/install/subdir_consumer" -B "$work/build" -DCMAKE_BUILD_TYPE=Debug \
  -DUMBRA_SOURCE="$source_dir" >/dev/null
cmake --build "$work/build" -j "$(nproc 2>/dev/null || echo 2)" >/dev/null
"$work/build/consumer" "$work/c.umb"
echo "add_subdirectory test passed"
