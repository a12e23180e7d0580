"""Queries from Python: predicates and iteration, nearest nodes, collision checks and ray casts.

References: brute force over the map's leaves in numpy (each predicate's
definition, shapes by their own geometry), the single-shape calls looped in
Python, the `umbra query` program (the C++ library's answers read from a
file) and hand-placed obstacles with known distances.
"""

import numpy as np
import pytest

import umbra
from conftest import numbers, office_points
from umbra import pred


def cube_distance(centers, sizes, point):
    """Distance from point to each axis-aligned cube (0 inside)."""
    gap = np.maximum(np.abs(point - centers) - sizes[:, None] / 2, 0.0)
    return np.sqrt((gap * gap).sum(axis=1))


def assert_same_nodes(found, expected, ordered=True):
    """The same nodes (key and depth), in the same order unless ordered is False."""
    assert len(found) == len(expected)
    if not ordered:
        found = found[np.lexsort((found["depth"], *found["key"].T))]
        expected = expected[np.lexsort((expected["depth"], *expected["key"].T))]
    np.testing.assert_array_equal(found["key"], expected["key"])
    np.testing.assert_array_equal(found["depth"], expected["depth"])
    np.testing.assert_array_equal(found["log_odds"], expected["log_odds"])


# --- predicates and iteration ---------------------------------------------------------------------------


def test_predicates_compose_and_print():
    p = pred.occupied() & ~pred.leaf() | pred.intersects(umbra.Sphere((1, 2, 3), 0.5))
    assert isinstance(p, umbra.Predicate)
    assert repr(p) == (
        "(pred.occupied() & ~pred.leaf()) | pred.intersects(Sphere(center=(1, 2, 3), radius=0.5))"
    )
    assert repr(pred.depth(2)) == "pred.depth(2)"
    with pytest.raises(TypeError, match="combine predicates with &, | and ~"):
        bool(pred.leaf())
    with pytest.raises(TypeError):
        _ = pred.leaf() and pred.free()
    with pytest.raises(TypeError):
        pred.intersects((1, 2, 3))


def test_leaf_queries_equal_the_leaves(office):
    leaves = office.leaves()
    everything = office.query(pred.leaf())
    assert_same_nodes(everything, leaves)
    for state in (umbra.OCCUPIED, umbra.FREE, umbra.UNKNOWN):
        p = {umbra.OCCUPIED: pred.occupied(), umbra.FREE: pred.free(), umbra.UNKNOWN: pred.unknown()}[state]
        found = office.query(p & pred.leaf())
        assert_same_nodes(found, leaves[leaves["state"] == state])
        assert office.count(p & pred.leaf()) == len(found)
    # The leaves tile the map once.
    assert (8.0 ** leaves["depth"]).sum() == 8.0**office.depth_levels


def test_query_without_predicate_lists_every_node(office):
    nodes = office.query()
    counts = office.node_counts()
    # Every stored node once (the query also yields inner nodes, parents first).
    assert len(nodes) == counts.total == office.count()
    assert nodes["depth"][0] == office.depth_levels
    assert set(np.unique(nodes["depth"])) == set(range(office.depth_levels + 1))


def test_spatial_predicates_against_geometry(office, rng):
    leaves = office.leaves()
    for _ in range(5):
        center = office_points(rng, 1)[0]
        radius = rng.uniform(0.2, 2.0)
        found = office.query(pred.leaf() & pred.intersects(umbra.Sphere(center, radius)))
        near = cube_distance(leaves["center"], leaves["size"], center) <= radius
        assert_same_nodes(found, leaves[near])

        low, high = np.sort(office_points(rng, 2), axis=0)
        found = office.query(pred.leaf() & pred.occupied() & pred.intersects(umbra.Aabb(low, high)))
        lo = leaves["center"] - leaves["size"][:, None] / 2
        hi = leaves["center"] + leaves["size"][:, None] / 2
        meets = np.all((lo <= high) & (hi >= low), axis=1) & (leaves["state"] == umbra.OCCUPIED)
        assert_same_nodes(found, leaves[meets])


