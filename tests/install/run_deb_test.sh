#!/usr/bin/env bash
# The Debian packages of a build (cpack -G DEB, cmake/UmbraDebianPackages.cmake):
#  - the four packages are made: libumbra, libumbra-dev, umbra, python3-umbra
#    (the last when the build has the Python module), with the dependencies
#    between them;
#  - apt accepts them together (`apt-get install --simulate ./*.deb`, which
#    resolves their dependencies against this machine without installing);
#  - unpacked into a throwaway root, their files work from there: the
#    program runs, a consumer compiles against libumbra-dev with pkg-config
#    and with find_package, and the Python module imports from outside the
#    source tree.
# Exits 77 (skipped) when dpkg-deb, dpkg-shlibdeps (dpkg-dev) or cpack is missing.
# Usage: run_deb_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build_dir="$(cd "$1" && pwd)"
source_dir="$(cd "$2" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
unset LD_LIBRARY_PATH PYTHONPATH PKG_CONFIG_PATH CMAKE_PREFIX_PATH

fail() {
  echo "Debian package test FAILED: $*" >&2
  exit 1
}
for tool in cpack dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null || { echo "SKIPPED: needs $tool (Debian: cmake, dpkg-dev)"; exit 77; }
done

(cd "$work" && cpack -G DEB --config "$build_dir/CPackConfig.cmake" -B "$work/debs") >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack -G DEB failed"; }

packages=(libumbra libumbra-dev umbra)
if compgen -G "$build_dir/python/umbra/_umbra*.so" >/dev/null; then
  packages+=(python3-umbra)
fi
debs=()
for package in "${packages[@]}"; do
  deb="$(find "$work/debs" -maxdepth 1 -name "${package}_*.deb" -print -quit)"
  [[ -n "$deb" ]] || fail "no ${package}_*.deb made (made: $(ls "$work/debs"))"
  [[ "$(dpkg-deb -f "$deb" Package)" == "$package" ]] || fail "$deb is not package $package"
  debs+=("$deb")
done
depends_on() {  # depends_on PACKAGE DEPENDENCY
  dpkg-deb -f "$(find "$work/debs" -maxdepth 1 -name "$1_*.deb" -print -quit)" Depends | grep -qw -- "$2" ||
    fail "$1 does not depend on $2"
}
depends_on libumbra-dev libumbra
depends_on libumbra-dev libzstd-dev
depends_on libumbra-dev liblzf-dev
depends_on umbra libumbra
depends_on libumbra libzstd1
depends_on libumbra liblzf1
if [[ " ${packages[*]} " == *" python3-umbra "* ]]; then
  depends_on python3-umbra libumbra
  depends_on python3-umbra python3-numpy
fi

if command -v apt-get >/dev/null; then
  apt-get install --simulate --no-install-recommends "${debs[@]}" >"$work/apt.log" 2>&1 ||
    { cat "$work/apt.log"; fail "apt-get install --simulate ./*.deb refuses the packages"; }
  for package in "${packages[@]}"; do
    grep -q "^Inst $package " "$work/apt.log" || { cat "$work/apt.log"; fail "apt would not install $package"; }
  done
fi

root="$work/root"
for deb in "${debs[@]}"; do dpkg-deb -x "$deb" "$root"; done
"$root/usr/bin/umbra" --version || fail "the packaged umbra does not run from the unpacked root"

pc="$(find "$root" -name umbra.pc -print -quit)"
[[ -n "$pc" ]] || fail "libumbra-dev has no umbra.pc"
export PKG_CONFIG_PATH
PKG_CONFIG_PATH="$(dirname "$pc")"
# shellcheck disable=SC2046
c++ "$source_dir/tests/install/consumer/main.cpp" -o "$work/pkg-consumer" $(pkg-config --cflags --libs umbra) ||
  fail "a consumer does not compile against libumbra-dev with pkg-config"
LD_LIBRARY_PATH="$(pkg-config --variable=libdir umbra)" "$work/pkg-consumer" "$work/a.umb"
cmake -S "$source_dir/tests/install/consumer" -B "$work/cmake-consumer" -DCMAKE_PREFIX_PATH="$root/usr" >/dev/null
cmake --build "$work/cmake-consumer" >/dev/null
"$work/cmake-consumer/consumer" "$work/b.umb"

if [[ " ${packages[*]} " == *" python3-umbra "* ]]; then
  module="$(find "$root" -name '_umbra*.so' -print -quit)"
  [[ -n "$module" ]] || fail "python3-umbra holds no _umbra*.so"
  python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build_dir/CMakeCache.txt")"
  mkdir "$work/elsewhere"
  (cd "$work/elsewhere" && PYTHONPATH="$(dirname "$(dirname "$module")")" "$python" -c '
import sys, umbra
assert umbra.__file__.startswith(sys.argv[1]), umbra.__file__
m = umbra.OccupancyMap(0.1)
m.insert([[1.0, 0.0, 0.0]], [0.0, 0.0, 0.0])
assert m.states([[1.0, 0.0, 0.0]])[0] == umbra.OCCUPIED
print("packaged Python module:", umbra.__version__, "from", umbra.__file__)
' "$root") || fail "the module of python3-umbra does not import"
fi
echo "Debian package test passed: $(cd "$work/debs" && ls ./*.deb | tr '\n' ' ')"
