#!/usr/bin/env bash
# Configures a parent project that embeds umbra with add_subdirectory and
# sets neither a build type nor BUILD_SHARED_LIBS (parent_settings/), which
# fails when umbra sets either for it.
# Usage: run_parent_settings_test.sh SOURCE_DIR
set -euo pipefail
source_dir="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake -S "$source_dir/tests/install/parent_settings" -B "$work/build" -DUMBRA_SOURCE="$source_dir" >"$work/log" 2>&1 || {
  cat "$work/log"
  exit 1
}
echo "parent settings test passed"
