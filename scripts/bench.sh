#!/usr/bin/env bash
# Benchmarks against liboctomap: an optimised build without internal
# assertions in build-bench/, then one benchmark program:
#   scripts/bench.sh [insert] ARGS...   bench/insert_benchmark.cpp (the default)
#   scripts/bench.sh query ARGS...      bench/query/query_benchmark.cpp
# ARGS go to the program (--help lists them); results: docs/benchmarks.md.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BENCH_BUILD_DIR:-$root/build-bench}"

benchmark=insert
if [[ $# -gt 0 && ( "$1" == insert || "$1" == query ) ]]; then
  benchmark="$1"
  shift
fi
target="umbra_${benchmark}_benchmark"

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=OFF -DUMBRA_BUILD_TESTS=OFF
cmake --build "$build_dir" --target "$target" -j "$(umbra_jobs)"
"$build_dir/bench/$target" --data "$root/../shared/data" "$@"
