"""umbra.OccupancyMap: construction, settings, insertion and per-point lookups.

References: the `umbra build` program (the C++ library's insertion, from a
file), the map's own leaves found by key arithmetic written here, and values
computed by hand from the sensor model.
"""

import copy
import math

import numpy as np
import pytest

import umbra
from conftest import build_office, finest_keys, leaf_containing, office_points, office_scans


def logit(p):
    return np.float32(math.log(p / (1 - p)))


def leaves_equal(a, b):
    """Same leaves in the same order: keys, depths, log-odds bit for bit, colors."""
    la, lb = a.leaves(), b.leaves()
    assert len(la) == len(lb)
    for field in ("key", "depth", "log_odds", "state", "has_color", "color"):
        np.testing.assert_array_equal(la[field], lb[field], err_msg=field)


# --- construction and settings ---------------------------------------------------------------------------


def test_construction_and_properties():
    m = umbra.OccupancyMap(0.05, depth_levels=12, color=True)
    assert m.resolution == 0.05
    assert m.depth_levels == 12
    assert m.has_color
    assert m.half_extent == pytest.approx(0.05 * 2**11)
    assert m.sensor_model == umbra.SensorModel()
    assert m.thresholds == umbra.Thresholds()
    assert m.auto_prune
    assert m.bounding_box is None
    counts = m.node_counts()
    assert (counts.inner, counts.inner_leaf, counts.leaf, counts.total) == (0, 1, 0, 1)
    assert m.memory_bytes() > 0
    assert "resolution=0.05" in repr(m) and "depth_levels=12" in repr(m)

    custom = umbra.OccupancyMap(
        0.1, sensor_model=umbra.SensorModel(p_hit=0.8, p_miss=0.3), thresholds=umbra.Thresholds(0.6, 0.4)
    )
    assert custom.sensor_model.p_hit == 0.8 and custom.sensor_model.p_miss == 0.3
    assert custom.thresholds.occupied == 0.6 and custom.thresholds.free == 0.4


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: umbra.OccupancyMap(0.0), "resolution must be a number of metres in"),
        (lambda: umbra.OccupancyMap(float("nan")), "resolution"),
        (lambda: umbra.OccupancyMap(0.1, depth_levels=22), "depth_levels must be in [1, 21], got 22"),
        (lambda: umbra.SensorModel(p_hit=0.4), "p_hit"),
        (lambda: umbra.SensorModel(p_miss=0.6), "p_miss"),
        (lambda: umbra.Thresholds(occupied=0.4, free=0.6), "free"),
        (lambda: umbra.Aabb((1, 0, 0), (0, 1, 1)), "min"),
        (lambda: umbra.Sphere((0, 0, 0), -1.0), "sphere radius must be finite and >= 0"),
        (lambda: umbra.Sphere((0, 0), 1.0), "center must be three numbers (x, y, z), got shape (2,)"),
        (lambda: umbra.OrientedBox((0, 0, 0), (1, 1, 1), np.ones((3, 3))), "orthonormal"),
        (lambda: umbra.Frustum((0, 0, 0), 0, 0, 4.0, 1.0, 0.0, 5.0), "frustum"),
    ],
)
def test_bad_parameters_raise_value_error_with_the_library_message(make, message):
    with pytest.raises(ValueError) as error:
        make()
    assert message in str(error.value)


def test_settings_change_the_map():
    m = umbra.OccupancyMap(0.1)
    p = np.array([[0.05, 0.05, 0.05]])
    m.set_log_odds(p, 0.3)
    assert m.states(p)[0] == umbra.OCCUPIED
    m.thresholds = umbra.Thresholds(occupied=0.6, free=0.4)  # p(0.3) = 0.574: now unknown
    assert m.states(p)[0] == umbra.UNKNOWN
    assert m.thresholds == umbra.Thresholds(0.6, 0.4)

    m.sensor_model = umbra.SensorModel(clamp_max=0.55)  # clamps stored values into the new range
    assert m.log_odds(p)[0] == pytest.approx(math.log(0.55 / 0.45), abs=1e-6)

    box = umbra.Aabb((-1, -1, -1), (1, 1, 1))
    m.bounding_box = box
    assert m.bounding_box == box
    m.bounding_box = None
    assert m.bounding_box is None

    m.auto_prune = False
    assert not m.auto_prune
    m.clear()
    assert m.states(p)[0] == umbra.UNKNOWN


