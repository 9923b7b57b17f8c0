"""crfmap.io.npy_grid: exact .npy grids with their sidecar YAML, and bad .npy files named in the error."""
import os

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.grid_files import load_grid
from crfmap.io.npy_grid import load_npy, npy_sidecar_path, save_npy


def test_npy_round_trip_is_exact(tmp_path):
    p = np.random.default_rng(4).random((7, 9))
    p[0, :3] = 0.0, 1.0, 0.5  # the extremes and unknown
    grid = OccupancyGrid(p, resolution=0.05, origin=(0.1, -0.2, 1e-9), frame_id="odom")
    save_npy(grid, tmp_path / "g.npy")
    assert sorted(os.listdir(tmp_path)) == ["g.npy", "g.npy.yaml"]
    back = load_npy(tmp_path / "g.npy")
    assert np.array_equal(back.probability, grid.probability)
    assert (back.resolution, back.origin, back.frame_id) == (grid.resolution, grid.origin, "odom")
    assert np.array_equal(load_grid(tmp_path / "g.npy.yaml").probability, grid.probability)


def test_npy_without_sidecar_gets_unit_metadata(tmp_path):
    np.save(tmp_path / "g.npy", np.full((2, 3), 0.25, dtype=np.float32))
    grid = load_npy(tmp_path / "g.npy")
    assert grid.shape == (2, 3) and grid.resolution == 1.0 and grid.origin == (0.0, 0.0, 0.0)
    assert grid.frame_id == "map"


@pytest.mark.parametrize("array, problem", [
    (np.full((2, 2, 2), 0.5), "2-D"),
    (np.array([[0, 1], [1, 0]]), "expected float probabilities"),
    (np.array([[0.5, np.nan]]), "NaN"),
    (np.array([[0.5, np.inf]]), "infinite"),
    (np.array([[0.5, 1.5]]), "[0, 1]"),
    (np.zeros((0, 3)), "empty grid"),
])
def test_bad_npy_is_an_input_error(tmp_path, array, problem):
    np.save(tmp_path / "g.npy", array)
    with pytest.raises(InputError) as err:
        load_npy(tmp_path / "g.npy")
    assert "g.npy" in str(err.value) and problem in str(err.value)


def test_unreadable_npy_and_sidecar(tmp_path):
    (tmp_path / "a.npy").write_bytes(b"not numpy")
    with pytest.raises(InputError, match="a.npy"):
        load_npy(tmp_path / "a.npy")
    np.save(tmp_path / "b.npy", np.array([["x", "y"]], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="b.npy: not a plain .npy array"):
        load_npy(tmp_path / "b.npy")
    with pytest.raises(InputError, match="c.npy: .npy grid file not found"):
        load_npy(tmp_path / "c.npy")
    np.save(tmp_path / "d.npy", np.full((2, 2), 0.5))
    (tmp_path / "d.npy.yaml").write_text("resolution: abc\n")
    with pytest.raises(InputError, match="d.npy.yaml: key 'resolution' must be a number"):
        load_npy(tmp_path / "d.npy")


def test_sidecar_sits_beside_the_array_and_does_not_clash_with_a_map_yaml(tmp_path):
    assert npy_sidecar_path(tmp_path / "map.npy") == tmp_path / "map.npy.yaml"
    with pytest.raises(InputError, match="g.txt: an .npy grid file must end in .npy"):
        save_npy(OccupancyGrid(np.zeros((2, 2))), tmp_path / "g.txt")
    assert os.listdir(tmp_path) == []
