"""Depth images from Python: umbra.back_project, umbra.PinholeCamera and OccupancyMap.insert_depth_image.

References: the pinhole model computed here with numpy (back_project), the
discrete integrator on back_project's points inserted with insert() (the
occupied voxels of the projective integrator; the whole map for the other
integrators), and a wall whose free, occupied and unknown space is known.
"""

import sys
import threading

import numpy as np
import pytest

import umbra
from umbra import pred

CAMERA = umbra.PinholeCamera(50.0, 50.0, 31.5, 23.5)
WIDTH, HEIGHT = 64, 48

# A camera at (1.02, 2.03, 1.47) looking along +x: optical z = map x, optical x = map -y, optical y = map -z.
ALONG_X = np.array(
    [
        [0.0, 0.0, 1.0, 1.02],
        [-1.0, 0.0, 0.0, 2.03],
        [0.0, -1.0, 0.0, 1.47],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def wall(metres=2.0, dtype=np.float32):
    """A flat wall `metres` ahead, without readings in the top-left 16 x 16 pixels (0 for uint16, NaN for floats)."""
    if dtype == np.uint16:
        image = np.full((HEIGHT, WIDTH), round(metres * 1000), dtype=np.uint16)
        image[:16, :16] = 0
    else:
        image = np.full((HEIGHT, WIDTH), metres, dtype=dtype)
        image[:16, :16] = np.nan
    return image


def scene():
    """A depth image with varied depths (a slanted surface with a step and holes), float32 metres."""
    v, u = np.mgrid[0:HEIGHT, 0:WIDTH]
    depth = (1.5 + 0.02 * u + 0.3 * np.sin(v / 6.0)).astype(np.float32)
    depth[v > 30] -= 0.6
    depth[5:9, 40:50] = np.nan
    depth[20, 10:20] = 0.0
    return depth


def yawed(pose, yaw):
    """The pose turned by `yaw` radians about the map's z axis through its position."""
    c, s = np.cos(yaw), np.sin(yaw)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out = pose.copy()
    out[:3, :3] = turn @ pose[:3, :3]
    return out


def occupied_keys(m):
    leaves = m.leaves()
    occupied = leaves[leaves["state"] == umbra.OCCUPIED]
    return {(tuple(int(c) for c in k), int(d)) for k, d in zip(occupied["key"], occupied["depth"])}


def leaves_equal(a, b):
    la, lb = a.leaves(), b.leaves()
    assert len(la) == len(lb)
    for field in ("key", "depth", "log_odds", "state", "has_color", "color"):
        np.testing.assert_array_equal(la[field], lb[field], err_msg=field)


# --- back_project and PinholeCamera ------------------------------------------------------------------------


def test_back_project_follows_the_pinhole_model():
    depth = np.array([[1.0, 2.0, np.nan, 4.0], [0.0, -1.0, np.inf, 3.5], [0.5, 1.5, 2.5, 3.0]], dtype=np.float32)
    camera = umbra.PinholeCamera(2.0, 3.0, 1.5, 1.0)
    points, pixels = umbra.back_project(depth, camera, return_pixels=True)
    v, u = np.divmod(np.arange(depth.size), depth.shape[1])
    z = depth.reshape(-1).astype(np.float64)
    read = np.isfinite(z) & (z > 0)
    np.testing.assert_array_equal(pixels, np.flatnonzero(read))
    assert pixels.dtype == np.uint32
    with np.errstate(invalid="ignore"):  # the NaN and infinite pixels, dropped by [read]
        want = np.stack([(u - 1.5) / 2.0 * z, (v - 1.0) / 3.0 * z, z], axis=1)[read]
    assert points.dtype == np.float32 and points.shape == (read.sum(), 3)
    np.testing.assert_allclose(points, want, rtol=1e-6)

    # With a pose (4 x 4 or 3 x 4): R p + t; a tuple camera is the same camera.
    pose = yawed(ALONG_X, 0.3)
    moved = umbra.back_project(depth, (2.0, 3.0, 1.5, 1.0), pose)
    np.testing.assert_allclose(moved, want @ pose[:3, :3].T + pose[:3, 3], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(umbra.back_project(depth, camera, pose[:3]), moved)

    # uint16 raw depths: depth_scale units per metre.
    raw = np.array([[1000, 0], [2500, 65535]], dtype=np.uint16)
    points = umbra.back_project(raw, camera, depth_scale=1000.0)
    np.testing.assert_allclose(points[:, 2], [1.0, 2.5, 65.535], rtol=1e-7)
    tum = umbra.back_project(raw, camera, depth_scale=5000.0)  # TUM RGB-D's units
    np.testing.assert_allclose(tum[:, 2], [0.2, 0.5, 13.107], rtol=1e-7)
    big_endian = umbra.back_project(raw.astype(">u2"), camera, depth_scale=1000.0)
    np.testing.assert_array_equal(big_endian, points)


def test_pinhole_camera():
    c = umbra.PinholeCamera(fx=580.8, fy=581.8, cx=308.8, cy=253.0)
    assert (c.fx, c.fy, c.cx, c.cy) == (580.8, 581.8, 308.8, 253.0)
    assert c == umbra.PinholeCamera(580.8, 581.8, 308.8, 253.0)
    assert c != umbra.PinholeCamera(580.8, 581.8, 308.8, 253.5)
    assert repr(c) == "PinholeCamera(fx=580.8, fy=581.8, cx=308.8, cy=253.0)"
    with pytest.raises(ValueError, match="fx and fy must be finite and > 0"):
        umbra.PinholeCamera(0.0, 1.0, 0.0, 0.0)


# --- insert_depth_image ---------------------------------------------------------------------------------------


def test_projective_frees_space_in_front_of_a_wall_and_nothing_behind():
    m = umbra.OccupancyMap(0.1)
    stats = m.insert_depth_image(wall(), CAMERA, ALONG_X)
    assert stats.points == WIDTH * HEIGHT
    assert m.states([2.02, 2.03, 1.47]) == umbra.FREE  # 1 m in front of the wall
    assert m.states([3.02, 2.03, 1.47]) == umbra.OCCUPIED  # the wall, 2 m ahead
    assert m.states([4.02, 2.03, 1.47]) == umbra.UNKNOWN  # 1 m behind it
    # 1 m ahead on the ray of pixel (8, 8), among the pixels without a reading, and of pixel (55, 39) opposite.
    assert m.states([2.02, 2.03 + 0.47, 1.47 + 0.31]) == umbra.UNKNOWN
    assert m.states([2.02, 2.03 - 0.47, 1.47 - 0.31]) == umbra.FREE
    # The whole wall seen is occupied: every back-projected point's voxel.
    points = umbra.back_project(wall(), CAMERA, ALONG_X)
    assert (m.states(points) == umbra.OCCUPIED).all()

    # The same wall in millimetres (uint16), in float64, and with a 3 x 4 pose: the same map.
    for depth, scale, pose in [(wall(dtype=np.uint16), 1000.0, ALONG_X), (wall(dtype=np.float64), None, ALONG_X[:3])]:
        other = umbra.OccupancyMap(0.1)
        other.insert_depth_image(depth, CAMERA, pose, depth_scale=scale)
        leaves_equal(m, other)


def test_projective_has_the_discrete_integrators_occupied_voxels():
    for yaw in (0.0, 0.4, -1.1):
        pose = yawed(ALONG_X, yaw)
        projective = umbra.OccupancyMap(0.05)
        projective.auto_prune = False
        projective.insert_depth_image(scene(), CAMERA, pose)
        points = umbra.back_project(scene(), CAMERA, pose)
        discrete = umbra.OccupancyMap(0.05)
        discrete.auto_prune = False
        discrete.insert(points, pose[:3, 3], integrator="discrete")
        want = occupied_keys(discrete)
        assert len(want) > 500
        assert occupied_keys(projective) == want, f"yaw {yaw}"
        # Free space differs from the rays' (it comes from the image), but not much.
        free_projective = projective.statistics().free_voxels
        free_discrete = discrete.statistics().free_voxels
        assert 0.8 * free_discrete < free_projective < 1.2 * free_discrete


@pytest.mark.parametrize("integrator", ["simple", "discrete", "fast"])
def test_other_integrators_insert_the_back_projected_points(integrator):
    pose = yawed(ALONG_X, 0.7)
    colors = np.random.default_rng(5).integers(0, 256, size=(HEIGHT, WIDTH, 3), dtype=np.uint8)
    image = umbra.OccupancyMap(0.05, color=True)
    image.insert_depth_image(scene(), CAMERA, pose, colors, integrator=integrator, max_range=2.0)
    points, pixels = umbra.back_project(scene(), CAMERA, pose, return_pixels=True)
    cloud = umbra.OccupancyMap(0.05, color=True)
    cloud.insert(points, pose[:3, 3], colors.reshape(-1, 3)[pixels], integrator=integrator, max_range=2.0)
    leaves_equal(image, cloud)
    assert image.leaves()["has_color"].any()


def test_projective_colors_and_options():
    pose = yawed(ALONG_X, 0.2)
    colors = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    colors[..., 0] = np.arange(WIDTH)[None, :] * 4
    colors[..., 1] = np.arange(HEIGHT)[:, None] * 5
    m = umbra.OccupancyMap(0.05, color=True)
    m.insert_depth_image(scene(), CAMERA, pose, colors)
    # Occupied voxels carry the colors of their points, as the discrete integrator gives them.
    points, pixels = umbra.back_project(scene(), CAMERA, pose, return_pixels=True)
    discrete = umbra.OccupancyMap(0.05, color=True)
    discrete.insert(points, pose[:3, 3], colors.reshape(-1, 3)[pixels], integrator="discrete")
    nodes, want = m.nodes(points), discrete.nodes(points)
    assert nodes["has_color"].all()
    np.testing.assert_array_equal(nodes["color"], want["color"])

    # max_range and surface_margin reach the integrator: less free space with each.
    free = m.statistics().free_voxels
    for options in ({"max_range": 1.0}, {"surface_margin": 8.0}):
        other = umbra.OccupancyMap(0.05)
        other.insert_depth_image(scene(), CAMERA, pose, **options)
        assert other.statistics().free_voxels < 0.9 * free, options


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda m: m.insert_depth_image(np.zeros((4, 4), np.int32), CAMERA, ALONG_X), TypeError,
         "depth must hold uint16 raw depths (with depth_scale) or float metres, got dtype int32"),
        (lambda m: m.insert_depth_image("wall", CAMERA, ALONG_X), TypeError, "depth must hold uint16 raw depths"),
        (lambda m: m.insert_depth_image(np.zeros((4, 4, 1), np.float32), CAMERA, ALONG_X), ValueError,
         "depth must be an image of shape (H, W), got shape (4, 4, 1)"),
        (lambda m: m.insert_depth_image(np.zeros((0, 4), np.float32), CAMERA, ALONG_X), ValueError,
         "depth has no pixels: shape (0, 4)"),
        (lambda m: m.insert_depth_image(wall(dtype=np.uint16), CAMERA, ALONG_X), ValueError,
         "depth_scale is needed for uint16 depth: raw units per metre (1000 for millimetres, 5000 for TUM RGB-D)"),
        (lambda m: m.insert_depth_image(wall(dtype=np.uint16), CAMERA, ALONG_X, depth_scale=0.0), ValueError,
         "depth_scale must be finite and > 0 (raw units per metre), got 0.000000"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, depth_scale=1000.0), ValueError,
         "depth_scale is for uint16 raw depths; depth holds float32 metres already"),
        (lambda m: m.insert_depth_image(wall(), (50.0, 50.0, 31.5), ALONG_X), ValueError,
         "camera must be a PinholeCamera or four numbers (fx, fy, cx, cy), got shape (3,)"),
        (lambda m: m.insert_depth_image(wall(), (50.0, -1.0, 31.5, 23.5), ALONG_X), ValueError,
         "camera: PinholeCamera: fx and fy must be finite and > 0"),
        (lambda m: m.insert_depth_image(wall(), "kinect", ALONG_X), TypeError, "camera must be an array of numbers"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, np.eye(3)), ValueError,
         "pose must be an array of shape (4, 4) or (3, 4), got shape (3, 3)"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X + np.diag([0, 0, 0, 1.0])), ValueError,
         "pose's last row must be (0, 0, 0, 1), got (0.0, 0.0, 0.0, 2.0)"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X * np.array([[2.0], [2.0], [2.0], [1.0]])), ValueError,
         "the camera pose must be a rotation and a translation"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, np.zeros((HEIGHT, WIDTH, 3), np.uint8)), ValueError,
         "colors given, but the map was made without color (color=False)"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, integrator="rays"), ValueError, "rays"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, surface_margin=-1.0), ValueError,
         "surface_margin must be finite and >= 0, got -1"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, threads=-1), ValueError, "threads must be >= 0"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X + np.array([[0, 0, 0, 1e9]] + [[0] * 4] * 3)),
         IndexError, "outside the map"),
    ],
)
def test_insertion_errors_name_the_argument(call, error, message):
    m = umbra.OccupancyMap(0.1)
    with pytest.raises(error) as raised:
        call(m)
    assert message in str(raised.value)
    assert m.node_counts().total == 1, "the map is unchanged after an error"