def test_copies_are_deep(office):
    for duplicate in (office.copy(), copy.copy(office), copy.deepcopy(office)):
        leaves_equal(duplicate, office)
        duplicate.clear()
        assert office.node_counts().total > 1


# --- insertion ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("integrator", ["simple", "discrete", "fast"])
def test_insertion_equals_the_umbra_program(integrator, cli, tmp_path):
    """The same scan inserted from numpy and by `umbra build` from a file gives the same map, leaf for leaf."""
    (origin, points) = office_scans(count=1)[0]
    xyz = tmp_path / "scan.xyz"
    np.savetxt(xyz, points, fmt="%.9g")  # 9 digits: every float32 exactly
    out = tmp_path / "scan.umb"
    cli("build", xyz, "-o", out, "--res", 0.1, "--integrator", integrator, "--max-range", 12,
        "--origin", ",".join(repr(float(v)) for v in origin))

    m = umbra.OccupancyMap(0.1)
    stats = m.insert(points, origin, integrator=integrator, max_range=12.0)
    assert stats.points == len(points)
    assert stats.truncated > 0  # the corridor is longer than 12 m
    leaves_equal(m, umbra.load(out))


@pytest.mark.parametrize(
    "options, flags",
    [
        ({"integrator": "fast", "clear_depth": 3, "fine_steps": 0, "threads": 2},
         ["--integrator", "fast", "--clear-depth", 3, "--fine-steps", 0, "--threads", 2]),
        ({"integrator": "fast", "clear_depth": 1, "fine_steps": 5, "threads": 1},
         ["--integrator", "fast", "--clear-depth", 1, "--fine-steps", 5, "--threads", 1]),
    ],
)
def test_insert_options_reach_the_library(options, flags, cli, tmp_path):
    """clear_depth, fine_steps, threads and the bounding box give the map `umbra build` makes with the same
    settings, and a different one than the defaults."""
    (origin, points) = office_scans(count=1)[0]
    xyz = tmp_path / "scan.xyz"
    np.savetxt(xyz, points, fmt="%.9g")
    out = tmp_path / "scan.umb"
    cli("build", xyz, "-o", out, "--res", 0.1, "--bbox", "0,0,0,12,8,2.5", *flags,
        "--origin", ",".join(repr(float(v)) for v in origin))

    m = umbra.OccupancyMap(0.1)
    m.bounding_box = umbra.Aabb((0, 0, 0), (12, 8, 2.5))
    m.insert(points, origin, **options)
    leaves_equal(m, umbra.load(out))
    known = m.leaves()
    known = known[known["state"] != umbra.UNKNOWN]
    assert (known["center"] - known["size"][:, None] / 2 >= -1e-9).all()
    assert (known["center"] + known["size"][:, None] / 2 <= np.array([12, 8, 2.5]) + 0.2).all()

    default = umbra.OccupancyMap(0.1)
    default.bounding_box = m.bounding_box
    default.insert(points, origin, integrator="fast")
    assert len(default.leaves()) != len(m.leaves()) or (default.leaves()["log_odds"] != m.leaves()["log_odds"]).any()


def test_auto_prune_keeps_the_values():
    """Eight equal voxels set one by one merge into their parent with auto-pruning, stay apart without it
    (same values), and merge when it is switched on."""
    (origin, points) = office_scans(count=1)[0]
    pruned = umbra.OccupancyMap(0.1)
    unpruned = umbra.OccupancyMap(0.1)
    unpruned.auto_prune = False
    corners = np.array([[x, y, z] for x in (0.05, 0.15) for y in (0.05, 0.15) for z in (0.05, 0.15)]) + 3.0
    for m in (pruned, unpruned):
        m.insert(points, origin)
        for corner in corners:
            m.set_log_odds(corner, 1.5)
    assert unpruned.node_counts().leaf == pruned.node_counts().leaf + 8
    assert pruned.nodes(corners[0])["depth"] == 1 and unpruned.nodes(corners[0])["depth"] == 0
    probe = np.vstack([corners, office_points(np.random.default_rng(5), 5000)])
    np.testing.assert_array_equal(unpruned.log_odds(probe), pruned.log_odds(probe))
    unpruned.auto_prune = True
    counts = [(c.inner, c.inner_leaf, c.leaf) for c in (unpruned.node_counts(), pruned.node_counts())]
    assert counts[0] == counts[1]
    leaves_equal(unpruned, pruned)


