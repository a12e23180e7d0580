#!/usr/bin/env bash
# Benchmarks against liboctomap: an optimised build without internal
# assertions in build-bench/, then the insertion benchmark. Arguments go to
# the benchmark (see bench/insert_benchmark.cpp); results: docs/benchmarks.md.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BENCH_BUILD_DIR:-$root/build-bench}"

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=OFF -DUMBRA_BUILD_TESTS=OFF
cmake --build "$build_dir" --target umbra_insert_benchmark -j "$(umbra_jobs)"
"$build_dir/bench/umbra_insert_benchmark" --data "$root/../shared/data" "$@"
