#!/usr/bin/env bash
# Builds the fuzz targets with clang in a build folder of their own and runs
# each for a while from its seed corpus.
#
#   fuzz/run_fuzzers.sh [--build DIR] [--seconds N | --runs N] [--jobs J] [TARGET...]
#
# TARGET: octomap_bt octomap_ot umb umb_body graph xyz xyz_bz2 ply pcd kitti query_lines insert (default:
# all). Defaults: --build build-fuzz (under the source folder), --seconds 10;
# --runs N stops each target after N inputs instead. Each target starts from
# the generated seeds and the corpus kept in the repository (fuzz/corpus/TARGET);
# new inputs go to DIR/corpus/TARGET (kept between runs, so longer runs build
# on shorter ones); crashes to DIR/crashes/TARGET-*. Exit codes: 0 no crash,
# 1 a fuzzer found a crash (or the build failed), 77 clang or libFuzzer is
# missing (CTest counts that as skipped). Environment: UMBRA_FUZZ_CXX (the
# compiler, default clang++; CXX is not used since it usually names the main
# build's GCC), UMBRA_FUZZ_FLAGS (extra libFuzzer flags).
# Also the target rosbag (the .bag scan source), named or by default, where
# the fuzz build found ROS 1; elsewhere it is skipped with a message.
set -euo pipefail

source_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$source_dir/build-fuzz"
seconds=10
runs=""
jobs=2
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) targets+=("$1"); named=1; shift ;;
  esac
done
[[ ${#targets[@]} -gt 0 ]] || targets=(octomap_bt octomap_ot umb umb_body graph xyz xyz_bz2 ply pcd kitti query_lines insert)

cxx="${UMBRA_FUZZ_CXX:-clang++}"
if ! command -v "$cxx" > /dev/null 2>&1 || ! "$cxx" --version 2>/dev/null | grep -qi clang; then
  echo "SKIPPED: the fuzzers need clang with libFuzzer; '$cxx' is not clang (set UMBRA_FUZZ_CXX=clang++-NN)"
  exit 77
fi
probe_dir="$(mktemp -d)"
trap 'rm -rf "$probe_dir"' EXIT
printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' > "$probe_dir/probe.cpp"
if ! "$cxx" -fsanitize=fuzzer,address "$probe_dir/probe.cpp" -o "$probe_dir/probe" > "$probe_dir/log" 2>&1; then
  echo "SKIPPED: $cxx cannot link a libFuzzer target (libclang-rt / compiler-rt missing?):"
  cat "$probe_dir/log"
  exit 77
fi

echo "== building the fuzz targets with $cxx in $build_dir"
mkdir -p "$build_dir"
cmake -S "$source_dir" -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DUMBRA_BUILD_FUZZERS=ON -DUMBRA_ENABLE_ASSERTS=ON -DBUILD_SHARED_LIBS=OFF -DUMBRA_BUILD_TESTS=OFF \
  -DUMBRA_BUILD_TOOLS=OFF -DUMBRA_BUILD_BENCHMARKS=OFF -DUMBRA_BUILD_EXAMPLES=OFF > "$build_dir/configure.log" 2>&1 ||
  { cat "$build_dir/configure.log"; echo "!! configuring the fuzz build failed"; exit 1; }
cmake --build "$build_dir" -j "$jobs" --target umbra_fuzzers || { echo "!! the fuzz build failed"; exit 1; }

seeds="$build_dir/seeds"
rm -rf "$seeds"
"$build_dir/fuzz/umbra_fuzz_seeds" "$seeds" || { echo "!! writing the seed corpora failed"; exit 1; }

[[ -n "${named:-}" ]] || targets+=(rosbag)  # by default too
status=0
for target in "${targets[@]}"; do
  binary="$build_dir/fuzz/umbra_fuzz_$target"
  if [[ "$target" == rosbag && ! -x "$binary" ]]; then
    echo "== rosbag: skipped (the fuzz build found no ROS 1; scripts/common.sh lists the Debian packages)"
    continue
  fi
  [[ -x "$binary" ]] || { echo "unknown target '$target'"; exit 2; }
  corpus="$build_dir/corpus/$target"
  mkdir -p "$corpus" "$build_dir/crashes"
  dict=()
  case "$target" in
    octomap_*) dict=(-dict="$source_dir/fuzz/octomap.dict") ;;
    ply) dict=(-dict="$source_dir/fuzz/ply.dict") ;;
    pcd) dict=(-dict="$source_dir/fuzz/pcd.dict") ;;
    rosbag) dict=(-dict="$source_dir/fuzz/rosbag.dict") ;;
  esac
  kept=()
  [[ -d "$source_dir/fuzz/corpus/$target" ]] && kept=("$source_dir/fuzz/corpus/$target")
  if [[ -n "$runs" ]]; then
    limit=(-runs="$runs")
    echo "== $target: $runs inputs"
  else
    limit=(-max_total_time="$seconds")
    echo "== $target: ${seconds} s"
  fi
  # shellcheck disable=SC2086
  if ! "$binary" "$corpus" "${kept[@]}" "$seeds/$target" "${dict[@]}" "${limit[@]}" -max_len=16384 \
       -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="$build_dir/crashes/$target-" ${UMBRA_FUZZ_FLAGS:-} > "$build_dir/$target.log" 2>&1; then
    echo "!! $target found a problem; input saved under $build_dir/crashes/$target-*; log:"
    tail -n 60 "$build_dir/$target.log"
    status=1
  else
    # A summary only: a log without these lines is not a failure (the fuzzer's exit code said it ran clean).
    { grep -E "^stat::(number_of_executed_units|new_units_added|peak_rss_mb)" "$build_dir/$target.log" | tr '\n' ' '
      grep -E "^#[0-9]+[[:space:]]+DONE" "$build_dir/$target.log" | tail -n 1 |
        sed -E 's/.*(cov: [0-9]+).*(corp: [^ ]+).*(exec\/s: [0-9]+).*/\1 \2 \3/'; } || true
    echo
  fi
done
exit $status
