#!/usr/bin/env bash
# Installs the build into a scratch prefix and uses it as a user would, with
# nothing from the build or source tree on any search path:
#  - runs the installed `umbra --version` (found its libraries through its
#    install RPATH: no LD_LIBRARY_PATH, no ldconfig), after moving the prefix
#    elsewhere (the RPATH is relative, so an unpacked tree works anywhere);
#  - builds and runs a consumer with find_package(umbra CONFIG), and one with
#    `c++ main.cpp $(pkg-config --cflags --libs umbra)` and no -std flag (the
#    .pc file says C++20);
#  - imports the installed Python module from outside the tree, when the
#    build has the module, and checks that it was loaded from the prefix.
# Usage: run_install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build_dir="$(cd "$1" && pwd)"
source_dir="$(cd "$2" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
unset LD_LIBRARY_PATH PYTHONPATH PKG_CONFIG_PATH CMAKE_PREFIX_PATH

fail() {
  echo "install test FAILED: $*" >&2
  exit 1
}

cmake --install "$build_dir" --prefix "$work/installed" >/dev/null
mv "$work/installed" "$work/prefix"   # nothing may point to where it was installed
prefix="$work/prefix"

# Every RUNPATH of an installed binary is relative to it ($ORIGIN), none into the build tree.
while IFS= read -r -d '' file; do
  if ! head -c 4 "$file" | grep -q ELF; then continue; fi
  runpath="$(readelf -d "$file" | sed -n 's/.*(\(RUNPATH\|RPATH\)).*\[\(.*\)\]/\2/p')"
  for entry in ${runpath//:/ }; do
    [[ "$entry" == '$ORIGIN'* ]] || fail "$file has RUNPATH entry $entry (expected \$ORIGIN-relative paths only)"
  done
done < <(find "$prefix" -type f \( -path '*/bin/*' -o -name '*.so*' \) -print0)

[[ -x "$prefix/bin/umbra" ]] || fail "no bin/umbra in the prefix"
version="$("$prefix/bin/umbra" --version)" || fail "$prefix/bin/umbra --version exited $?"
[[ "$version" == umbra* ]] || fail "umbra --version printed '$version'"
echo "installed program: $version"

cmake -S "$source_dir/tests/install/consumer" -B "$work/cmake-consumer" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/cmake-consumer" >/dev/null
"$work/cmake-consumer/consumer" "$work/a.umb"

export PKG_CONFIG_PATH
PKG_CONFIG_PATH="$(dirname "$(find "$prefix" -name umbra.pc -print -quit)")"
# No -std flag here: the .pc file must bring C++20 itself.
# shellcheck disable=SC2046
c++ "$source_dir/tests/install/consumer/main.cpp" -o "$work/pkg-consumer" $(pkg-config --cflags --libs umbra) ||
  fail "the pkg-config consumer does not compile with \$(pkg-config --cflags --libs umbra) alone"
# A program of the user's own has no RPATH: outside ld.so's paths (or before ldconfig) it needs LD_LIBRARY_PATH.
LD_LIBRARY_PATH="$(pkg-config --variable=libdir umbra)" "$work/pkg-consumer" "$work/b.umb"

# The Python module, when this build has one: installed beside the libraries' prefix, imported from elsewhere.
if compgen -G "$build_dir/python/umbra/_umbra*.so" >/dev/null; then
  module="$(find "$prefix" -name '_umbra*.so' -print -quit)"
  [[ -n "$module" ]] || fail "the build has the Python module but cmake --install did not install it"
  site="$(dirname "$(dirname "$module")")"
  python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build_dir/CMakeCache.txt")"
  mkdir "$work/elsewhere"
  (cd "$work/elsewhere" && PYTHONPATH="$site" "$python" -c '
import sys, umbra
prefix, source, build = sys.argv[1:4]
assert umbra.__file__.startswith(prefix), f"umbra imported from {umbra.__file__}, not from {prefix}"
for path in sys.path:
    assert not path.startswith((source, build)), f"{path} is on sys.path"
m = umbra.OccupancyMap(0.1)
m.insert([[1.0, 0.0, 0.0]], [0.0, 0.0, 0.0])
assert m.states([[1.0, 0.0, 0.0]])[0] == umbra.OCCUPIED
print("installed Python module:", umbra.__version__, "from", umbra.__file__)
' "$prefix" "$source_dir" "$build_dir") || fail "the installed Python module does not import from $site"
fi
echo "install test passed"