def test_color_errors_name_the_argument():
    m = umbra.OccupancyMap(0.1, color=True)
    with pytest.raises(ValueError, match=r"colors must be an array of shape \(48, 64, 3\), one color per pixel, "
                                         r"got shape \(48, 63, 3\)"):
        m.insert_depth_image(wall(), CAMERA, ALONG_X, np.zeros((HEIGHT, WIDTH - 1, 3), np.uint8))
    with pytest.raises(TypeError, match="colors must hold integers"):
        m.insert_depth_image(wall(), CAMERA, ALONG_X, np.zeros((HEIGHT, WIDTH, 3)))
    too_bright = np.zeros((HEIGHT, WIDTH, 3), np.int64)
    too_bright[1, 2, 0] = 300
    with pytest.raises(ValueError, match=r"colors\[66\] holds 300, outside \[0, 255\]"):  # pixel v * W + u
        m.insert_depth_image(wall(), CAMERA, ALONG_X, too_bright)
    assert m.node_counts().total == 1, "the map is unchanged after an error"


def test_non_contiguous_arrays_are_read_as_their_values():
    """Views with strides (every other column, a transposed image, Fortran order) give the map of their copies."""
    wide = np.repeat(scene(), 2, axis=1)
    wide[:, 1::2] = 7.0  # the columns the view skips: a reader ignoring strides would see them
    colors = np.random.default_rng(9).integers(0, 256, size=(HEIGHT, 2 * WIDTH, 3), dtype=np.uint8)
    pose = yawed(ALONG_X, 0.5)
    views = [
        (wide[:, ::2], colors[:, ::2]),
        (np.asfortranarray(scene()), np.asfortranarray(colors[:, ::2])),
        (np.ascontiguousarray(scene().T).T, colors[:, ::2].copy()),
    ]
    reference = umbra.OccupancyMap(0.05, color=True)
    reference.insert_depth_image(scene(), CAMERA, pose, colors[:, ::2].copy())
    for depth, color_view in views:
        assert not depth.flags.c_contiguous
        m = umbra.OccupancyMap(0.05, color=True)
        m.insert_depth_image(depth, CAMERA, pose, color_view)
        leaves_equal(m, reference)
        np.testing.assert_array_equal(umbra.back_project(depth, CAMERA, pose), umbra.back_project(scene(), CAMERA, pose))
    # A strided pose (every other column of a wider array) is the same pose.
    wide_pose = np.repeat(pose, 2, axis=1)
    m = umbra.OccupancyMap(0.05)
    m.insert_depth_image(scene(), CAMERA, wide_pose[:, ::2])
    plain = umbra.OccupancyMap(0.05)
    plain.insert_depth_image(scene(), CAMERA, pose)
    leaves_equal(m, plain)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda m: m.insert_depth_image(wall().astype(np.complex64), CAMERA, ALONG_X),
         "depth must hold uint16 raw depths (with depth_scale) or float metres, got dtype complex64"),
        (lambda m: m.insert_depth_image(wall(), np.array([50, 50, 31.5, 23.5], np.complex128), ALONG_X),
         "camera must hold real numbers, got dtype complex128"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X.astype(np.complex128)),
         "pose must hold real numbers, got dtype complex128"),
        (lambda m: m.insert_depth_image(wall(), CAMERA, ALONG_X, np.zeros((HEIGHT, WIDTH, 3), np.complex64)),
         "colors must hold integers"),
        (lambda m: umbra.back_project(wall().astype(np.complex128), CAMERA), "got dtype complex128"),
    ],
)
def test_complex_arrays_are_refused_not_converted(call, message):
    m = umbra.OccupancyMap(0.1, color=True)
    with pytest.raises(TypeError) as raised:
        call(m)
    assert message in str(raised.value)
    assert m.node_counts().total == 1, "the map is unchanged after an error"


