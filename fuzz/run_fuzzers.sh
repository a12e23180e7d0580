#!/usr/bin/env bash
# Builds the fuzz targets with clang in a build folder of their own and runs
# each for a while from its seed corpus.
#
#   fuzz/run_fuzzers.sh [--build DIR] [--seconds N | --runs N] [--jobs J] [TARGET...]
#   fuzz/run_fuzzers.sh [--build DIR] --total N [--chunk N] [--parallel P] [--background] [TARGET...]
#   fuzz/run_fuzzers.sh [--build DIR] --report
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
#
# Long runs, resumable (docs/fuzzing.md, "Long runs"): --total N (10000000
# or 1e7) runs each target until it has run N inputs in all, over any number
# of runs of this script on this build folder, the cheapest targets first,
# in chunks of --chunk inputs (default 1000000), --parallel P targets at a
# time (default 1). The state is DIR/state: TARGET.count (inputs so far),
# TARGET.history (one line per chunk), TARGET.log (the fuzzer's output of
# the last chunk), TARGET.crash. Stopping the script credits the chunk under
# way with what it ran; after a lost machine the next run credits it with
# the count of the last line its log shows. A
# target whose fuzzer finds a crash stops there (TARGET.crash names the
# input), the others go on; later runs skip it until that file is removed.
# --background starts such a run detached, under nice -n 19, its output in
# DIR/state/run.log, its process id in DIR/state/run.pid. --report prints
# the counts as a Markdown table and exits. One run at a time per build
# folder (DIR/state/lock); a second is refused with exit code 2.
set -euo pipefail

source_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$source_dir/build-fuzz"
seconds=10
runs=""
total=""
chunk=1000000
parallel=1
report=""
background=""
jobs=2
targets=()
arguments=()  # for --background: the same run, detached
while [[ $# -gt 0 ]]; do
  case "$1" in
    --background) background=1; shift; continue ;;
  esac
  arguments+=("$1")
  case "$1" in
    --build) build_dir="$(realpath -m "$2")"; arguments+=("$build_dir"); shift 2 ;;
    --seconds) seconds="$2"; arguments+=("$2"); shift 2 ;;
    --runs) runs="$2"; arguments+=("$2"); shift 2 ;;
    --total) total="$(awk -v n="$2" 'BEGIN { printf "%.0f", n }')"; arguments+=("$2"); shift 2 ;;
    --chunk) chunk="$(awk -v n="$2" 'BEGIN { printf "%.0f", n }')"; arguments+=("$2"); shift 2 ;;
    --parallel) parallel="$2"; arguments+=("$2"); shift 2 ;;
    --report) report=1; shift ;;
    --jobs) jobs="$2"; arguments+=("$2"); shift 2 ;;
    -h|--help) sed -n '2,36p' "$0"; exit 0 ;;
    *) targets+=("$1"); named=1; shift ;;
  esac
done
if [[ -n "$total" ]] && ! ((total > 0 && chunk > 0 && parallel > 0)); then
  echo "--total, --chunk and --parallel take positive numbers (got $total, $chunk, $parallel)"
  exit 2