def test_boolean_algebra_and_depths(office):
    leaves = office.leaves()
    occupied = leaves["state"] == umbra.OCCUPIED
    fine = leaves["depth"] <= 1
    cases = [
        (pred.leaf() & (pred.occupied() | pred.max_depth(1)), occupied | fine),
        (pred.leaf() & ~pred.occupied() & pred.min_depth(2), ~occupied & ~fine),
        (pred.leaf() & pred.depth(0) & pred.contains_unknown(), (leaves["depth"] == 0) & (leaves["state"] == umbra.UNKNOWN)),
    ]
    for p, expected in cases:
        assert_same_nodes(office.query(p), leaves[expected])


def test_satisfies_calls_python(office):
    leaves = office.leaves()
    threshold = 1.0
    found = office.query(pred.leaf() & pred.satisfies(lambda node: node.log_odds > threshold))
    assert_same_nodes(found, leaves[leaves["log_odds"] > threshold])
    assert len(found) > 0

    def broken(node):
        raise KeyError("from the rule")

    with pytest.raises(KeyError, match="from the rule"):
        office.query(pred.leaf() & pred.satisfies(broken))
    # A rule that changes the map while the query holds it gets the library's error.
    m = office.copy()
    with pytest.raises(RuntimeError):
        m.query(pred.satisfies(lambda node: m.clear()))


@pytest.mark.parametrize("depth", [1, 3])
def test_queries_at_depth(office, depth):
    nodes = office.query(pred.leaf(), depth)
    assert nodes["depth"].min() == depth
    assert (8.0 ** nodes["depth"]).sum() == 8.0**office.depth_levels
    # Each depth-d node's value is the maximum over the leaves below it.
    coarse = office.nodes(nodes["center"], depth)
    np.testing.assert_array_equal(coarse["log_odds"], nodes["log_odds"])
    np.testing.assert_array_equal(coarse["contains_unknown"], nodes["contains_unknown"])


def test_nearest_nodes(office, rng):
    point = np.array([4.0, 6.0, 1.2])
    nodes, distances = office.query_nearest(point, pred.occupied() & pred.leaf(), max_distance=3.0)
    occupied = office.query(pred.occupied() & pred.leaf())
    expected = cube_distance(occupied["center"], occupied["size"], point)
    within = expected <= 3.0
    assert len(nodes) == within.sum() > 0
    assert (np.diff(distances) >= 0).all(), "nearest first"
    np.testing.assert_allclose(distances, cube_distance(nodes["center"], nodes["size"], point), atol=1e-12)
    assert_same_nodes(nodes, occupied[within], ordered=False)
    first, d = office.query_nearest(point, pred.occupied() & pred.leaf(), k=3)
    assert len(first) == 3
    np.testing.assert_allclose(d, distances[:3])
    assert d[0] == pytest.approx(expected.min())


# --- collision checks --------------------------------------------------------------------------------------


def blocking(leaves, meets, unknown_is_free):
    blocks = leaves["state"] == umbra.OCCUPIED
    if not unknown_is_free:
        blocks |= leaves["state"] == umbra.UNKNOWN
    return bool((blocks & meets).any())


@pytest.mark.parametrize("unknown_is_free", [False, True])
def test_spheres_against_brute_force_and_single_checks(office, rng, unknown_is_free):
    centers = office_points(rng, 200)
    radii = rng.uniform(0.0, 0.6, size=len(centers))
    free = office.spheres_free(centers, radii, unknown_is_free=unknown_is_free)
    assert free.dtype == np.bool_ and free.shape == (200,)
    leaves = office.leaves()
    leaves = leaves[leaves["state"] != umbra.FREE]  # only these can block
    for c, r, answer in zip(centers, radii, free):
        expected = not blocking(leaves, cube_distance(leaves["center"], leaves["size"], c) <= r, unknown_is_free)
        assert answer == expected
        single = office.is_free(umbra.Sphere(c, r), unknown_is_free=unknown_is_free)
        assert single.free == answer == bool(single)
        if single.free:
            assert single.blocking is None
        else:  # a blocking leaf that meets the sphere
            b = single.blocking
            assert b.state == umbra.OCCUPIED or (b.state == umbra.UNKNOWN and not unknown_is_free)
            assert not b.has_children
            assert cube_distance(np.array([b.center]), np.array([b.size]), c)[0] <= r
    assert 0 < free.sum() < len(free), "the test needs free and blocked spheres"