def test_insert_stats_and_input_dtypes():
    (origin, points) = office_scans(count=1)[0]
    with_nan = np.vstack([points, [[np.nan, 0, 0], [1e9, 0, 0]]])
    m32 = umbra.OccupancyMap(0.1)
    stats = m32.insert(with_nan, origin, integrator="simple", threads=1)
    assert stats.points == len(points) + 2
    assert stats.non_finite == 1
    assert stats.out_of_bounds == 1
    assert stats.rays == stats.hits == len(points)
    assert stats.exclusive_seconds >= 0.0
    assert "InsertStats(points=" in repr(stats)

    # float64 points are rounded to float32 as the library takes them; lists work too.
    m64 = umbra.OccupancyMap(0.1)
    m64.insert(with_nan.astype(np.float64), origin.tolist(), integrator="simple", threads=2)
    leaves_equal(m32, m64)


def test_insertion_with_colors_averages_per_voxel():
    m = umbra.OccupancyMap(0.1, color=True)
    # Three points in voxel (1.05, 0.05, 0.05), one in (2.05, 0.05, 0.05); sensor at the origin.
    points = np.array([[1.01, 0.01, 0.01], [1.02, 0.02, 0.02], [1.03, 0.03, 0.03], [2.05, 0.05, 0.05]])
    colors = np.array([[30, 60, 90], [60, 90, 120], [90, 120, 150], [1, 2, 3]], dtype=np.uint8)
    m.insert(points, (0.05, 0.05, 0.05), colors, integrator="simple")
    nodes = m.nodes(points)
    assert nodes["has_color"].all()
    np.testing.assert_array_equal(nodes["color"][0], [60, 90, 120])
    np.testing.assert_array_equal(nodes["color"][3], [1, 2, 3])
    # A voxel passed by rays only has no color.
    assert not m.nodes([[0.55, 0.05, 0.05]])["has_color"][0]

    # Integer colors of another dtype are accepted when in range.
    m.insert(points[:1], (0.05, 0.05, 0.05), colors[:1].astype(np.int64))


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda m: m.insert(np.zeros((4, 2)), (0, 0, 0)), ValueError, "points must be an array of shape (N, 3), got shape (4, 2)"),
        (lambda m: m.insert(np.zeros((4, 3)), (0, 0)), ValueError, "origin must be three numbers"),
        (lambda m: m.insert(np.zeros((4, 3)), (0, 0, 0), integrator="dda"), ValueError, "dda"),
        (lambda m: m.insert(np.zeros((4, 3)), (0, 0, 0), fine_steps=-1), ValueError, "fine_steps"),
        (lambda m: m.insert(np.zeros((4, 3)), (0, 0, 0), threads=-2), ValueError, "threads must be >= 0"),
        (lambda m: m.insert(np.zeros((4, 3)), (1e9, 0, 0)), IndexError, "outside the map"),
        (lambda m: m.insert(np.zeros((4, 3)), (np.nan, 0, 0)), ValueError, "origin"),
        (lambda m: m.insert(np.zeros((2, 3)), (0, 0, 0), np.zeros((2, 3), dtype=np.uint8)), ValueError, "made without color"),
        (lambda m: m.insert("points", (0, 0, 0)), TypeError, "points must be an array of numbers"),
        (lambda m: m.insert(np.zeros((4, 3), dtype=np.complex128), (0, 0, 0)), TypeError,
         "points must hold real numbers, got dtype complex128"),
        (lambda m: m.insert([[1j, 0, 0]], (0, 0, 0)), TypeError, "points must hold real numbers"),
        (lambda m: m.insert(np.zeros((4, 3)), (0, 0, 1j)), TypeError, "origin must hold real numbers"),
        (lambda m: m.insert(np.array([["1", "2", "3"]]), (0, 0, 0)), TypeError,
         "points must be an array of numbers, got dtype <U1"),
    ],
)
def test_insertion_errors(call, error, message):
    m = umbra.OccupancyMap(0.1)
    with pytest.raises(error) as raised:
        call(m)
    assert message in str(raised.value)
    assert m.node_counts().total == 1, "the map is unchanged after an error"