fi
if [[ ${#targets[@]} -eq 0 ]]; then
  if [[ -n "$total" || -n "$report" ]]; then
    # Cheapest first (inputs per second on one core, docs/fuzzing.md), so
    # that most targets are done early in a run that gets cut short.
    targets=(umb graph octomap_bt octomap_ot umb_body kitti xyz pcd ply query_lines rosbag xyz_bz2 insert)
  else
    targets=(octomap_bt octomap_ot umb umb_body graph xyz xyz_bz2 ply pcd kitti query_lines insert)
  fi
fi
state="$build_dir/state"

# --report: one Markdown row per target; a chunk under way counts with the
# inputs its log shows so far.
print_report() {
  echo "| target | inputs so far | of | crashes | corpus (files, KB) | edges | exec/s (last chunk) | hours |"
  echo "|---|---|---|---|---|---|---|---|"
  local target goal="${total:-$(cat "$state/total" 2> /dev/null || echo '?')}"
  for target in "${targets[@]}"; do
    [[ "$target" != rosbag || -x "$build_dir/fuzz/umbra_fuzz_rosbag" ]] || continue
    local count=0 history="$state/$target.history" crash="none" corpus="$build_dir/corpus/$target" files=0 kb=0
    [[ -f "$state/$target.count" ]] && count="$(cat "$state/$target.count")"
    if [[ -f "$state/$target.running" ]]; then
      count="$((count + $(inputs_in_log "$state/$target.log")))"
      if flock -n "$state/lock" true; then
        count+=" (stopped in a chunk)"
      else
        count+=" (running)"
      fi
    fi
    [[ -f "$state/$target.crash" ]] && crash="1: $(basename "$(cat "$state/$target.crash")")"
    if [[ -d "$corpus" ]]; then
      files="$(find "$corpus" -type f | wc -l)"
      kb="$(du -sk "$corpus" | cut -f 1)"
    fi
    local edges="" rate="" hours=""
    if [[ -s "$history" ]]; then
      edges="$(tail -n 1 "$history" | awk '{print $5}')"
      rate="$(tail -n 1 "$history" | awk '{print $4}')"
      hours="$(awk '{ s += $3 } END { printf "%.2f", s / 3600 }' "$history")"
    fi
    echo "| \`$target\` | $count | $goal | $crash | $files, $kb | ${edges:--} | ${rate:--} | ${hours:-0} |"
  done
}

# The inputs a fuzzer's log shows run: its final count, else (a fuzzer that
# was killed) the count of its last progress line.
inputs_in_log() {
  local n
  n="$(grep -E "^stat::number_of_executed_units" "$1" 2> /dev/null | tail -n 1 | awk '{print $2}' || true)"
  [[ -n "$n" ]] || n="$(grep -oE "^#[0-9]+" "$1" 2> /dev/null | tail -n 1 | tr -d '#' || true)"
  echo "${n:-0}"
}

if [[ -n "$report" ]]; then
  print_report
  exit 0
fi
if [[ -n "$background" ]]; then
  [[ -n "$total" ]] || { echo "--background goes with --total"; exit 2; }
  mkdir -p "$state"
  # setsid: its own session, so that closing the terminal does not stop it.
  setsid nohup nice -n 19 "$0" "${arguments[@]}" >> "$state/run.log" 2>&1 < /dev/null &
  echo $! > "$state/run.pid"
  echo "started: process $!, output $state/run.log"
  echo "counts: $0 --build $build_dir --report; stop: kill $! (a later run goes on from the counts)"
  exit 0
fi

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

mkdir -p "$build_dir"
# One run of this script per build folder: a second would rebuild the
# fuzzers and rewrite the seeds under the first, and a second --total run
# would count the same targets twice. The lock is inherited by the fuzzers,
# so it also covers one left running by a killed script.
mkdir -p "$state"
exec 9> "$state/lock"
if ! flock -n 9; then
  echo "!! another run of this script uses $build_dir (a --total run's process id: $(cat "$state/run.pid" 2> /dev/null || echo '?'))"
  exit 2
fi
echo "== building the fuzz targets with $cxx in $build_dir"
cmake -S "$source_dir" -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DUMBRA_BUILD_FUZZERS=ON -DUMBRA_ENABLE_ASSERTS=ON -DBUILD_SHARED_LIBS=OFF -DUMBRA_BUILD_TESTS=OFF \
  -DUMBRA_BUILD_TOOLS=OFF -DUMBRA_BUILD_BENCHMARKS=OFF -DUMBRA_BUILD_EXAMPLES=OFF > "$build_dir/configure.log" 2>&1 ||
  { cat "$build_dir/configure.log"; echo "!! configuring the fuzz build failed"; exit 1; }
cmake --build "$build_dir" -j "$jobs" --target umbra_fuzzers || { echo "!! the fuzz build failed"; exit 1; }

seeds="$build_dir/seeds"
rm -rf "$seeds"
"$build_dir/fuzz/umbra_fuzz_seeds" "$seeds" || { echo "!! writing the seed corpora failed"; exit 1; }

[[ -n "${named:-}" || " ${targets[*]} " == *" rosbag "* ]] || targets+=(rosbag)  # by default too

# Runs the fuzzer of $1 once with the libFuzzer flags $3..., its output in
# the file $2; in the background, so that a signal to this script can stop
# it; returns the fuzzer's exit code.
fuzz_once() {
  local target="$1" log="$2"
  shift 2
  local corpus="$build_dir/corpus/$target"
  mkdir -p "$corpus" "$build_dir/crashes"
  local dict=()
  case "$target" in
    octomap_*) dict=(-dict="$source_dir/fuzz/octomap.dict") ;;
    ply) dict=(-dict="$source_dir/fuzz/ply.dict") ;;
    pcd) dict=(-dict="$source_dir/fuzz/pcd.dict") ;;
    rosbag) dict=(-dict="$source_dir/fuzz/rosbag.dict") ;;
  esac
  local kept=()
  [[ -d "$source_dir/fuzz/corpus/$target" ]] && kept=("$source_dir/fuzz/corpus/$target")
  # shellcheck disable=SC2086
  "$build_dir/fuzz/umbra_fuzz_$target" "$corpus" "${kept[@]}" "$seeds/$target" "${dict[@]}" "$@" -max_len=16384 \
    -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$build_dir/crashes/$target-" ${UMBRA_FUZZ_FLAGS:-} > "$log" 2>&1 &
  fuzzer_pid=$!
  local rc=0
  wait "$fuzzer_pid" || rc=$?
  fuzzer_pid=""
  return $rc
}

