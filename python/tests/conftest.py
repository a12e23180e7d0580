"""Shared fixtures of the Python tests: maps of the simulated office built
with fixed settings, the `umbra` program to compare with, and the shared data.

The tests run from CTest (python_tests) with PYTHONPATH pointing at the
build's python/ folder; UMBRA_CLI names the `umbra` program and
UMBRA_SHARED_DATA_DIR the real sensor data (tests needing either skip with a
message naming what is missing).
"""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import umbra

SOURCE_DIR = Path(__file__).resolve().parents[2]


def small_lidar():
    """A quarter of the default beams: scans of the office in a few milliseconds."""
    return umbra.sim.LidarModel(rings=16, azimuth_steps=360)


def office_scans(count=10, lidar=None):
    """(origin, points) of the first `count` poses of the demo path."""
    scene = umbra.sim.demo_scene()
    return [
        (np.array(pose.position, dtype=np.float32), umbra.sim.simulate_scan(scene, pose, lidar or small_lidar()))
        for pose in umbra.sim.demo_path()[:count]
    ]


def build_office(resolution=0.1, count=10, **insert_options):
    office = umbra.OccupancyMap(resolution)
    for origin, points in office_scans(count):
        office.insert(points, origin, **insert_options)
    return office


@pytest.fixture(scope="session")
def office():
    """The office at 10 cm after the ten poses of the demo path (discrete). Do not change it: copy() first."""
    return build_office()


@pytest.fixture(scope="session")
def office_file(office, tmp_path_factory):
    path = tmp_path_factory.mktemp("office") / "office.umb"
    office.save(path)
    return path


@pytest.fixture(scope="session")
def rng():
    return np.random.default_rng(20261122)


def office_points(rng, n, margin=0.0):
    """Random points in the office's box (x 0..20, y 0..12, z 0..3), widened by margin."""
    low = np.array([0.0, 0.0, 0.0]) - margin
    high = np.array([20.0, 12.0, 3.0]) + margin
    return rng.uniform(low, high, size=(n, 3))


@pytest.fixture(scope="session")
def cli():
    """Runs `umbra ARGS` with the given standard input; returns stdout."""
    path = os.environ.get("UMBRA_CLI", "")
    if not path or not Path(path).exists():
        pytest.skip("the `umbra` program is not built (UMBRA_CLI unset): no comparison with it")

    def run(*args, input_text=None):
        result = subprocess.run(
            [path, *map(str, args)], input=input_text, capture_output=True, text=True, check=False
        )
        assert result.returncode == 0, f"umbra {' '.join(map(str, args))} failed:\n{result.stderr}"
        return result.stdout

    return run


@pytest.fixture(scope="session")
def shared_data():
    path = Path(os.environ.get("UMBRA_SHARED_DATA_DIR", SOURCE_DIR.parent / "shared" / "data"))
    if not path.is_dir():
        pytest.skip(f"shared data not found at {path}: the test needs ../shared/data")
    return path


def finest_keys(points, resolution, depth_levels=16):
    """Finest keys (N, 3) of points as docs/design.md (Semantics) defines them: floor(c / res) + 2^(depth_levels - 1)."""
    return np.floor(np.asarray(points, dtype=np.float64) * (1.0 / resolution)).astype(np.int64) + (
        1 << (depth_levels - 1)
    )


def leaf_containing(leaves, points, resolution, depth_levels=16):
    """Index into `leaves` (a NODE_DTYPE array that tiles the map) of the leaf holding each point, found
    from the leaves' own keys and depths (no lookup through the map): -1 where none does."""
    by_key = {
        (int(k[0]) >> int(d), int(k[1]) >> int(d), int(k[2]) >> int(d), int(d)): i
        for i, (k, d) in enumerate(zip(leaves["key"], leaves["depth"]))
    }
    depths = sorted(set(int(d) for d in leaves["depth"]))
    index = np.full(len(points), -1)
    for i, key in enumerate(finest_keys(points, resolution, depth_levels)):
        for d in depths:
            found = by_key.get((int(key[0]) >> d, int(key[1]) >> d, int(key[2]) >> d, d))
            if found is not None:
                index[i] = found
                break
    return index


def numbers(rows):
    """Rows of numbers as text lines for `umbra query` (repr: every double exactly)."""
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows)
