"""Runs the Python tests with pytest (CTest's python_tests).

Exits 77 (CTest: skipped) with a message naming the missing package when
numpy or pytest is not installed, and makes "no tests ran" a failure.
"""

import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

missing = [name for name in ("numpy", "pytest") if importlib.util.find_spec(name) is None]
if missing:
    print(
        "SKIPPED: the Python tests need "
        + " and ".join(missing)
        + " for "
        + sys.executable
        + " (Debian: apt-get install python3-numpy python3-pytest)"
    )
    sys.exit(77)

import pytest  # noqa: E402

# -p no:cacheprovider: no .pytest_cache in the source tree.
code = pytest.main([HERE, "-p", "no:cacheprovider", "-q", "-rs"] + sys.argv[1:])
sys.exit(1 if code == pytest.ExitCode.NO_TESTS_COLLECTED else int(code))