# --total: adds a chunk of $2 inputs in $3 seconds, ended by $4
# (finished, interrupted, crash), to the count of target $1, with the
# coverage and corpus size its log shows and the commit that ran it.
credit() {
  local target="$1" inputs="$2" secs="$3" how="$4" log="$state/$1.log"
  local count rate cov corp
  count="$(cat "$state/$target.count" 2> /dev/null || echo 0)"
  rate="?"
  ((secs <= 0)) || rate=$((inputs / secs))
  cov="$(grep -oE "cov: [0-9]+" "$log" 2> /dev/null | tail -n 1 | awk '{print $2}' || true)"
  corp="$(grep -oE "corp: [^ ]+" "$log" 2> /dev/null | tail -n 1 | awk '{print $2}' || true)"
  echo "$(date -u +%Y-%m-%dT%H:%M:%SZ) $inputs $secs $rate ${cov:-?} ${corp:-?} $how $commit" >> "$state/$target.history"
  echo $((count + inputs)) > "$state/$target.count.tmp"
  mv "$state/$target.count.tmp" "$state/$target.count"
}

# --total, on a signal: stops the fuzzer of the chunk under way, credits
# what it ran (libFuzzer prints its count when stopped) and exits.
# shellcheck disable=SC2317  # called by the trap in fuzz_to_total
stop_chunk() {
  if [[ -n "${fuzzer_pid:-}" ]]; then
    kill "$fuzzer_pid" 2> /dev/null || true
    wait "$fuzzer_pid" 2> /dev/null || true
  fi
  if [[ -f "$state/$target.running" ]]; then
    credit "$target" "$(inputs_in_log "$log")" $(($(date +%s) - $(cat "$state/$target.running"))) interrupted
    rm -f "$state/$target.running"
  fi
  exit 130
}

