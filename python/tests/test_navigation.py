"""OccupancyMap.project (the 2D navigation grid) against brute force: the
states of every voxel centre of the band, read with OccupancyMap.states, merged
per cell by the rules written out here; and NavigationGrid.save's files read
back as map_server reads them."""

import numpy as np
import pytest

import umbra

RULES = ("all_known", "any_free")


def brute_force(office, z_min, z_max, depth, rule, x0, y0, width, height):
    """Cell values over the block of cells (x0, y0) .. (x0 + width, y0 + height) (cell keys), and whether
    each cell's band holds a known voxel."""
    res = office.resolution
    k = 2**depth
    rows = np.arange(np.floor(z_min / res), np.floor(z_max / res) + 1)  # the band's voxel rows (keys - offset)
    xs = (np.arange(x0 * k, (x0 + width) * k) + 0.5) * res
    ys = (np.arange(y0 * k, (y0 + height) * k) + 0.5) * res
    zs = (rows + 0.5) * res
    grid = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1)  # (X, Y, Z, 3)
    states = office.states(grid)  # (X, Y, Z)
    per_cell = states.reshape(width, k, height, k, len(zs)).transpose(2, 0, 1, 3, 4).reshape(height, width, -1)
    occupied = (per_cell == umbra.OCCUPIED).any(axis=2)
    some_free = (per_cell == umbra.FREE).any(axis=2)
    all_free = (per_cell == umbra.FREE).all(axis=2)
    free = all_free if rule == "all_known" else some_free
    cells = np.where(occupied, 100, np.where(free, 0, -1)).astype(np.int8)
    return cells, occupied | some_free


@pytest.mark.parametrize("depth", [0, 1])
@pytest.mark.parametrize("rule", RULES)
def test_project_equals_brute_force(office, depth, rule):
    z_min, z_max = 0.15, 1.25  # inside voxel rows 1 and 12: no bound on a face
    grid = office.project(z_min, z_max, depth=depth, rule=rule)
    cell = office.resolution * 2**depth
    assert grid.resolution == pytest.approx(cell)
    assert grid.cells.shape == (grid.height, grid.width) and grid.cells.dtype == np.int8
    assert not grid.cells.flags.writeable
    x0, y0 = (round(c / cell) for c in grid.origin)
    # One ring of cells around the grid too: nothing known there.
    want, known = brute_force(office, z_min, z_max, depth, rule, x0 - 1, y0 - 1, grid.width + 2, grid.height + 2)
    np.testing.assert_array_equal(grid.cells, want[1:-1, 1:-1])
    assert not known[0, :].any() and not known[-1, :].any() and not known[:, 0].any() and not known[:, -1].any()
    assert known[1, 1:-1].any() and known[-2, 1:-1].any() and known[1:-1, 1].any() and known[1:-1, -2].any()
    for value in (-1, 0, 100):
        assert (grid.cells == value).sum() > 10, f"no {value} cells: the comparison proves little"


def test_save_writes_what_map_server_reads(office, tmp_path):
    grid = office.project(0.15, 1.25, rule="any_free")
    yaml_path = grid.save(tmp_path / "office.pgm")
    assert yaml_path == str(tmp_path / "office.yaml")
    fields = dict(line.split(": ", 1) for line in (tmp_path / "office.yaml").read_text().splitlines())
    assert fields["image"] == '"office.pgm"' and fields["mode"] == "trinary" and fields["negate"] == "0"
    assert float(fields["resolution"]) == pytest.approx(grid.resolution)
    origin = [float(v) for v in fields["origin"].strip("[]").split(",")]
    assert origin == pytest.approx([*grid.origin, 0.0])
    data = (tmp_path / "office.pgm").read_bytes()
    header = f"P5\n# CREATOR: umbra project, {fields['resolution']} m/pix\n{grid.width} {grid.height}\n255\n".encode()
    assert data.startswith(header)
    pixels = np.frombuffer(data[len(header) :], dtype=np.uint8).reshape(grid.height, grid.width)[::-1]
    occupancy = (255.0 - pixels) / 255.0
    read = np.where(
        occupancy > float(fields["occupied_thresh"]), 100, np.where(occupancy < float(fields["free_thresh"]), 0, -1)
    )
    np.testing.assert_array_equal(read, grid.cells)


def test_bad_arguments_raise_naming_the_value(office, tmp_path):
    with pytest.raises(ValueError, match="z_min must be below z_max, got z_min 1 and z_max 1"):
        office.project(1.0, 1.0)
    with pytest.raises(ValueError, match="unknown projection rule 'most_free'"):
        office.project(0.0, 1.0, rule="most_free")
    with pytest.raises(ValueError, match="depth must be at most the map's depth_levels 16, got 17"):
        office.project(0.0, 1.0, depth=17)
    with pytest.raises(IndexError, match="lies outside the map"):
        office.project(1e6, 1e6 + 1)
    empty = office.project(50.0, 51.0)
    assert empty.width == 0 and empty.height == 0 and empty.cells.shape == (0, 0)
    with pytest.raises(ValueError, match="empty"):
        empty.save(tmp_path / "empty.pgm")
    grid = office.project(0.15, 1.25)
    with pytest.raises(ValueError, match=r"must be a \.pgm file"):
        grid.save(tmp_path / "office.png")
    with pytest.raises(OSError, match="missing"):
        grid.save(tmp_path / "missing" / "office.pgm")