def test_color_errors():
    m = umbra.OccupancyMap(0.1, color=True)
    points = np.zeros((2, 3))
    with pytest.raises(TypeError, match="colors must hold integers"):
        m.insert(points, (1, 1, 1), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"colors\[1\] holds 256, outside \[0, 255\]"):
        m.insert(points, (1, 1, 1), np.array([[0, 0, 0], [0, 0, 256]]))
    with pytest.raises(ValueError, match=r"colors must be an array of shape \(N, 3\)"):
        m.insert(points, (1, 1, 1), np.zeros((2, 4), dtype=np.uint8))
    # Named as the integers they are, whatever their dtype.
    for value in (2**63, 2**64 - 1, 256):
        with pytest.raises(ValueError, match=rf"colors\[1\] holds {value}, outside \[0, 255\]"):
            m.insert(points, (1, 1, 1), np.array([[0, 0, 0], [0, value, 0]], dtype=np.uint64))
    with pytest.raises(ValueError, match=rf"colors\[0\] holds {-2**63}, outside \[0, 255\]"):
        m.insert(points, (1, 1, 1), np.array([[-2**63, 0, 0], [0, 0, 0]], dtype=np.int64))
    assert m.node_counts().total == 1, "the map is unchanged after an error"
    m.insert(points, (1, 1, 1), np.array([[255, 0, 7], [255, 0, 7]], dtype=np.uint64))  # one voxel: no average
    np.testing.assert_array_equal(m.nodes(points[:1])["color"][0], [255, 0, 7])


def test_a_copy_that_does_not_fit_is_a_memory_error():
    # A broadcast view of 10^12 points costs nothing; its float64 copy would need 22 TiB.
    huge = np.broadcast_to(np.zeros(3, dtype=np.float32), (10**12, 3))
    m = umbra.OccupancyMap(0.1, color=True)
    for call, name in ((lambda: m.states(huge), "points"), (lambda: m.spheres_free(huge, 0.1), "centers")):
        with pytest.raises(MemoryError, match=name + ": not enough memory to convert it"):
            call()
    wide = np.broadcast_to(np.zeros(3, dtype=np.int32), (10**12, 3))
    with pytest.raises(MemoryError, match="colors: not enough memory to convert it"):
        m.insert(np.zeros((1, 3)), (1, 1, 1), wide)


# --- single voxels --------------------------------------------------------------------------------------


def test_voxel_updates_follow_the_sensor_model():
    m = umbra.OccupancyMap(0.1)
    model = m.sensor_model
    hit, miss = logit(model.p_hit), logit(model.p_miss)
    low, high = logit(model.clamp_min), logit(model.clamp_max)
    a = np.array([[0.05, 0.05, 0.05]])
    b = np.array([[1.05, 0.05, 0.05]])

    expected = np.float32(0)
    for _ in range(8):  # eight hits: clamped at clamp_max
        m.update_hit(a)
        expected = min(np.float32(expected + hit), high)
        assert m.log_odds(a)[0] == expected
    m.update_miss(b)
    assert m.log_odds(b)[0] == miss
    m.update_log_odds(b, -10.0)
    assert m.log_odds(b)[0] == low
    m.set_log_odds(np.vstack([a, b]), [0.25, -0.25])
    np.testing.assert_array_equal(m.log_odds(np.vstack([a, b])), np.float32([0.25, -0.25]))
    np.testing.assert_array_equal(m.states(np.vstack([a, b])), [umbra.OCCUPIED, umbra.FREE])
    with pytest.raises(ValueError, match="finite"):
        m.set_log_odds(a, float("nan"))
    with pytest.raises(ValueError, match="points has 2 rows but values has 3"):
        m.set_log_odds(np.vstack([a, b]), [1, 2, 3])


def test_add_color_averages():
    m = umbra.OccupancyMap(0.1, color=True)
    p = np.array([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05]])
    m.add_color(p, np.array([[10, 20, 30], [30, 40, 50]], dtype=np.uint8))
    np.testing.assert_array_equal(m.nodes(p[:1])["color"][0], [20, 30, 40])
    with pytest.raises(ValueError, match="the map was made without color"):
        umbra.OccupancyMap(0.1).add_color(p, np.zeros((2, 3), dtype=np.uint8))


