"""Files from Python: umbra.load / OccupancyMap.save and umbra.read_scans, and their errors.

References: round trips through each format (leaf for leaf), the `umbra
info` program, files written here by hand (xyz, PLY) with known contents,
and the real data in ../shared/data where present.
"""

import json
import os

import numpy as np
import pytest

import umbra


def test_umb_round_trip_is_exact(office, tmp_path):
    path = tmp_path / "map.umb"
    office.save(str(path))  # str and os.PathLike both work
    loaded = umbra.load(path)
    a, b = office.leaves(), loaded.leaves()
    for field in ("key", "depth", "log_odds"):
        np.testing.assert_array_equal(a[field], b[field])
    assert loaded.sensor_model == office.sensor_model
    assert loaded.resolution == office.resolution


@pytest.mark.parametrize("extension", ["bt", "ot"])
def test_octomap_files_keep_the_states(office, tmp_path, extension):
    path = tmp_path / f"map.{extension}"
    office.save(path)
    loaded = umbra.load(path, sensor_model=umbra.SensorModel(p_hit=0.8))
    assert loaded.sensor_model.p_hit == 0.8
    points = np.random.default_rng(7).uniform([0, 0, 0], [20, 12, 3], size=(5000, 3))
    np.testing.assert_array_equal(loaded.states(points), office.states(points))


def test_saved_file_matches_umbra_info(office, office_file, cli):
    info = json.loads(cli("info", office_file, "--json"))
    stats = office.statistics()
    assert info["occupied_voxels"] == stats.occupied_voxels
    assert info["free_voxels"] == stats.free_voxels
    assert info["nodes"] == office.node_counts().total


def test_load_errors(tmp_path):
    with pytest.raises(FileNotFoundError) as missing:
        umbra.load(tmp_path / "missing.umb")
    assert missing.value.filename == str(tmp_path / "missing.umb")

    unknown = tmp_path / "map.foo"
    unknown.write_bytes(b"x")
    with pytest.raises(ValueError, match=r"unknown map file extension '\.foo'"):
        umbra.load(unknown)

    corrupt = tmp_path / "corrupt.umb"
    corrupt.write_bytes(b"NOTAMAP!" + bytes(100))
    with pytest.raises(umbra.FormatError) as error:
        umbra.load(corrupt)
    assert isinstance(error.value, ValueError)
    assert str(corrupt) in str(error.value) and "bad magic" in str(error.value)
    assert type(error.value).__module__ == "umbra"

    bt = tmp_path / "bad.bt"
    bt.write_text("# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n")
    with pytest.raises(umbra.FormatError, match="bad.bt"):
        umbra.load(bt)


def test_save_errors(office, tmp_path):
    with pytest.raises(OSError):
        office.save(tmp_path / "no" / "such" / "folder" / "map.umb")
    with pytest.raises(ValueError, match="unknown map file extension"):
        office.save(tmp_path / "map.txt")
    deep = umbra.OccupancyMap(0.1, depth_levels=12)
    with pytest.raises(ValueError):
        deep.save(tmp_path / "deep.bt")
    assert not (tmp_path / "deep.bt").exists()


# --- point clouds ---------------------------------------------------------------------------------------


def test_read_xyz(tmp_path):
    points = np.random.default_rng(3).uniform(-5, 5, size=(1000, 3)).astype(np.float32)
    path = tmp_path / "cloud.xyz"
    np.savetxt(path, points, fmt="%.9g")
    reader = umbra.read_scans(path, origin=(1, 2, 3))
    scans = list(reader)
    assert len(scans) == 1
    origin, read, colors = scans[0]
    assert origin.dtype == np.float32 and read.dtype == np.float32
    np.testing.assert_array_equal(origin, [1, 2, 3])
    np.testing.assert_array_equal(read, points)
    assert colors is None
    assert reader.progress == 1.0
    assert "cloud.xyz" in reader.name
    assert reader.stamp is None  # .xyz files carry no time


def test_tum_frames_carry_their_time(shared_data):
    # TUM names each depth image by its time: the reader's stamp, for decay.
    folder = shared_data / "tum_fr2_pioneer_slam2"
    association = next(folder.glob("*assoc*.txt"))
    rows = [line.split() for line in association.read_text().splitlines() if line and not line.startswith("#")]
    # The first row whose images are on disk (the reader skips the others).
    first_depth = next(r[1] for r in rows if (folder / r[1]).exists() and (folder / r[0]).exists())
    reader = umbra.read_scans(folder)
    next(reader)
    assert reader.stamp == pytest.approx(float(first_depth[len("depth/"):-len(".png")]), abs=1e-6)


def test_read_colored_ply(tmp_path):
    rng = np.random.default_rng(4)
    points = rng.uniform(-5, 5, size=(50, 3)).astype(np.float32)
    colors = rng.integers(0, 256, size=(50, 3), dtype=np.uint8)
    path = tmp_path / "cloud.ply"
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 50\nproperty float x\nproperty float y\nproperty float z\n")
        f.write("property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
        for p, c in zip(points, colors):
            f.write("%.9g %.9g %.9g %d %d %d\n" % (*p, *c))
    (origin, read, read_colors), = umbra.read_scans(str(path))
    np.testing.assert_array_equal(read, points)
    np.testing.assert_array_equal(read_colors, colors)
    # Straight into a colored map.
    m = umbra.OccupancyMap(0.1, color=True)
    m.insert(read, origin, read_colors)
    assert m.nodes(read)["has_color"].all()


def test_read_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        umbra.read_scans(tmp_path / "missing.xyz")
    bad = tmp_path / "bad.xyz"
    bad.write_text("1 2 3\n4 five 6\n")
    with pytest.raises(umbra.FormatError, match=r"bad\.xyz:2"):
        list(umbra.read_scans(bad))
    with pytest.raises(ValueError, match="unknown"):
        umbra.read_scans(bad, format="nosuchformat")
    (tmp_path / "cloud.abc").write_text("1 2 3\n")
    with pytest.raises(ValueError):
        umbra.read_scans(tmp_path / "cloud.abc")
    with pytest.raises(TypeError):
        umbra.read_scans(bad, color=True)  # not a reader option


def test_read_the_3dtk_graph(shared_data):
    graph = shared_data / "3dtk" / "3dtk_registered.graph"
    if not graph.exists():
        pytest.skip(f"{graph} is absent")
    reader = umbra.read_scans(graph)
    assert reader.scan_count == 3
    sizes = [len(points) for _, points, _ in reader]
    assert sizes == [77690, 77910, 77584]  # the data set described in the README, "Data for the examples"


def test_read_tum_frames(shared_data):
    folder = shared_data / "tum_fr2_pioneer_slam2"
    if not folder.exists():
        pytest.skip(f"{folder} is absent")
    reader = umbra.read_scans(folder, camera=umbra.DepthCamera())
    origin, points, colors = next(iter(reader))
    assert colors is not None and colors.shape == points.shape and colors.dtype == np.uint8
    assert np.isfinite(points).all()
    assert reader.scan_count in (0, 10)
