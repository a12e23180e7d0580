"""Build a map in Python from real laser scans, query it with numpy, and plot it.

    build/python/python3 examples/python_map.py map.png

(build/python/python3 runs the python3 the module was built for, with
build/python on PYTHONPATH; with umbra installed, plain python3 does.)

Reads the three registered 3DTK scans of ../shared/data (the simulated
office when that folder is absent), builds a 10 cm map, asks it what a
planner asks (collision checks of many balls, a fan of ray casts, the
nearest obstacle, the unknown space left, where to look next) and draws a horizontal slice of
free / unknown / occupied space with the answers on top into the PNG.
"""

import argparse
import sys
import time
from pathlib import Path

try:
    import matplotlib.pyplot as plt
except ModuleNotFoundError as error:
    # Another python3 than the one umbra was built for (first on PATH) may lack it.
    sys.exit(f"examples/python_map.py: {sys.executable} cannot import {error.name} "
             "(Debian: apt-get install python3-matplotlib); build/python/python3 runs the python3 umbra was built for")
import numpy as np

import umbra
from umbra import pred


def scans_from(data):
    """(origin, points) of the 3DTK scans, or of the simulated office when the data is absent."""
    graph = data / "3dtk" / "3dtk_registered.graph"
    if graph.exists():
        return "3DTK scans", [(origin, points) for origin, points, _ in umbra.read_scans(graph)]
    print(f"{graph} not found: using the simulated office instead", file=sys.stderr)
    office = umbra.sim.demo_scene()
    return "simulated office", [
        (np.array(pose.position, dtype=np.float32), umbra.sim.simulate_scan(office, pose))
        for pose in umbra.sim.demo_path()
    ]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", help="PNG file to write")
    parser.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared" / "data",
                        help="the shared data folder (default: ../shared/data beside the repository)")
    parser.add_argument("--res", type=float, default=0.1, help="voxel edge in metres")
    args = parser.parse_args()
    plt.switch_backend("Agg")  # files only, no display

    name, scans = scans_from(args.data)
    m = umbra.OccupancyMap(args.res)
    start = time.perf_counter()
    for origin, points in scans:
        stats = m.insert(points, origin, integrator="discrete", max_range=30.0)
        print(f"scan of {stats.points} points: {stats.hits} hits, {stats.truncated} rays cut at 30 m")
    print(f"{name}: {len(scans)} scans in {time.perf_counter() - start:.2f} s, {m.node_counts().total} nodes")

    # A horizontal slice at the first sensor's height: the state of every cell centre.
    sensor = scans[0][0].astype(np.float64)
    stats = m.statistics()
    (x0, y0, _), (x1, y1, _) = stats.known_min, stats.known_max
    xs = np.arange(x0, x1, args.res) + args.res / 2
    ys = np.arange(y0, y1, args.res) + args.res / 2
    grid = np.stack(np.meshgrid(xs, ys, indexing="xy") + [np.full((len(ys), len(xs)), sensor[2])], axis=-1)
    states = m.states(grid)  # (rows, columns) of umbra.UNKNOWN / FREE / OCCUPIED

    # Collision checks of 20,000 balls of 0.3 m at sensor height (unknown space blocks).
    rng = np.random.default_rng(1)
    centers = np.column_stack([rng.uniform(x0, x1, 20000), rng.uniform(y0, y1, 20000), np.full(20000, sensor[2])])
    free = m.spheres_free(centers, 0.3)
    print(f"{free.sum()} of {len(free)} balls of 0.3 m are free")

    # A fan of 360 ray casts from the first sensor, obstacles within 15 m (unknown space is passed through).
    angles = np.radians(np.arange(360))
    directions = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    hits = m.cast_rays(sensor, directions, max_range=15.0)
    print(f"{hits.hit.sum()} of 360 rays hit an obstacle within 15 m, the nearest at {np.nanmin(hits.distance):.2f} m")

    nearest, distance = m.query_nearest(sensor, pred.occupied() & pred.leaf(), k=1)
    print(f"nearest obstacle to the sensor: {distance[0]:.2f} m at {np.round(nearest['center'][0], 2)}")
    unknown = m.count(pred.unknown() & pred.leaf() & pred.intersects(umbra.Aabb(stats.known_min, stats.known_max)), 2)
    print(f"unknown 40 cm nodes within the known bounds: {unknown}")

    # Where to look next: the information gain of 16 headings at the sensor (a 90 x 60 degree camera, 8 m).
    yaws = np.arange(0.0, 360.0, 22.5)
    gains = m.information_gains(sensor, yaws, 0.0, 90.0, 60.0, 0.0, 8.0)
    best = int(np.argmax(gains["unknown_voxels"]))
    print(f"looking at yaw {yaws[best]:.1f} deg would reveal {gains['unknown_voxels'][best]} unknown voxels "
          f"({gains['volume'][best]:.1f} m^3); the least, {gains['unknown_voxels'].min()}")

    colors = np.array([[0.55, 0.55, 0.55], [1.0, 1.0, 1.0], [0.1, 0.1, 0.1]])  # unknown, free, occupied
    figure, axes = plt.subplots(figsize=(10, 10 * len(ys) / max(len(xs), 1) + 1), dpi=100)
    axes.imshow(colors[states], origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]), interpolation="nearest")
    axes.scatter(*centers[free, :2].T, s=1, c="tab:green", label="free 0.3 m balls")
    for end in hits.point[hits.hit]:
        axes.plot([sensor[0], end[0]], [sensor[1], end[1]], color="tab:orange", linewidth=0.3)
    axes.plot(*sensor[:2], "o", color="tab:red", label="sensor")
    axes.set_title(f"umbra: {name} at {args.res} m, slice z = {sensor[2]:.2f} m "
                   "(white free, grey unknown, black occupied)")
    axes.set_xlabel("x (m)")
    axes.set_ylabel("y (m)")
    axes.legend(loc="upper right")
    figure.savefig(args.output, bbox_inches="tight")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