# --- lookups of many points ----------------------------------------------------------------------------


def test_point_lookups_equal_the_leaves(office, rng):
    """states / log_odds / occupancy / nodes at depth 0 equal the leaf holding each point (found by key)."""
    points = office_points(rng, 3000, margin=1.0)
    leaves = office.leaves()
    index = leaf_containing(leaves, points, office.resolution)
    assert (index >= 0).all()
    expected = leaves[index]
    states = office.states(points)
    assert states.dtype == np.uint8
    np.testing.assert_array_equal(states, expected["state"])
    assert set(np.unique(states)) == {umbra.UNKNOWN, umbra.FREE, umbra.OCCUPIED}
    log_odds = office.log_odds(points)
    assert log_odds.dtype == np.float32
    np.testing.assert_array_equal(log_odds, expected["log_odds"])
    np.testing.assert_allclose(office.occupancy(points), 1 - 1 / (1 + np.exp(expected["log_odds"].astype(np.float64))))
    nodes = office.nodes(points)
    assert nodes.dtype == umbra.NODE_DTYPE
    for field in ("key", "depth", "center", "size", "log_odds", "state", "has_children"):
        np.testing.assert_array_equal(nodes[field], expected[field], err_msg=field)


@pytest.mark.parametrize("depth", [1, 3])
def test_point_lookups_at_depth_are_the_maximum_of_the_leaves_below(office, rng, depth):
    points = office_points(rng, 100)
    leaves = office.leaves()
    keys = finest_keys(points, office.resolution)
    nodes = office.nodes(points, depth)
    for i, key in enumerate(keys):
        block = key >> depth
        # The leaves inside this depth-d block, or the one coarser leaf covering it.
        shift = np.maximum(leaves["depth"], depth)
        inside = np.all((leaves["key"].astype(np.int64) >> shift[:, None]) == (block << depth >> shift[:, None]), axis=1)
        below = leaves[inside]
        assert len(below) > 0
        assert nodes["log_odds"][i] == below["log_odds"].max()
        assert nodes["contains_unknown"][i] == (below["state"] == umbra.UNKNOWN).any()
        assert nodes["contains_free"][i] == (below["state"] == umbra.FREE).any()
    np.testing.assert_array_equal(office.states(points, depth), nodes["state"])
    np.testing.assert_array_equal(office.log_odds(points, depth), nodes["log_odds"])


def test_point_lookups_keep_the_leading_shape(office, rng):
    grid = office_points(rng, 24).reshape(2, 4, 3, 3)
    assert office.states(grid).shape == (2, 4, 3)
    np.testing.assert_array_equal(office.states(grid).ravel(), office.states(grid.reshape(-1, 3)))
    single = office.log_odds([4.0, 6.0, 1.2])
    assert single.shape == ()
    assert office.nodes(np.zeros((0, 3))).shape == (0,)


def test_node_fields_are_consistent(office, rng):
    nodes = office.nodes(office_points(rng, 500), depth=2)
    assert (nodes["size"] == office.resolution * 2.0 ** nodes["depth"]).all()
    corner = (nodes["key"].astype(np.int64) >> nodes["depth"][:, None] << nodes["depth"][:, None]) - 2**15
    np.testing.assert_allclose(nodes["center"], (corner + 2.0 ** nodes["depth"][:, None] / 2) * office.resolution)
    assert (nodes["state"][nodes["log_odds"] > 0] == umbra.OCCUPIED).all()


def test_lookup_errors_name_the_point(office):
    points = np.array([[1.0, 1.0, 1.0], [1.0, 4000.0, 1.0]])
    for lookup in (office.states, office.log_odds, office.occupancy, office.nodes):
        with pytest.raises(IndexError) as error:
            lookup(points)
        assert "points[1]: coordinate (1, 4000, 1) is outside the map" in str(error.value)
    with pytest.raises(ValueError, match=r"points must be an array of shape \(\.\.\., 3\), got shape \(2, 2\)"):
        office.states(np.zeros((2, 2)))
    with pytest.raises(IndexError, match="depth"):
        office.states(points[:1], depth=17)


