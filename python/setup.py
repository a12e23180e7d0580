"""Builds the Python package umbra for pip (python/pyproject.toml holds the metadata).

The compiled part umbra/_umbra*.so is built by umbra's own CMake project (the
repository above this folder) for the interpreter that runs pip, with
umbra's libraries linked in statically: the module then depends on nothing
but Debian's shared libraries (zstd, bzip2, libpng, zlib, liblzf, libstdc++), so an
installed package or a wheel keeps working when the clone or its build
folder is gone, and needs no libumbra installed beside it.

Environment: CMAKE_ARGS, extra options for CMake's configure step (e.g.
"-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"); CMAKE_BUILD_PARALLEL_LEVEL, the
number of compile jobs (default: the machine's cores).
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

PYTHON_DIR = Path(__file__).resolve().parent
SOURCE_DIR = PYTHON_DIR.parent


def project_version():
    """The version in the top-level CMakeLists.txt's project() call, the one place it is written."""
    text = (SOURCE_DIR / "CMakeLists.txt").read_text()
    match = re.search(r"project\(\s*umbra\s+VERSION\s+([0-9.]+)", text)
    if not match:
        sys.exit(f"setup.py: no 'project(umbra VERSION x.y.z' in {SOURCE_DIR / 'CMakeLists.txt'}")
    return match.group(1)


class CMakeExtension(Extension):
    """An extension whose sources CMake knows; setuptools only places the result."""

    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures umbra with only the Python module on and builds its target umbra_python."""

    def build_extension(self, ext):
        if shutil.which("cmake") is None:
            sys.exit("setup.py: building umbra needs cmake (Debian: apt-get install cmake)")
        build_dir = Path(self.build_temp).resolve() / "cmake"
        configure = [
            "cmake",
            "-S", str(SOURCE_DIR),
            "-B", str(build_dir),
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DBUILD_SHARED_LIBS=OFF",
            "-DUMBRA_BUILD_PYTHON=ON",
            "-DUMBRA_BUILD_TOOLS=OFF",
            "-DUMBRA_BUILD_TESTS=OFF",
            "-DUMBRA_BUILD_BENCHMARKS=OFF",
            "-DUMBRA_BUILD_EXAMPLES=OFF",
            "-DUMBRA_BUILD_ROS=OFF",
            "-DUMBRA_INSTALL=OFF",
        ]
        configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "umbra_python", "--parallel", jobs], check=True)

        built = build_dir / "python" / "umbra" / ("_umbra" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.exists():
            # python/CMakeLists.txt returns early, with a message, when pybind11 or the headers are missing.
            sys.exit(
                f"setup.py: CMake did not build {built}; its output above says why "
                "(Debian: apt-get install python3-dev pybind11-dev)"
            )
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


setup(
    version=project_version(),
    ext_modules=[CMakeExtension("umbra._umbra")],
    cmdclass={"build_ext": CMakeBuild},
)
