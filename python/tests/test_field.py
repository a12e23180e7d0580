"""umbra.DistanceField against the map's own sphere checks and a brute force
over voxel centres, and its numpy shapes and errors."""

import threading

import numpy as np
import pytest

import umbra


def room_map():
    """A 2 m room seen from its centre: occupied walls, free inside, unknown outside."""
    m = umbra.OccupancyMap(0.1)
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.0, 1.0, size=(3000, 3))
    wall = rng.integers(0, 6, size=len(points))
    points[np.arange(len(points)), wall // 2] = np.where(wall % 2 == 0, -1.05, 1.05)
    m.insert(points.astype(np.float32), (0.0, 0.0, 0.0))
    return m


def test_distance_agrees_with_sphere_checks():
    m = room_map()
    field = umbra.DistanceField(m, max_distance=0.6)
    rng = np.random.default_rng(4)
    points = rng.uniform(-1.3, 1.3, size=(200, 3))
    # Voxel centres: floor to the grid, then half a voxel.
    centres = (np.floor(points / 0.1) + 0.5) * 0.1
    d = field.distance(centres)
    assert d.shape == (200,)
    inside = d < 0.6
    assert inside.sum() > 50
    for c, r in zip(centres[inside], d[inside]):
        if r > 0:
            assert m.is_free(umbra.Sphere(c, r * (1 - 1e-9)))
        assert not m.is_free(umbra.Sphere(c, r * (1 + 1e-9) + 1e-12))


def test_rows_and_shapes():
    m = room_map()
    field = umbra.DistanceField(m, max_distance=0.5, depth=1)
    assert field.max_distance == 0.5 and field.depth == 1
    points = np.zeros((4, 7, 3))
    rows = field.distance_and_gradient(points)
    assert rows.shape == (4, 7, 5)
    np.testing.assert_array_equal(field.distance(points), np.minimum(rows[..., 0], rows[..., 1]))
    gradient = field.distance_and_gradient([[0.55, 0.02, 0.03]])[0, 2:]
    assert abs(np.linalg.norm(gradient) - 1) < 1e-12
    assert field.memory_bytes() > 0
    with pytest.raises(IndexError, match="point 1"):
        field.distance([[0, 0, 0], [1e9, 0, 0]])
    with pytest.raises(ValueError):
        field.distance(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="max_distance"):
        umbra.DistanceField(m, max_distance=-1.0)


def test_update_after_scans_equals_rebuild_while_another_thread_queries():
    m = umbra.OccupancyMap(0.1)
    field = umbra.DistanceField(m, max_distance=0.4, box=umbra.Aabb((-1.5, -1.5, -1.5), (1.5, 1.5, 1.5)), threads=2)
    rng = np.random.default_rng(5)
    probe = rng.uniform(-1.4, 1.4, size=(5000, 3))
    stop = threading.Event()

    def query():
        while not stop.is_set():
            assert np.all(field.distance(probe) <= 0.4)

    reader = threading.Thread(target=query)
    reader.start()
    try:
        for scan in range(4):
            points = rng.uniform(-1.0, 1.0, size=(500, 3)).astype(np.float32)
            points[:, scan % 3] = 1.05
            m.insert(points, tuple(rng.uniform(-0.3, 0.3, size=3)))
            field.update()
            fresh = umbra.DistanceField(m, max_distance=0.4, box=umbra.Aabb((-1.5, -1.5, -1.5), (1.5, 1.5, 1.5)))
            np.testing.assert_array_equal(field.distance_and_gradient(probe), fresh.distance_and_gradient(probe))
    finally:
        stop.set()
        reader.join()
