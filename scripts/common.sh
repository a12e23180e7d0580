# Shared by scripts/demo.sh, scripts/test.sh and scripts/bench.sh (sourced).
# Installs the Debian packages umbra needs (only those missing) and
# configures a build folder once.

# Everything umbra, its tests and its benchmarks need on Debian 12.
UMBRA_APT_PACKAGES=(
  build-essential cmake pkg-config git
  libzstd-dev libbz2-dev libpng-dev zlib1g-dev liblzf-dev  # umbra_io
  liblz4-dev                                    # lz4 chunks of .bag files (ros/src/bag_chunk.cpp)
  libcli11-dev                                  # the umbra program
  libgtest-dev libgmock-dev                     # tests
  liboctomap-dev                                # differential tests and benchmarks only
  libdynamicedt3d-dev                           # bench/field: OctoMap's distance field, compared with umbra's
  clang                                         # fuzz targets (optional label)
  bzip2 python3                                 # test helpers
  python3-dev python3-pybind11 pybind11-dev     # the Python module umbra (python/)
  python3-numpy python3-pytest python3-matplotlib  # its tests and examples/python_map.py
  python3-pip python3-venv python3-setuptools python3-wheel  # pip install ./python offline (--no-build-isolation)
  file                                          # cpack -G DEB (dpkg-shlibdeps comes with build-essential)
  chromium                                      # the `umbra view` page tested in a headless browser
  # ROS 1 (ros/: umbra_server, `umbra build` of .bag files, their tests; optional, found by CMake):
  ros-core-dev libroscpp-dev libsensor-msgs-dev libtf2-ros-dev librosbag-dev
  libstd-srvs-dev libvisualization-msgs-dev libtf2-msgs-dev libnav-msgs-dev
  python3-gencpp python3-genmsg python3-empy     # message headers (ros/generate_messages.py)
  python3-genpy                                  # Python modules of octomap_msgs/umbra_msgs (ros/generate_python_messages.py)
  # Python modules of the node's other message types, for rostopic and rosservice (ros-core brings the tools):
  python3-sensor-msgs python3-geometry-msgs python3-visualization-msgs python3-std-srvs python3-tf2-msgs python3-nav-msgs
  ros-std-msgs ros-geometry-msgs ros-sensor-msgs ros-visualization-msgs ros-tf2-msgs ros-actionlib-msgs ros-std-srvs ros-nav-msgs
)

# Commands installed only when missing, as COMMAND:PACKAGE: Node.js and npm
# bundle three.js into the page of `umbra view` at build time. A machine may
# have them from elsewhere (NodeSource's nodejs, which provides npm and
# conflicts with Debian's npm package).
UMBRA_APT_COMMANDS=(node:nodejs npm:npm)

umbra_root() { cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd; }

umbra_install_packages() {
  local missing=()
  local package
  for package in "${UMBRA_APT_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$package")
    fi
  done
  local entry
  for entry in "${UMBRA_APT_COMMANDS[@]}"; do
    if ! command -v "${entry%%:*}" >/dev/null 2>&1; then
      missing+=("${entry#*:}")
    fi
  done
  if ((${#missing[@]} == 0)); then
    return 0
  fi
  local sudo=()
  if [[ "$(id -u)" != 0 ]]; then
    sudo=(sudo)
  fi
  echo "umbra: installing Debian packages: ${missing[*]}" >&2
  "${sudo[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# umbra_configure BUILD_DIR [cmake options...]: configures once; later runs
# keep the existing configuration (so a second run is quick).
umbra_configure() {
  local build_dir="$1"
  shift
  if [[ ! -f "$build_dir/CMakeCache.txt" ]]; then
    cmake -S "$(umbra_root)" -B "$build_dir" "$@"
  fi
}

umbra_jobs() { nproc 2>/dev/null || echo 2; }