# --total: runs target $1 chunk by chunk until its count reaches $total.
# TARGET.running holds the start time (seconds since 1970) of the chunk
# under way; finding it at the start means that chunk was stopped.
fuzz_to_total() {
  local target="$1" log="$state/$1.log"
  trap stop_chunk INT TERM
  if [[ -f "$state/$target.crash" ]]; then
    echo "!! $target: skipped, its fuzzer found a crash earlier: $(cat "$state/$target.crash")"
    return 1
  fi
  if [[ -f "$state/$target.running" ]]; then
    credit "$target" "$(inputs_in_log "$log")" $(($(stat -c %Y "$log" 2> /dev/null || date +%s) - $(cat "$state/$target.running"))) interrupted
    rm -f "$state/$target.running"
  fi
  local count
  count="$(cat "$state/$target.count" 2> /dev/null || echo 0)"
  while ((count < total)); do
    local n=$((total - count < chunk ? total - count : chunk)) started rc=0
    started="$(date +%s)"
    echo "== $target: $count of $total inputs done, running $n more ($(date -u +%H:%M:%SZ))"
    echo "$started" > "$state/$target.running"
    fuzz_once "$target" "$log" -runs="$n" || rc=$?
    local inputs secs
    inputs="$(inputs_in_log "$log")"
    secs=$(($(date +%s) - started))
    rm -f "$state/$target.running"
    if ((rc != 0)); then
      local found
      found="$(grep -oE "Test unit written to .*" "$log" | tail -n 1 | sed 's/Test unit written to //' || true)"
      if [[ -z "$found" ]]; then  # stopped from outside (a signal, the kernel's OOM killer): not a finding
        credit "$target" "$inputs" "$secs" interrupted
        echo "!! $target: the fuzzer stopped (exit code $rc) without a crash input; log $log"
        return 1
      fi
      credit "$target" $((inputs > 0 ? inputs - 1 : 0)) "$secs" crash  # the input that crashed does not count
      echo "$found" > "$state/$target.crash"
      echo "!! $target found a problem after $(cat "$state/$target.count") inputs: $found; log:"
      tail -n 60 "$log"
      return 1
    fi
    credit "$target" "$inputs" "$secs" finished
    count="$(cat "$state/$target.count")"
  done
  echo "== $target: $count inputs, done"
}

status=0
if [[ -n "$total" ]]; then
  commit="$(git -C "$source_dir" describe --always --dirty 2> /dev/null || echo unknown)"
  echo "$total" > "$state/total"
  live=()
  for target in "${targets[@]}"; do
    if [[ "$target" == rosbag && ! -x "$build_dir/fuzz/umbra_fuzz_rosbag" ]]; then
      echo "== rosbag: skipped (the fuzz build found no ROS 1; scripts/common.sh lists the Debian packages)"
      continue
    fi
    [[ -x "$build_dir/fuzz/umbra_fuzz_$target" ]] || { echo "unknown target '$target'"; exit 2; }
    live+=("$target")
  done
  echo "== $(date -u +%Y-%m-%dT%H:%M:%SZ): ${live[*]} to $total inputs each, $parallel at a time, commit $commit"
  trap 'kill $(jobs -p) 2> /dev/null; wait; exit 130' INT TERM
  running=0
  for target in "${live[@]}"; do
    if ((running >= parallel)); then
      wait -n || status=1
      running=$((running - 1))
    fi
    fuzz_to_total "$target" &
    running=$((running + 1))
  done
  while ((running > 0)); do
    wait -n || status=1
    running=$((running - 1))
  done
  targets=("${live[@]}")
  print_report
  exit $status
fi

for target in "${targets[@]}"; do
  binary="$build_dir/fuzz/umbra_fuzz_$target"
  if [[ "$target" == rosbag && ! -x "$binary" ]]; then
    echo "== rosbag: skipped (the fuzz build found no ROS 1; scripts/common.sh lists the Debian packages)"
    continue
  fi
  [[ -x "$binary" ]] || { echo "unknown target '$target'"; exit 2; }
  if [[ -n "$runs" ]]; then
    limit=(-runs="$runs")
    echo "== $target: $runs inputs"
  else
    limit=(-max_total_time="$seconds")
    echo "== $target: ${seconds} s"
  fi
  if ! fuzz_once "$target" "$build_dir/$target.log" "${limit[@]}"; then
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
