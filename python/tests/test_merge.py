"""OccupancyMap.merge: the other map's log-odds added voxel by voxel.

References: sums computed here with numpy in float32 (the C++ merge is
checked against a dense brute force in tests/map/map_merge_test.cpp), the
rule for transforms (a voxel takes the other map's voxel its centre maps
back into) worked out by hand for a half-voxel shift.
"""

import numpy as np
import pytest

import umbra

RES = 0.1


def voxel_centres(n, rng):
    """n distinct voxel centres of a depth-5 map (keys 8..23 on each axis)."""
    keys = rng.choice(16**3, size=n, replace=False)
    ijk = np.stack([keys % 16, keys // 16 % 16, keys // 256], axis=1) + 8
    return (ijk - 16 + 0.5) * RES


def two_maps():
    rng = np.random.default_rng(3)
    a = umbra.OccupancyMap(RES, 5)
    b = umbra.OccupancyMap(RES, 5)
    pa = voxel_centres(300, rng)
    pb = voxel_centres(300, rng)
    a.set_log_odds(pa, rng.uniform(-1.5, 1.5, len(pa)).astype(np.float32))
    b.set_log_odds(pb, rng.uniform(-1.5, 1.5, len(pb)).astype(np.float32))
    return a, b, pa, pb


def clamped(values, m):
    """values clamped to the map's sensor model, in float32 as the map stores them."""
    model = m.sensor_model
    low = np.float32(np.log(model.clamp_min / (1 - model.clamp_min)))
    high = np.float32(np.log(model.clamp_max / (1 - model.clamp_max)))
    return np.clip(values.astype(np.float32), low, high)


def test_merge_adds_the_log_odds_and_clamps():
    a, b, pa, pb = two_maps()
    points = np.concatenate([pa, pb])
    expected = clamped(a.log_odds(points) + b.log_odds(points), a)
    stats = a.merge(b)
    assert isinstance(stats, umbra.MergeStats)
    assert stats.voxels == len(pb)
    np.testing.assert_array_equal(a.log_odds(points), expected)


def test_merge_with_an_offset_moves_the_other_map():
    a, b, _, pb = two_maps()
    moved = pb + np.array([2, -1, 3]) * RES
    expected = clamped(a.log_odds(moved) + b.log_odds(pb), a)
    a.merge(b, offset=(2, -1, 3))
    np.testing.assert_array_equal(a.log_odds(moved), expected)


def test_merge_with_a_half_voxel_transform_takes_the_voxel_the_centre_maps_into():
    a = umbra.OccupancyMap(RES, 5)
    b = umbra.OccupancyMap(RES, 5)
    b.set_log_odds([[0.05, 0.05, 0.05]], 1.0)
    pose = np.eye(4)
    pose[0, 3] = 0.5 * RES  # other's frame shifted half a voxel along x
    a.merge(b, transform=pose)
    # Voxel centre 0.05 maps back to 0.0 (in other's voxel [0, 0.1)), 0.15 to 0.1 (the next one).
    np.testing.assert_array_equal(a.log_odds([[0.05, 0.05, 0.05], [0.15, 0.05, 0.05], [-0.05, 0.05, 0.05]]),
                                  np.float32([1.0, 0.0, 0.0]))


def test_merge_refuses_bad_input_and_keeps_the_map():
    a, b, pa, _ = two_maps()
    before = a.log_odds(pa)
    with pytest.raises(ValueError, match="resolutions differ"):
        a.merge(umbra.OccupancyMap(0.2, 5))
    with pytest.raises(ValueError, match="depth levels differ"):
        a.merge(umbra.OccupancyMap(RES, 6))
    with pytest.raises(ValueError, match="not both"):
        a.merge(b, offset=(1, 0, 0), transform=np.eye(4))
    with pytest.raises(ValueError, match="offset"):
        a.merge(b, offset=(1, 0))
    skew = np.eye(4)
    skew[0, 1] = 0.5
    with pytest.raises(ValueError, match="rigid"):
        a.merge(b, transform=skew)
    with pytest.raises(IndexError, match="outside"):
        a.merge(b, offset=(20, 0, 0))
    np.testing.assert_array_equal(a.log_odds(pa), before)
