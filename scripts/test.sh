#!/usr/bin/env bash
# Quick start, step 2: install what is missing, build everything (library,
# program, examples, benchmarks, tests) and run the whole test suite.
# Idempotent; a second run rebuilds only what changed.
# Extra arguments go to ctest, e.g. ./scripts/test.sh -R Oracle
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BUILD_DIR:-$root/build}"

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=ON
cmake --build "$build_dir" -j "$(umbra_jobs)"
ctest --test-dir "$build_dir" --output-on-failure -j "$(umbra_jobs)" "$@"
