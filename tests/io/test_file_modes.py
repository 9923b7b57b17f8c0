"""Files crfmap writes get 0666 minus the umask (folders 0777 minus it), as map_saver's do; a replaced file keeps its mode."""
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from crfmap.grid import OccupancyGrid
from crfmap.io.atomic import atomic_path, current_umask
from crfmap.io.bag_writer import write_bag
from crfmap.io.map_server import save_map
from crfmap.io.npy_grid import save_npy

from test_bag_reader import make_recording  # noqa: E402 (tests/io is on pytest's pythonpath)


@pytest.fixture(params=[0o022, 0o002])
def umask(request):
    old = os.umask(request.param)
    try:
        yield request.param
    finally:
        os.umask(old)


def mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_current_umask_reads_the_process_umask(umask):
    assert current_umask() == umask


def test_maps_and_npy_get_0666_minus_umask(tmp_path, umask):
    grid = OccupancyGrid(np.array([[0.0, 1.0], [0.5, 0.3]]), resolution=0.05)
    save_map(grid, tmp_path / "m.yaml")
    save_npy(grid, tmp_path / "g.npy")
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == ["g.npy", "g.npy.yaml", "m.pgm", "m.yaml"]
    for name in written:
        assert mode(tmp_path / name) == 0o666 & ~umask, name


def test_a_replaced_file_keeps_its_mode(tmp_path, umask):
    target = tmp_path / "kept.txt"
    target.write_text("old")
    os.chmod(target, 0o640)
    with atomic_path(target) as tmp:
        Path(tmp).write_text("new")
    assert target.read_text() == "new" and mode(target) == 0o640


@pytest.mark.parametrize("fmt, name", [("ros2", "bag"), ("ros1", "b.bag")])
def test_bags_get_the_umask_modes(tmp_path, umask, fmt, name):
    write_bag(make_recording(), tmp_path / name, fmt=fmt)
    path = tmp_path / name
    if fmt == "ros2":
        assert mode(path) == 0o777 & ~umask
        for item in path.iterdir():
            assert mode(item) == 0o666 & ~umask, item.name
    else:
        assert mode(path) == 0o666 & ~umask
