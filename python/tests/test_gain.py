"""Information gain from Python: one pose, a list of Frustums, and numpy arrays of poses.

Reference: the definition, voxel by voxel, in numpy: every finest voxel
within max_range of the sensor, its state and log-odds read with the map's
per-point lookups, Frustum.contains on its centre, and its visibility from
the library's own ray walk (segments_free from the float origin to the float
centre with unknown space passing: OctoMap's computeRayKeys, the walk the
gain is defined by). The batch forms are held to the single calls.
"""

import numpy as np
import pytest

import umbra
from conftest import office_points


def voxel_centres_near(m, frustum):
    """Centres (N, 3) of every finest voxel whose centre can lie within max_range of the origin."""
    res = m.resolution
    origin = np.array(frustum.origin)
    low = np.floor((origin - frustum.max_range) / res).astype(np.int64)
    high = np.floor((origin + frustum.max_range) / res).astype(np.int64)
    axes = [(np.arange(low[a], high[a] + 1) + 0.5) * res for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def entropy_bits(log_odds):
    p = 1.0 / (1.0 + np.exp(-log_odds.astype(np.float64)))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = -p * np.log2(p) - (1 - p) * np.log2(1 - p)
    return np.where((p > 0) & (p < 1), h, 0.0)


def brute_force_gain(m, frustum, hidden=None):
    """(unknown_voxels, entropy_bits) by the definition; hidden (a list) gets the number of unknown voxels in
    the frustum that are not visible."""
    centres = voxel_centres_near(m, frustum)
    candidates = centres[(m.states(centres) == umbra.UNKNOWN) & frustum.contains(centres)]
    if len(candidates) == 0:
        return 0, 0.0
    origin = np.array(frustum.origin, dtype=np.float32).astype(np.float64)
    ends = candidates.astype(np.float32).astype(np.float64)
    visible = candidates[m.segments_free(origin, ends, unknown_is_free=True)]
    if hidden is not None:
        hidden.append(len(candidates) - len(visible))
    return len(visible), float(entropy_bits(m.log_odds(visible)).sum())


def random_frustums(rng, n, origins):
    """Frustums with random headings, fields of view and ranges from the given origins."""
    return [
        umbra.Frustum.from_degrees(
            origins[i % len(origins)],
            rng.uniform(-180, 180),
            rng.uniform(-30, 30),
            rng.uniform(20, 150),
            rng.uniform(20, 120),
            rng.uniform(0.0, 0.5),
            rng.uniform(1.5, 4.0),
        )
        for i in range(n)
    ]


def test_exact_gain_is_the_definition_in_the_office(office, rng):
    poses = [np.array(p.position) for p in umbra.sim.demo_path()[:10]]
    # Poses on the path (mostly seen space) and at random places (some in unseen space, some inside walls).
    frustums = random_frustums(rng, 6, poses) + random_frustums(rng, 6, office_points(rng, 6))
    hidden = []
    for f in frustums:
        expected_voxels, expected_entropy = brute_force_gain(office, f, hidden)
        gain = office.information_gain(f)
        assert gain.unknown_voxels == expected_voxels, f
        assert gain.volume == pytest.approx(expected_voxels * office.resolution**3)
        assert gain.entropy_bits == pytest.approx(expected_entropy, rel=1e-9, abs=1e-9)
    gains = [office.information_gain(f).unknown_voxels for f in frustums]
    assert sum(gains) > 1000 and sum(hidden) > 1000, "the poses must see unknown space, and miss some behind walls"


def test_entropy_counts_unknown_voxels_by_their_probability(rng):
    # Thresholds wide enough that voxels with p != 0.5 stay unknown and weigh less than a bit.
    m = umbra.OccupancyMap(0.1, thresholds=umbra.Thresholds(occupied=0.8, free=0.2))
    points = rng.uniform(-1.5, 1.5, size=(3000, 3))
    m.set_log_odds(points, rng.uniform(-1.2, 1.2, size=len(points)))
    # (An origin off the voxel centres: a centre exactly max_range away is a tie, decided by rounding.)
    f = umbra.Frustum.from_degrees((0.031, 0.017, 0.062), 10, 5, 120, 90, 0.0, 2.0)
    voxels, entropy = brute_force_gain(m, f)
    gain = m.information_gain(f)
    assert gain.unknown_voxels == voxels
    assert gain.entropy_bits == pytest.approx(entropy, rel=1e-9)
    assert gain.entropy_bits < gain.unknown_voxels - 10, "voxels with p != 0.5 weigh less than a bit"


def test_batch_forms_equal_the_single_calls(office, rng):
    origins = np.array([p.position for p in umbra.sim.demo_path()[:10]])[rng.integers(0, 10, 12)]
    yaw = rng.uniform(-180, 180, 12)
    pitch = rng.uniform(-20, 20, 12)
    hfov = rng.uniform(30, 120, 12)
    frustums = [umbra.Frustum.from_degrees(origins[i], yaw[i], pitch[i], hfov[i], 60, 0.2, 4.0) for i in range(12)]
    for method in ("exact", "fast"):
        single = [office.information_gain(f, method=method) for f in frustums]
        expected = np.array([(g.unknown_voxels, g.volume, g.entropy_bits) for g in single], dtype=umbra.GAIN_DTYPE)
        listed = office.information_gains(frustums, method=method, threads=2)
        arrays = office.information_gains(origins, yaw, pitch, hfov, 60, 0.2, 4.0, method=method, threads=1)
        assert listed.dtype == umbra.GAIN_DTYPE and listed.shape == (12,)
        np.testing.assert_array_equal(listed, expected)
        np.testing.assert_array_equal(arrays, expected)
    # fast_depth 0 makes the fast method exact.
    np.testing.assert_array_equal(
        office.information_gains(frustums, method="fast", fast_depth=0), office.information_gains(frustums)
    )
    # One origin for all poses broadcasts.
    one = office.information_gains(origins[0], yaw, pitch, 90, 60, 0.0, 3.0)
    for i in (0, 5, 11):
        g = office.information_gain(umbra.Frustum.from_degrees(origins[0], yaw[i], pitch[i], 90, 60, 0.0, 3.0))
        assert one[i]["unknown_voxels"] == g.unknown_voxels and one[i]["entropy_bits"] == g.entropy_bits
    assert len(office.information_gains([])) == 0


def test_gain_errors(office):
    f = umbra.Frustum.from_degrees((5, 5, 1), 0, 0, 90, 60, 0, 3)
    with pytest.raises(ValueError, match="method must be 'exact' or 'fast'"):
        office.information_gain(f, method="quick")
    with pytest.raises(ValueError, match="fast_depth"):
        office.information_gain(f, method="fast", fast_depth=99)
    with pytest.raises(ValueError, match="pose 1: frustum fields of view"):
        office.information_gains([[5, 5, 1], [5, 5, 1]], 0, 0, [90, 200], 60, 0, 3)
    with pytest.raises(ValueError, match="pose 0: frustum ranges"):
        office.information_gains([5, 5, 1], 0, 0, 90, 60, 3, 1)
    with pytest.raises(IndexError, match="pose 2: origin outside the map"):
        office.information_gains([[5, 5, 1], [5, 5, 1], [1e5, 5, 1]], 0, 0, 90, 60, 0, 3)
    with pytest.raises(IndexError):
        office.information_gain(umbra.Frustum.from_degrees((1e5, 0, 0), 0, 0, 90, 60, 0, 3))
    with pytest.raises(ValueError, match="origins has 2 rows but yaw has 3"):
        office.information_gains([[5, 5, 1], [5, 5, 1]], [0, 1, 2], 0, 90, 60, 0, 3)
    with pytest.raises(ValueError, match="threads"):
        office.information_gains([f], threads=-1)
    # The bound insert() has: thousands of threads used to end the interpreter.
    with pytest.raises(ValueError, match=r"threads must be at most \d+ \(4 per hardware thread, at least 16.*got 2000"):
        office.information_gains([f], threads=2000)
    with pytest.raises(ValueError, match="threads must be at most"):
        office.information_gains([5, 5, 1], 0, 0, 90, 60, 0, 3, threads=2000)
    with pytest.raises(ValueError, match="threads must be at most"):
        umbra.OccupancyMap(0.1).insert(np.zeros((1, 3)), (0, 0, 0), threads=2000)
    assert len(office.information_gains([f, f], threads=16)) == 2  # 16 is always allowed, as for insert()


def test_gain_falls_as_the_map_fills():
    # Observing what a sensor would see lowers its gain: a property, independent of the counting.
    scans = [(np.array(p.position, dtype=np.float32), umbra.sim.simulate_scan(umbra.sim.demo_scene(), p))
             for p in umbra.sim.demo_path()[:3]]
    m = umbra.OccupancyMap(0.1)
    f = umbra.Frustum.from_degrees(scans[0][0], 0, 0, 120, 60, 0, 5)
    gains = [m.information_gain(f).unknown_voxels]
    for origin, points in scans:
        m.insert(points, origin)
        gains.append(m.information_gain(f).unknown_voxels)
    centres = voxel_centres_near(m, f)
    assert gains[0] == f.contains(centres).sum(), "in an empty map every voxel in view counts"
    assert gains == sorted(gains, reverse=True) and gains[-1] < gains[0]
