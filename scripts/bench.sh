#!/usr/bin/env bash
# Benchmarks against liboctomap: an optimised build without internal
# assertions in build-bench/, then one benchmark program:
#   scripts/bench.sh [insert] ARGS...   bench/insert_benchmark.cpp (the default)
#   scripts/bench.sh query ARGS...      bench/query/query_benchmark.cpp
#   scripts/bench.sh concurrency ARGS...  bench/concurrency_benchmark.cpp
#                                       (readers during insertion)
#   scripts/bench.sh python ARGS...     bench/python_batch_benchmark.py (the
#                                       Python module against C++, same map)
#   scripts/bench.sh build ARGS...      bench/build_benchmark.cpp (the whole
#                                       `umbra build` process, reading and
#                                       writing included, against OctoMap)
#   scripts/bench.sh navigation ARGS... bench/navigation_grid_benchmark.cpp
#                                       (the 2D navigation grid)
#   scripts/bench.sh field ARGS...      bench/field_benchmark.cpp (the
#                                       distance field against dynamicEDT3D)
#   scripts/bench.sh merge ARGS...      bench/merge_benchmark.cpp (merging
#                                       maps against inserting and OctoMap)
#   scripts/bench.sh decay ARGS...      bench/decay_benchmark.cpp (decay
#                                       toward unknown against insertion and
#                                       an OctoMap leaf loop)
# ARGS go to the program (--help lists them); results: docs/benchmarks.md.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BENCH_BUILD_DIR:-$root/build-bench}"

benchmark=insert
if [[ $# -gt 0 && ( "$1" == insert || "$1" == query || "$1" == concurrency || "$1" == python || "$1" == build || "$1" == navigation || "$1" == field || "$1" == merge || "$1" == decay ) ]]; then
  benchmark="$1"
  shift
fi
target="umbra_${benchmark}_benchmark"

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=OFF -DUMBRA_BUILD_TESTS=OFF
if [[ "$benchmark" == python ]]; then
  target=umbra_python_batch_benchmark
  cmake --build "$build_dir" --target "$target" umbra_python -j "$(umbra_jobs)"
  # The interpreter the module was built for (python/CMakeLists.txt picks one with numpy).
  python="$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' "$build_dir/CMakeCache.txt")"
  PYTHONPATH="$build_dir/python" "${python:-python3}" "$root/bench/python_batch_benchmark.py" \
    --cpp "$build_dir/bench/$target" --data "$root/../shared/data" "$@"
  exit
fi
if [[ "$benchmark" == build ]]; then
  # It runs the umbra program itself, as a user would.
  cmake --build "$build_dir" --target "$target" umbra_cli -j "$(umbra_jobs)"
  "$build_dir/bench/$target" --umbra "$build_dir/tools/umbra" --data "$root/../shared/data" "$@"
  exit
fi
cmake --build "$build_dir" --target "$target" -j "$(umbra_jobs)"
"$build_dir/bench/$target" --data "$root/../shared/data" "$@"