def test_boxes_against_brute_force(office, rng):
    corners = office_points(rng, 400).reshape(200, 2, 3)
    low, high = corners.min(axis=1), corners.min(axis=1) + rng.uniform(0, 0.8, size=(200, 3))
    free = office.boxes_free(low, high, unknown_is_free=True)
    leaves = office.leaves()
    leaves = leaves[leaves["state"] == umbra.OCCUPIED]  # only these can block
    lo = leaves["center"] - leaves["size"][:, None] / 2
    hi = leaves["center"] + leaves["size"][:, None] / 2
    for a, b, answer in zip(low, high, free):
        meets = np.all((lo <= b) & (hi >= a), axis=1)
        assert answer == (not blocking(leaves, meets, True))
        assert office.is_free(umbra.Aabb(a, b), unknown_is_free=True).free == answer
    assert 0 < free.sum() < len(free)


def test_oriented_boxes(office, rng):
    centers = office_points(rng, 200)
    half = rng.uniform(0.05, 0.5, size=(200, 3))
    # Unturned, they are the axis-aligned boxes.
    np.testing.assert_array_equal(
        office.oriented_boxes_free(centers, half, np.eye(3)), office.boxes_free(centers - half, centers + half)
    )
    # Turned a quarter about z, they are the boxes with x and y extents swapped.
    quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    swapped = half[:, [1, 0, 2]]
    np.testing.assert_array_equal(
        office.oriented_boxes_free(centers, half, np.broadcast_to(quarter, (200, 3, 3)), unknown_is_free=True),
        office.boxes_free(centers - swapped, centers + swapped, unknown_is_free=True),
    )
    # Any rotation: the batch equals the single checks.
    angles = rng.uniform(-np.pi, np.pi, size=(200, 3))
    boxes = [umbra.OrientedBox.from_yaw_pitch_roll(c, h, *a) for c, h, a in zip(centers, half, angles)]
    rotations = np.array([b.rotation for b in boxes])
    free = office.oriented_boxes_free(centers, half, rotations, unknown_is_free=True)
    assert [office.is_free(b, unknown_is_free=True).free for b in boxes] == free.tolist()
    q = umbra.OrientedBox.from_quaternion((1, 1, 1), (1, 2, 3), (np.cos(0.25), 0, 0, np.sin(0.25)))
    np.testing.assert_allclose(q.rotation, umbra.OrientedBox.from_yaw_pitch_roll((1, 1, 1), (1, 2, 3), 0.5).rotation, atol=1e-12)


def test_capsules_and_segments_against_single_checks(office, rng):
    starts = office_points(rng, 200)
    ends = starts + rng.normal(0, 1.5, size=starts.shape)
    radii = rng.uniform(0, 0.3, size=200)
    capsules = office.capsules_free(starts, ends, radii)
    segments = office.segments_free(starts, ends, unknown_is_free=True)
    for a, b, r, c, s in zip(starts, ends, radii, capsules, segments):
        assert office.is_free(umbra.Capsule(a, b, r)).free == c
        assert office.is_free(umbra.Segment(a, b), unknown_is_free=True).free == s
    # A capsule of radius 0 holds its segment's voxels and more: free capsule -> free segment.
    assert not (office.capsules_free(starts, ends, 0.0, unknown_is_free=True) & ~segments).any()
    assert 0 < segments.sum() < len(segments)


