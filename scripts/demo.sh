#!/usr/bin/env bash
# Quick start, step 1: install what is missing, build the `umbra` program,
# run its demo. Output goes to ./demo-output (or $UMBRA_DEMO_OUTPUT).
# Idempotent; a second run only re-runs the demo.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BUILD_DIR:-$root/build}"
output="${UMBRA_DEMO_OUTPUT:-$root/demo-output}"

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=ON
cmake --build "$build_dir" --target umbra_cli -j "$(umbra_jobs)"
"$build_dir/tools/umbra" demo -o "$output"
