"""Python bindings benchmark: 1,000,000 sphere checks and 1,000,000 point lookups
from Python against the same work in C++ on the same map (issue 11; results in
docs/benchmarks.md, "Python bindings").

    scripts/bench.sh python [--points 1000000] [--repeat 5]

Builds a 10 cm map of the three 3DTK scans of ../shared/data (the simulated
office when absent), saves it as .umb, draws the inputs (fixed seed): sphere
centres uniform in the known bounds with radii uniform in [0.1, 0.5] m, and
points uniform in the same bounds. Then times, each the median thread CPU
time of --repeat runs:

  Python  map.spheres_free(centers, radii) and map.states(points), arguments
          as a user has them (float64 numpy arrays), everything the call does
          included (argument checks, the answer array);
  C++     bench/python_batch_benchmark.cpp on the saved map and inputs: the
          same library calls as a C++ user writes them.

Both halves must give the same answers (checked by count); the ratio
Python / C++ is the bindings' overhead.
"""

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import umbra


def build_map(data, resolution):
    graph = data / "3dtk" / "3dtk_registered.graph"
    m = umbra.OccupancyMap(resolution)
    if graph.exists():
        for origin, points, _ in umbra.read_scans(graph):
            m.insert(points, origin, max_range=30.0)
        return f"3DTK scans at {resolution} m", m
    print(f"{graph} not found: the simulated office instead", file=sys.stderr)
    scene = umbra.sim.demo_scene()
    for pose in umbra.sim.demo_path():
        m.insert(umbra.sim.simulate_scan(scene, pose), np.array(pose.position, dtype=np.float32))
    return f"simulated office at {resolution} m", m


def median_thread_seconds(repeat, task):
    times = []
    answer = None
    for _ in range(repeat):
        start = time.thread_time()
        answer = task()
        times.append(time.thread_time() - start)
    return float(np.median(times)), answer


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cpp", required=True, type=Path, help="the umbra_python_batch_benchmark program")
    parser.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data")
    parser.add_argument("--resolution", type=float, default=0.1)
    parser.add_argument("--points", type=int, default=1_000_000, help="spheres and points per batch")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    name, m = build_map(args.data, args.resolution)
    stats = m.statistics()
    low, high = np.array(stats.known_min), np.array(stats.known_max)
    rng = np.random.default_rng(11)
    centers = rng.uniform(low, high, size=(args.points, 3))
    radii = rng.uniform(0.1, 0.5, size=args.points)
    points = rng.uniform(low, high, size=(args.points, 3))

    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        m.save(scratch / "map.umb")
        np.column_stack([centers, radii]).astype("<f8").tofile(scratch / "spheres.f64")
        points.astype("<f8").tofile(scratch / "points.f64")
        output = subprocess.run(
            [str(args.cpp), str(scratch / "map.umb"), str(scratch / "spheres.f64"), str(scratch / "points.f64"),
             "--repeat", str(args.repeat)],
            check=True, capture_output=True, text=True,
        ).stdout
        # Python on the saved map too: both halves answer on the same tree, laid out alike in memory.
        m = umbra.load(scratch / "map.umb")
    cpp = {}
    for line in output.splitlines():
        task, seconds, ones = line.split()
        cpp[task] = (float(seconds), int(ones))

    sphere_seconds, free = median_thread_seconds(args.repeat, lambda: m.spheres_free(centers, radii))
    state_seconds, states = median_thread_seconds(args.repeat, lambda: m.states(points))
    python = {
        "spheres": (sphere_seconds, int(free.sum())),
        "states": (state_seconds, int((states == umbra.OCCUPIED).sum())),
    }

    print(f"{name}: {m.node_counts().total} nodes; {args.points} spheres (r 0.1-0.5 m) and points uniform in the "
          f"known bounds; median thread CPU time of {args.repeat} runs")
    print("| task | Python s | C++ s | Python / C++ | answers (1s) |")
    print("|---|---|---|---|---|")
    failed = False
    for task, label in (("spheres", f"{args.points} sphere checks"), ("states", f"{args.points} point lookups")):
        (py_s, py_ones), (cpp_s, cpp_ones) = python[task], cpp[task]
        same = "same" if py_ones == cpp_ones else f"DIFFER: {py_ones} vs {cpp_ones}"
        failed |= py_ones != cpp_ones
        print(f"| {label} | {py_s:.3f} | {cpp_s:.3f} | {py_s / cpp_s:.2f}x | {py_ones} ({same}) |")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