@pytest.mark.parametrize("unknown", ["blocks", "free"])
@pytest.mark.parametrize("depth", [0, 2])
def test_batches_equal_the_umbra_program(office, office_file, cli, rng, unknown, depth):
    """spheres_free, boxes_free, segments_free, capsules_free and cast_rays against `umbra query`."""
    options = ["--unknown", unknown, "--depth", depth]
    unknown_is_free = unknown == "free"
    centers = office_points(rng, 500)
    radii = rng.uniform(0.0, 0.5, size=500)
    answers = cli("query", office_file, "sphere", "--input", "-", *options,
                  input_text=numbers(np.column_stack([centers, radii])))
    expected = np.array([line == "0" for line in answers.split()])
    np.testing.assert_array_equal(
        office.spheres_free(centers, radii, unknown_is_free=unknown_is_free, depth=depth), expected
    )

    low = office_points(rng, 300)
    high = low + rng.uniform(0, 0.7, size=low.shape)
    answers = cli("query", office_file, "box", "--input", "-", *options, input_text=numbers(np.hstack([low, high])))
    np.testing.assert_array_equal(
        office.boxes_free(low, high, unknown_is_free=unknown_is_free, depth=depth),
        [line == "0" for line in answers.split()],
    )

    starts = office_points(rng, 300)
    ends = office_points(rng, 300)
    answers = cli("query", office_file, "line", "--input", "-", *options, input_text=numbers(np.hstack([starts, ends])))
    np.testing.assert_array_equal(
        office.segments_free(starts, ends, unknown_is_free=unknown_is_free, depth=depth),
        [line == "0" for line in answers.split()],
    )
    answers = cli("query", office_file, "line", "--radius", 0.2, "--input", "-", *options,
                  input_text=numbers(np.hstack([starts, ends])))
    np.testing.assert_array_equal(
        office.capsules_free(starts, ends, 0.2, unknown_is_free=unknown_is_free, depth=depth),
        [line == "0" for line in answers.split()],
    )


def test_ray_casts_equal_the_umbra_program(office, office_file, cli, rng):
    origins = office_points(rng, 400)
    directions = rng.normal(size=(400, 3))
    answers = cli("query", office_file, "raycast", "--input", "-",
                  input_text=numbers(np.column_stack([origins, directions, np.full(400, 15.0)]))).splitlines()
    hits = office.cast_rays(origins, directions, max_range=15.0)
    assert len(hits) == 400
    for i, line in enumerate(answers):
        fields = line.split()
        assert hits.hit[i] == (fields[0] == "1")
        if hits.hit[i]:
            np.testing.assert_allclose(hits.center[i], [float(v) for v in fields[1:]], rtol=1e-9)
        else:
            assert np.isnan(hits.distance[i]) and np.isnan(hits.center[i]).all()
    assert 0 < hits.hit.sum() < 400


def test_batch_checks_broadcast_and_validate(office):
    center = np.array([4.0, 6.0, 1.2])
    radii = np.array([0.1, 0.3, 3.0])
    many = office.spheres_free(center, radii)
    assert many.tolist() == [office.is_free(umbra.Sphere(center, r)).free for r in radii]
    assert office.spheres_free(center, 0.2).shape == (1,)
    assert office.spheres_free(np.zeros((0, 3)), 0.2).shape == (0,)
    with pytest.raises(ValueError, match="centers has 2 rows but radii has 3"):
        office.spheres_free(np.zeros((2, 3)), radii)
    with pytest.raises(ValueError, match=r"centers must be an array of shape \(N, 3\) or \(3,\), got shape \(2, 4\)"):
        office.spheres_free(np.zeros((2, 4)), 1.0)
    with pytest.raises(ValueError, match=r"rotations must be an array of shape \(N, 3, 3\) or \(3, 3\)"):
        office.oriented_boxes_free(center, (1, 1, 1), np.eye(4))
    with pytest.raises(ValueError, match="sphere radius must be finite and >= 0"):
        office.spheres_free(center, -1.0)
    with pytest.raises(IndexError, match="the sphere reaches outside the map"):
        office.spheres_free([[0.0, 0.0, 0.0], [3276.0, 0.0, 0.0]], 1.0)
    with pytest.raises(IndexError, match="depth"):
        office.spheres_free(center, 1.0, depth=40)


def test_coarse_checks_are_conservative(office, rng):
    centers = office_points(rng, 500)
    fine = office.spheres_free(centers, 0.3, unknown_is_free=True)
    for depth in (1, 2, 3):
        coarse = office.spheres_free(centers, 0.3, unknown_is_free=True, depth=depth)
        assert not (coarse & ~fine).any(), "free at a coarse depth implies free at the finest"


# --- ray casts against known geometry ---------------------------------------------------------------------


