"""Quirks of real logs and concurrent use that are not refusals: the result must be right.

- CARMEN no-returns: values at or beyond the laser's maximum range, varying within a file;
- a log whose longest reading is a real wall keeps it;
- /tf quaternions: tf2's rule (refuse |q|^2 more than 0.01 from 1, normalise within it);
- two writers of one .npy grid: a reader sees one writer's array with that writer's sidecar.
"""
import math
import multiprocessing
from types import SimpleNamespace

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.frames import quaternion_to_yaw
from crfmap.io.carmen import read_carmen
from crfmap.mapping.builder import build_grid
from fixtures import carmen_text


def _log(tmp_path, readings, params=""):
    """Scans of 9 beams: the given readings, spread over scans, the robot at the origin."""
    lines = [params] if params else []
    for k, r in enumerate(readings):
        ranges = " ".join(r)
        lines.append(f"FLASER 9 {ranges} 0 0 0 0 0 0 {k + 1.0} nohost {k + 1.0}")
    path = tmp_path / "q.log"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_sick_codes_that_vary_within_a_file_are_all_no_returns(tmp_path):
    mixed = [["81.87", "2.00", "81.89", "3.00", "81.91", "2.50", "81.83", "1.00", "81.90"]] * 3
    rec = read_carmen(_log(tmp_path, mixed))
    r = rec.scans.ranges
    assert np.isposinf(r[:, [0, 2, 4, 6, 8]]).all() and np.isfinite(r[:, [1, 3, 5, 7]]).all()
    grid = build_grid(rec.scans, 0.1)
    # no 82 m spokes: the map spans the 3 m of real returns (plus padding), not 160 m
    assert grid.width * grid.resolution < 10 and grid.height * grid.resolution < 10


def test_param_max_range_wins_and_readings_beyond_it_are_no_returns(tmp_path):
    scans = [["7.99", "8.00", "8.50", "3.00", "3.00", "3.00", "3.00", "3.00", "3.00"]]
    rec = read_carmen(_log(tmp_path, scans, "PARAM robot_front_laser_max 8.0 nohost 0"))
    assert rec.scans.ranges[0, 0] == np.float32(7.99) and np.isposinf(rec.scans.ranges[0, 1:3]).all()
    assert rec.meta["max_range_source"] == "PARAM robot_front_laser_max" and rec.scans.range_max == 8.0


def test_the_longest_reading_of_a_real_wall_stays_a_hit(tmp_path):
    # a far wall seen a few times at its closest point among spread readings: not a spike
    rng = np.random.default_rng(0)
    scans = [[f"{v:.2f}" for v in rng.uniform(2.0, 11.9, 9)] for _ in range(40)]
    scans[3][4] = scans[9][4] = scans[20][4] = "12.00"
    rec = read_carmen(_log(tmp_path, scans))
    assert np.isfinite(rec.scans.ranges).all() and rec.meta["no_return_code"] is None


def test_a_spike_at_the_maximum_is_a_no_return_code(tmp_path):
    rng = np.random.default_rng(1)
    scans = [[f"{v:.2f}" for v in rng.uniform(1.0, 40.0, 9)] for _ in range(40)]
    for k in range(40):
        scans[k][k % 9] = "50.00"
    rec = read_carmen(_log(tmp_path, scans))
    assert rec.meta["no_return_code"] == 50.0 and np.isposinf(rec.scans.ranges).sum() == 40


@pytest.mark.parametrize("scale", [0.996, 1.0, 1.004])
def test_quaternions_near_unit_length_are_normalised(scale):
    yaw = 1.1
    q = SimpleNamespace(x=0.0, y=0.0, z=scale * math.sin(yaw / 2), w=scale * math.cos(yaw / 2))
    assert quaternion_to_yaw(q) == pytest.approx(yaw, abs=1e-12)


@pytest.mark.parametrize("q", [(0, 0, 0, 0), (0, 0, 0.5, 0.5), (0, 0, 2.0, 1.0), (0, 0, math.nan, 1.0)])
def test_quaternions_that_are_not_rotations_are_refused(q):
    with pytest.raises(InputError, match="not a rotation"):
        quaternion_to_yaw(SimpleNamespace(x=q[0], y=q[1], z=q[2], w=q[3]), "bag: /tf message 3")


def _writer(path, value, rounds):
    from crfmap.grid import OccupancyGrid
    from crfmap.io.npy_grid import save_npy

    for _ in range(rounds):
        save_npy(OccupancyGrid(np.full((40, 40), value), resolution=value), path)


def test_concurrent_writers_never_mix_array_and_sidecar(tmp_path):
    from crfmap.io.npy_grid import load_npy

    path = tmp_path / "g.npy"
    _writer(path, 0.25, 1)
    ctx = multiprocessing.get_context("fork")
    writers = [ctx.Process(target=_writer, args=(path, v, 150)) for v in (0.25, 0.75)]
    for w in writers:
        w.start()
    mixed = reads = 0
    while any(w.is_alive() for w in writers) or reads < 50:
        g = load_npy(path)
        reads += 1
        mixed += g.resolution != g.probability[0, 0]
    for w in writers:
        w.join()
    assert mixed == 0 and reads >= 50
    assert not list(tmp_path.glob(".*tmp"))


def test_fixture_log_builds(tmp_path):
    (tmp_path / "ok.log").write_text(carmen_text())
    assert read_carmen(tmp_path / "ok.log").scans.ranges.shape == (4, 9)