def test_back_project_errors_name_the_argument():
    with pytest.raises(ValueError, match="depth_scale is needed for uint16 depth"):
        umbra.back_project(wall(dtype=np.uint16), CAMERA)
    with pytest.raises(ValueError, match=r"pose must be an array of shape \(4, 4\) or \(3, 4\)"):
        umbra.back_project(wall(), CAMERA, np.zeros(3))
    with pytest.raises(ValueError, match="camera must be a PinholeCamera or four numbers"):
        umbra.back_project(wall(), [1.0, 2.0])


def test_insertion_releases_the_gil():
    """With thread switches only where a call releases the GIL, a waiting thread runs inside insert_depth_image."""
    m = umbra.OccupancyMap(0.02)
    big = np.full((480, 640), 3.0, dtype=np.float32)
    camera = umbra.PinholeCamera(525.0, 525.0, 319.5, 239.5)
    state = {"inside": False, "seen_inside": False}
    go = threading.Event()

    def watcher():
        go.wait()
        state["seen_inside"] = state["inside"]

    old_interval = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    try:
        for attempt in range(5):  # the watcher may lose the race for the released GIL; it cannot win it otherwise
            go.clear()
            t = threading.Thread(target=watcher)
            t.start()
            state["inside"] = True
            go.set()
            m.insert_depth_image(big, camera, yawed(ALONG_X, 0.3 * attempt), threads=1)
            state["inside"] = False
            t.join()
            if state["seen_inside"]:
                break
    finally:
        sys.setswitchinterval(old_interval)
    assert state["seen_inside"], "no thread ran while insert_depth_image() worked: it holds the GIL"
    assert m.count(pred.occupied() & pred.leaf()) > 0