@pytest.fixture()
def wall():
    """A map of free space with a wall of occupied voxels at x in [2.0, 2.1)."""
    m = umbra.OccupancyMap(0.1)
    y, z = np.meshgrid(np.arange(-1, 1, 0.1) + 0.05, np.arange(-1, 1, 0.1) + 0.05)
    m.set_log_odds(np.column_stack([np.full(y.size, 2.05), y.ravel(), z.ravel()]), 2.0)
    x, y, z = np.meshgrid(np.arange(-1, 2, 0.1) + 0.05, np.arange(-1, 1, 0.1) + 0.05, np.arange(-1, 1, 0.1) + 0.05)
    m.set_log_odds(np.column_stack([x.ravel(), y.ravel(), z.ravel()]), -2.0)
    return m


def test_ray_casts_hit_the_wall(wall):
    origins = np.array([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05], [0.05, 0.05, 0.05], [1.0, 0.5, 0.5]])
    directions = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    hits = wall.cast_rays(origins, directions, max_range=[30.0, 0.5, 1.0, 30.0])
    assert hits.hit.tolist() == [True, False, False, True]
    np.testing.assert_allclose(hits.distance[[0, 3]], [1.95, 1.0], atol=1e-9)
    np.testing.assert_allclose(hits.center[0], [2.05, 0.05, 0.05], atol=1e-9)
    np.testing.assert_allclose(hits.point[3], [2.0, 0.5, 0.5], atol=1e-9)
    np.testing.assert_allclose(hits.size[[0, 3]], 0.1)
    single = wall.cast_ray(origins[0], directions[0])
    assert single and single.distance == hits.distance[0] and single.node.center == tuple(hits.center[0])
    assert not wall.cast_ray(origins[1], directions[1], max_range=0.5)
    # Behind the free box lies unknown space: stopping there ends the ray going west at x = -1.
    west = wall.cast_ray(origins[1], directions[1], stop_at_unknown=True)
    assert west.hit and west.node.state == umbra.UNKNOWN and west.distance == pytest.approx(1.05)
    with pytest.raises(ValueError, match="direction"):
        wall.cast_rays(origins[0], [0.0, 0.0, 0.0])
    with pytest.raises(IndexError, match="ray 1: "):
        wall.cast_rays([[0, 0, 0], [5000.0, 0, 0]], [1.0, 0, 0])


def test_octomap_ray_casts(wall):
    hit, end = wall.cast_rays_octomap([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05]], [[1.0, 0, 0], [-1.0, 0, 0]],
                                      ignore_unknown=False)
    assert hit.tolist() == [True, False]
    assert end.dtype == np.float32
    np.testing.assert_allclose(end[0], [2.05, 0.05, 0.05], atol=1e-6)
    np.testing.assert_allclose(end[1], [-1.05, 0.05, 0.05], atol=1e-6)  # stopped at the first unknown voxel
    hit, _ = wall.cast_rays_octomap([0.05, 0.05, 0.05], [1.0, 0, 0], max_range=1.0)
    assert not hit[0]
    # A NaN range is refused as cast_ray refuses it (OctoMap would read it as unlimited).
    for cast in (lambda: wall.cast_rays_octomap([0.05, 0.05, 0.05], [1.0, 0, 0], max_range=np.nan),
                 lambda: wall.cast_rays([0.05, 0.05, 0.05], [1.0, 0, 0], max_range=np.nan)):
        with pytest.raises(ValueError, match="max_range is NaN"):
            cast()


def test_frustum_contains(rng):
    f = umbra.Frustum.from_degrees((1, 2, 1), 30, -10, 90, 60, 0.5, 5.0)
    assert f.yaw == pytest.approx(np.radians(30))
    points = rng.uniform(-6, 6, size=(2000, 3)) + np.array([1, 2, 1])
    inside = f.contains(points)
    d = points - np.array(f.origin)
    forward = np.array([np.cos(f.pitch) * np.cos(f.yaw), np.cos(f.pitch) * np.sin(f.yaw), np.sin(f.pitch)])
    left = np.array([-np.sin(f.yaw), np.cos(f.yaw), 0.0])
    up = np.cross(forward, left)
    df, dl, du = d @ forward, d @ left, d @ up
    r = np.linalg.norm(d, axis=1)
    expected = (df > 0) & (np.abs(np.arctan2(dl, df)) <= f.hfov / 2) & (np.abs(np.arctan2(du, df)) <= f.vfov / 2) & (
        (r >= 0.5) & (r <= 5.0)
    )
    np.testing.assert_array_equal(inside, expected)
    assert inside.sum() > 10