def test_statistics(office):
    stats = office.statistics()
    leaves = office.leaves()
    voxels = 8.0 ** leaves["depth"]
    assert stats.occupied_voxels == voxels[leaves["state"] == umbra.OCCUPIED].sum()
    assert stats.free_voxels == voxels[leaves["state"] == umbra.FREE].sum()
    assert stats.nodes.total == office.node_counts().total
    known = leaves[leaves["state"] != umbra.UNKNOWN]
    np.testing.assert_allclose(stats.known_min, (known["center"] - known["size"][:, None] / 2).min(axis=0))
    assert umbra.OccupancyMap(0.1).statistics().known_min is None


def test_simulated_scans_are_deterministic_and_on_surfaces():
    scene = umbra.sim.demo_scene()
    pose = umbra.sim.demo_path()[0]
    a = umbra.sim.simulate_scan(scene, pose)
    b = umbra.sim.simulate_scan(scene, pose)
    np.testing.assert_array_equal(a, b)
    assert a.dtype == np.float32 and a.shape[1] == 3
    assert len(a) <= 32 * 720
    # End points lie on the solids: nudged 1 cm further along the beam, they are inside one.
    direction = a - np.array(pose.position, dtype=np.float32)
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    assert scene.is_inside_solid(a + 0.01 * direction).mean() > 0.99
    assert len(umbra.sim.demo_path()) == 10
    assert scene.bounds()[0][0] <= 0.0


@pytest.mark.parametrize("integrator", ["simple", "discrete"])
def test_occupied_voxels_hold_end_points(integrator):
    """Known geometry: only a voxel holding an end point gets a hit, so every occupied voxel holds one."""
    scans = office_scans(count=4)
    m = umbra.OccupancyMap(0.1)
    for origin, points in scans:
        m.insert(points, origin, integrator=integrator)
    end_keys = {tuple(k) for _, points in scans for k in finest_keys(points, 0.1)}
    occupied = m.query(umbra.pred.occupied() & umbra.pred.leaf())
    assert len(occupied) > 1000 and (occupied["depth"] == 0).all()
    assert {tuple(int(v) for v in k) for k in occupied["key"]} <= end_keys


# --- decay toward unknown ----------------------------------------------------------------------------------


def decayed(log_odds, occupied_step, free_step):
    """docs/design.md's rule in float32: positive values lose occupied_step, negative ones gain free_step, to 0."""
    l = np.asarray(log_odds, dtype=np.float32)
    a, b = np.float32(occupied_step), np.float32(free_step)
    return np.where(l > 0, np.maximum(l - a, np.float32(0)), np.where(l < 0, np.minimum(l + b, np.float32(0)), l))


def test_decay_moves_every_voxel_toward_unknown_by_the_rule():
    m = umbra.OccupancyMap(0.1, depth_levels=10)
    points = office_points(np.random.default_rng(5), 2000)
    m.insert(points, (10.0, 6.0, 1.5), stamp=10.0)
    assert m.clock == 10.0
    m.set_decay(0.4, 0.3)
    assert m.decay == (0.4, 0.3, None)
    before = m.leaves()
    known = before[before["state"] != umbra.UNKNOWN]
    centres = known["center"]
    m.advance_clock(11.5)  # 1.5 s: 0.6 and 0.45 rounded down to whole quanta of 2**-16
    quanta = lambda amount: np.floor(amount * 65536.0) / 65536.0
    np.testing.assert_array_equal(m.log_odds(centres), decayed(known["log_odds"], quanta(0.4 * 1.5), quanta(0.3 * 1.5)))
    assert (m.states(centres) == umbra.UNKNOWN).any()  # single misses (-0.405) are forgotten
    m.advance_clock(11.0)  # earlier: nothing
    assert m.clock == 11.5
    m.advance_clock(100.0)
    assert m.node_counts().total == 1  # everything forgotten: the root alone


def test_decay_refuses_bad_rates_and_stamps():
    m = umbra.OccupancyMap(0.1, depth_levels=8)
    with pytest.raises(ValueError, match="occupied_per_second"):
        m.set_decay(-1.0, 0.0)
    with pytest.raises(ValueError, match="stamp"):
        m.insert(np.array([[1.0, 0.0, 0.0]]), (0, 0, 0), stamp=float("nan"))
    assert m.clock is None
