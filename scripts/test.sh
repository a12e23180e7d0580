#!/usr/bin/env bash
# Quick start, step 2: install what is missing, build everything (library,
# program, examples, tests, the Python module, the ROS node) and run the
# default test suite: every behaviour test, leaving out the labels that
# build and test a tree of their own for minutes (fuzz, install, sanitize,
# tsan; `.ci/run` runs them after this, docs/testing.md says what they are).
# Idempotent; a second run rebuilds only what changed.
#
# Extra arguments go to ctest, e.g. ./scripts/test.sh -R Oracle. Arguments
# that choose labels themselves (-L, -LE, --label-regex, --label-exclude)
# replace the default exclusion: ./scripts/test.sh -L install runs the
# install tests, ./scripts/test.sh -LE sanitize everything built.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$(umbra_root)"
build_dir="${UMBRA_BUILD_DIR:-$root/build}"

# The labels left out by default, as one ctest regular expression.
excluded_labels="fuzz|install|sanitize|tsan"
labels=(-LE "$excluded_labels")
for argument in "$@"; do
  case "$argument" in
    -L | -LE | --label-regex | --label-exclude) labels=() ;;
  esac
done

umbra_install_packages
umbra_configure "$build_dir" -DCMAKE_BUILD_TYPE=Release -DUMBRA_ENABLE_ASSERTS=ON
cmake --build "$build_dir" -j "$(umbra_jobs)"
ctest --test-dir "$build_dir" --output-on-failure -j "$(umbra_jobs)" "${labels[@]}" "$@"
