#!/usr/bin/env bash
# `pip install` of the Python package as the README tells a user, offline:
# a copy of the source tree (what a clone holds), a fresh virtual
# environment with Debian's packages visible (--system-site-packages, for
# numpy), `pip install --no-build-isolation --no-index ./python`, then an
# import from outside the tree, with the copy deleted first: the installed
# module must need neither its sources nor its build folder. Then
# `pip wheel` of the same copy must give a wheel holding the module.
# Exits 77 (skipped) naming the Debian package that is missing.
# Usage: run_venv_test.sh BUILD_DIR SOURCE_DIR
#   The interpreter is the one CMake built BUILD_DIR's module for
#   (Python3_EXECUTABLE in its cache), else /usr/bin/python3.
set -euo pipefail
python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$1/CMakeCache.txt")"
python="${python:-/usr/bin/python3}"
source_dir="$(cd "$2" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
unset PYTHONPATH PIP_INDEX_URL PIP_EXTRA_INDEX_URL

fail() {
  echo "venv test FAILED: $*" >&2
  exit 1
}
skip() {
  echo "SKIPPED: $*"
  exit 77
}

"$python" -c 'import venv, ensurepip' 2>/dev/null || skip "$python cannot make virtual environments with pip (Debian: python3-venv)"
"$python" -c 'import setuptools, wheel' 2>/dev/null || skip "$python lacks setuptools or wheel (Debian: python3-setuptools python3-wheel)"
"$python" -c 'import numpy' 2>/dev/null || skip "$python lacks numpy (Debian: python3-numpy)"
"$python" -c 'import pybind11' 2>/dev/null || skip "$python lacks pybind11 (Debian: python3-pybind11 pybind11-dev)"

# The files of a clone: the tracked and the new ones, not build folders or ignored files.
mkdir "$work/clone"
if git -C "$source_dir" rev-parse --git-dir >/dev/null 2>&1; then
  git -C "$source_dir" ls-files -z --cached --others --exclude-standard |
    tar -C "$source_dir" --null --no-recursion --ignore-failed-read -T - -cf - 2>/dev/null | tar -C "$work/clone" -xf -
else
  cp -r "$source_dir/CMakeLists.txt" "$source_dir/cmake" "$source_dir/include" "$source_dir/src" "$source_dir/python" \
    "$work/clone/"
fi

"$python" -m venv --system-site-packages "$work/venv"
venv_python="$work/venv/bin/python"
# ccache, when there is one, makes a second run of this test quick (paths
# relative to the scratch folder, so that each run's compile lines match).
if command -v ccache >/dev/null; then
  export CMAKE_ARGS="${CMAKE_ARGS:-} -DCMAKE_CXX_COMPILER_LAUNCHER=ccache" CCACHE_BASEDIR="$work"
fi
(cd "$work/clone" && "$venv_python" -m pip install --no-build-isolation --no-index ./python) >"$work/pip.log" 2>&1 ||
  { tail -n 40 "$work/pip.log"; fail "pip install --no-build-isolation --no-index ./python failed"; }

# Wheel first (same clone, its CMake build is reused), then delete the clone before importing.
(cd "$work/clone" && "$venv_python" -m pip wheel --no-build-isolation --no-index --no-deps -w "$work/wheels" ./python) \
  >"$work/wheel.log" 2>&1 || { tail -n 40 "$work/wheel.log"; fail "pip wheel ./python failed"; }
rm -rf "$work/clone"

wheel="$(find "$work/wheels" -name 'umbra-*.whl' -print -quit)"
[[ -n "$wheel" ]] || fail "pip wheel made no umbra-*.whl"
"$python" - "$wheel" <<'EOF' || fail "the wheel lacks files"
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
for wanted in ("umbra/__init__.py", "umbra/__init__.pyi", "umbra/py.typed"):
    assert wanted in names, f"{wanted} not in {sys.argv[1]}: {names}"
assert any(n.startswith("umbra/_umbra") and n.endswith(".so") for n in names), f"no umbra/_umbra*.so in {names}"
print("wheel:", sys.argv[1].rsplit("/", 1)[-1])
EOF

mkdir "$work/elsewhere"
cd "$work/elsewhere"
"$venv_python" - "$work/venv" "$source_dir" <<'EOF' || fail "the pip-installed module does not work from outside the tree"
import inspect, subprocess, sys
import umbra

venv, source = sys.argv[1:3]
assert umbra.__file__.startswith(venv), f"umbra imported from {umbra.__file__}, not from the virtual environment"
assert not any(p.startswith(source) for p in sys.path), "the source tree is on sys.path"
# The module links umbra's libraries statically: no libumbra in its dependencies.
ldd = subprocess.run(["ldd", umbra._umbra.__file__], capture_output=True, text=True, check=True).stdout
assert "libumbra" not in ldd and "not found" not in ldd, ldd
assert umbra.__version__.count(".") == 2, umbra.__version__
assert "resolution" in inspect.signature(umbra.OccupancyMap).parameters
m = umbra.OccupancyMap(0.1)
stats = m.insert([[1.0, 0.0, 0.0]], [0.0, 0.0, 0.0])
assert m.states([[1.0, 0.0, 0.0]])[0] == umbra.OCCUPIED
print("pip-installed module:", umbra.__version__, "from", umbra.__file__, stats)
EOF
echo "venv test passed"
