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
    start = np.array([[-2.0, 0.0, 0.0]])
    assert m.states(start)[0] == umbra.UNKNOWN
    assert whole.states(start)[0] != umbra.UNKNOWN
    assert m.memory_bytes() <= whole.memory_bytes()
    assembled = umbra.load_spill(spill)
    assembled.merge(m)
    line = np.array([[x, 0.05, 0.05] for x in np.arange(-2.4, 2.0, 0.1)])
    np.testing.assert_allclose(assembled.log_odds(line), whole.log_odds(line), atol=1e-4)
    assert np.count_nonzero(whole.log_odds(line)) > 10
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
