"""A map that moves: the window's box follows the scans, what leaves it is
forgotten or spilled to a file, and the spill merged with the window gives
the map of the whole run (in C++ tested against brute force:
tests/map/moving_window_test.cpp)."""

import numpy as np
import pytest

import umbra


def drive(m, seed=2):
    rng = np.random.default_rng(seed)
    whole = umbra.OccupancyMap(0.1, depth_levels=6)
    for i in range(20):
        origin = np.array([-2.0 + 0.2 * i, 0.0, 0.0], dtype=np.float32)
        points = (origin + rng.uniform(-0.45, 0.45, size=(50, 3))).astype(np.float32)
        m.insert(points, origin)
        whole.insert(points, origin)
    return whole


def test_the_window_forgets_what_leaves_and_the_spill_gives_it_back(tmp_path):
    spill = tmp_path / "run.umbs"
    m = umbra.OccupancyMap(0.1, depth_levels=6)
    m.set_moving_window(0.5, spill_path=spill, step_depth=1)
    assert m.window_box is None
    whole = drive(m)
    (lo, hi) = m.window_box
    assert all(a <= b for a, b in zip(lo, hi))
    # The start of the drive has left the box: unknown here, known in the whole map.
    assert m.state([-2.0, 0.0, 0.0]) == umbra.UNKNOWN
    assert whole.state([-2.0, 0.0, 0.0]) != umbra.UNKNOWN
    assert m.node_counts().total < whole.node_counts().total
    assembled = umbra.load_spill(spill)
    assembled.merge(m)
    for x in np.arange(-2.4, 2.0, 0.1):
        assert assembled.log_odds([x, 0.05, 0.05]) == pytest.approx(whole.log_odds([x, 0.05, 0.05]), abs=1e-4)
    move = m.move_window([1.5, 0.0, 0.0])
    assert isinstance(move, umbra.WindowMove) and move.moved


def test_bad_settings_and_a_damaged_spill_file(tmp_path):
    m = umbra.OccupancyMap(0.1, depth_levels=6)
    with pytest.raises(ValueError):
        m.set_moving_window(0.0)
    with pytest.raises(RuntimeError):
        m.move_window([0.0, 0.0, 0.0])
    bad = tmp_path / "bad.umbs"
    bad.write_bytes(b"UMBSPILL\xff\x00\x00\x00\x00\x00\x00\x00abc")
    with pytest.raises(umbra.FormatError, match="byte 8"):
        umbra.load_spill(bad)
    m.set_moving_window(None)
    assert m.window_box is None
