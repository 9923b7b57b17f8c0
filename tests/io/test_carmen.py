"""crfmap.io.carmen: CARMEN logs (FLASER / ODOM / PARAM) into a Recording."""
import gzip
import math

import numpy as np
import pytest

from crfmap.data import data_file, have_data
from crfmap.mapping.builder import count_hits
from crfmap.io.carmen import read_carmen
from crfmap.errors import InputError

INTEL = "carmen/intel-corrected.log.gz"
ACES = "carmen/aces-corrected.log.gz"

LOG = """# message formats defined: PARAM SYNC ODOM FLASER
PARAM robot_frontlaser_offset 0.0 nohost 0
PARAM laser_unit metres nohost 0
PARAM robot_front_laser_max 30.0 nohost 0
ODOM 0 0 0 0 0 0 0.5 pippo 0.5
NEFF 15
FLASER 5 1.0 2.5 30.0 0.75 30.0 1.0 2.0 0.5 1.0 2.0 0.5 1.25 pippo 1.26
ODOM 0.1 0.0 0.05 0.2 0.1 0 1.5 pippo 1.5

FLASER 5 30.0 2.0 3.0 4.0 5.0 1.5 2.0 -3.0 1.5 2.0 -3.0 2.25 pippo 2.26
"""


@pytest.fixture
def log_file(tmp_path):
    path = tmp_path / "tiny.log"
    path.write_text(LOG)
    return path


def test_flaser_odom_param_parsed(log_file):
    rec = read_carmen(log_file)
    s = rec.scans
    assert s.ranges.dtype == np.float32 and s.ranges.shape == (2, 5)
    # 30.0 is the laser's maximum range (PARAM robot_front_laser_max): no return, +inf (REP 117).
    np.testing.assert_array_equal(s.ranges[0], np.float32([1.0, 2.5, np.inf, 0.75, np.inf]))
    np.testing.assert_array_equal(s.ranges[1], np.float32([np.inf, 2.0, 3.0, 4.0, 5.0]))
    assert s.range_max == 30.0 and rec.meta["no_return_code"] == 30.0 and rec.meta["no_return_readings"] == 3
    # Beams from the robot's right (-90 deg) to its left (+90 deg), counter-clockwise.
    np.testing.assert_allclose(s.angles, np.deg2rad([-90, -45, 0, 45, 90]))
    np.testing.assert_array_equal(s.laser_poses, [[1.0, 2.0, 0.5], [1.5, 2.0, -3.0]])
    np.testing.assert_array_equal(s.stamps, [1.25, 2.25])
    assert s.frame_id == "map" and rec.laser_mount == (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(rec.true_poses.poses, s.laser_poses)
    assert rec.true_poses.frame_id == "map"
    o = rec.odometry
    assert o.frame_id == "odom" and o.child_frame_id == "base_link"
    np.testing.assert_array_equal(o.stamps, [0.5, 1.5])
    np.testing.assert_array_equal(o.poses, [[0, 0, 0], [0.1, 0.0, 0.05]])
    np.testing.assert_array_equal(o.twists, [[0, 0], [0.2, 0.1]])
    assert rec.meta["max_range_source"] == "PARAM robot_front_laser_max"
    assert rec.meta["params"] == {"robot_frontlaser_offset": "0.0", "laser_unit": "metres",
                                  "robot_front_laser_max": "30.0"}
    assert rec.meta["skipped_messages"] == {"NEFF": 1}


def test_gzip_and_plain_agree(log_file, tmp_path):
    gz = tmp_path / "tiny.log.gz"
    gz.write_bytes(gzip.compress(LOG.encode()))
    a, b = read_carmen(log_file), read_carmen(gz)
    np.testing.assert_array_equal(a.scans.ranges, b.scans.ranges)
    np.testing.assert_array_equal(a.scans.laser_poses, b.scans.laser_poses)


def test_no_return_choices(log_file):
    kept = read_carmen(log_file, no_return=None)
    assert np.isfinite(kept.scans.ranges).all() and kept.scans.ranges.max() == 30.0
    five = read_carmen(log_file, no_return=5.0)
    # at or beyond the maximum range: no return (30.0 too, never a hit)
    assert np.isposinf(five.scans.ranges[1, 4]) and np.isposinf(five.scans.ranges[0, 2])
    assert five.scans.ranges[1, 3] == 4.0
    with pytest.raises(InputError, match="no_return"):
        read_carmen(log_file, no_return="max")


def test_a_single_largest_reading_is_not_a_code(tmp_path):
    path = tmp_path / "once.log"
    path.write_text(LOG.replace("PARAM robot_front_laser_max 30.0 nohost 0\n", "").replace("30.0", "1.5"))  # 5.0 once
    rec = read_carmen(path)
    assert rec.meta["no_return_code"] is None and np.isfinite(rec.scans.ranges).all()
    assert rec.scans.range_max == 5.0


@pytest.mark.parametrize("bad_line, problem", [
    ("FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.0 host", "line 3: FLASER with 5 readings needs 16 fields, found 15"),
    ("FLASER 5 1 2 x 4 5 0 0 0 0 0 0 1.0 host 1.0", "line 3: FLASER value 'x' is not a number"),
    ("FLASER 4 1 2 3 4 0 0 0 0 0 0 1.0 host 1.0", "line 3: FLASER with 4 readings, earlier lines have 5"),
    ("FLASER five 1 2", "line 3: FLASER needs the number of readings"),
    ("FLASER 5 1 2 3 4 5 nan 0 0 0 0 0 1.0 host 1.0", "line 3: FLASER pose is not finite"),
    ("FLASER 5 1 -2 3 4 5 0 0 0 0 0 0 1.0 host 1.0", "line 3: negative range"),
    ("ODOM 1 2 3", "line 3: ODOM needs 10 fields, found 4"),
    ("ODOM 1 2 3 0 0 0 z host 1", "line 3: ODOM value 'z' is not a number"),
    ("PARAM lonely", "line 3: PARAM needs a name and a value"),
])
def test_malformed_lines_name_file_and_line(tmp_path, bad_line, problem):
    path = tmp_path / "broken.log"
    good = "FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.0 host 1.0"
    path.write_text(f"# header\n{good}\n{bad_line}\n{good}\n")
    with pytest.raises(InputError) as info:
        read_carmen(path)
    assert str(info.value).startswith(str(path)) and problem in str(info.value)


@pytest.mark.parametrize("content, problem", [
    (b"", "no FLASER lines"),
    (b"ODOM 0 0 0 0 0 0 0.5 pippo 0.5\n", "no FLASER lines"),
    (b"\x1f\x8b\x08\x00garbage", "corrupt gzip"),
    (b"FLASER \xff\xfe", "not a text CARMEN log"),
])
def test_unreadable_files(tmp_path, content, problem):
    path = tmp_path / "x.log"
    path.write_bytes(content)
    with pytest.raises(InputError, match=problem) as info:
        read_carmen(path)
    assert str(path) in str(info.value)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(InputError, match="nope.log: no such file"):
        read_carmen(tmp_path / "nope.log")
    with pytest.raises(InputError, match="is a folder"):
        read_carmen(tmp_path)


@pytest.mark.skipif(not (have_data(INTEL) and have_data(ACES)), reason="CARMEN logs not downloaded")
@pytest.mark.parametrize("name, n_scans, code, first_pose", [
    (INTEL, 910, 80.0, (0.600266, -0.0320327, -0.354665)),  # 81.83 m readings: beyond a SICK's 80 m
    (ACES, 440, 50.0, (0.89706, -0.180771, -0.454003)),
])
def test_real_logs(name, n_scans, code, first_pose):
    rec = read_carmen(data_file(name))
    s = rec.scans
    assert s.ranges.shape == (n_scans, 180)
    assert rec.meta["no_return_code"] == code and s.range_max == code
    assert np.isposinf(s.ranges).sum() == rec.meta["no_return_readings"] > 0
    assert np.all(s.ranges[np.isfinite(s.ranges)] < code - 0.005)
    np.testing.assert_allclose(s.laser_poses[0], first_pose)
    assert s.angle_min == -math.pi / 2 and math.isclose(s.angles[-1], math.pi / 2)
    assert len(rec.odometry) > n_scans


def _wall_agreement(scans):
    occ, emp = count_hits(scans, 0.05)
    return occ[occ > emp].sum() / occ.sum()


@pytest.mark.skipif(not have_data(INTEL), reason="Intel log not downloaded")
def test_intel_beam_order_is_right():
    # The data README: reversing the beam order turns the Intel map into noise. Our order
    # must give scans that agree with each other far better than the reversed one.
    s = read_carmen(data_file(INTEL)).scans
    right = _wall_agreement(s)
    s.ranges = np.ascontiguousarray(s.ranges[:, ::-1])
    assert right > 2 * _wall_agreement(s)


# --- corrupt odometry -------------------------------------------------------------------------------
CORRUPT_ODOM = """FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 0.30 pippo 0.30
ODOM 0.00 0 0 0 0 0 0.10 pippo 0.10
ODOM 7.00 3 1 0 0 0 0 pippo 0
ODOM 0.05 0 0 0 0 0 0.20 pippo 0.20
ODOM 6.00 2 0 0 0 0 0.15 pippo 0.15
ODOM 6.50 2 0 0 0 0 0.20 pippo 0.20
ODOM 0.10 0 0 0 0 0 1.2e-153 pippo 0
ODOM 0.10 0 0 0 0 0 0.30 pippo 0.30
ODOM 3.10 0 0 0 0 0 0.40 pippo 0.40
"""


def test_corrupt_odometry_is_dropped_with_one_warning_and_jumps_are_warned_of(tmp_path):
    path = tmp_path / "corrupt.log"
    path.write_text(CORRUPT_ODOM)
    with pytest.warns(UserWarning) as caught:
        rec = read_carmen(path)
    lines = [str(w.message) for w in caught]
    assert len(lines) == 2 and all("\n" not in line for line in lines)
    assert "dropped 4 of 8 ODOM records with a zero or non-increasing timestamp" in lines[0]
    # 0.30 -> 0.40 s: 3 m in 0.1 s, which no stamp explains: kept, and said (line 9 of the log)
    assert "1 ODOM moves faster than 2 m/s" in lines[1] and "line 9, 3.00 m in 0.1 s" in lines[1]
    np.testing.assert_array_equal(rec.odometry.stamps, [0.10, 0.20, 0.30, 0.40])
    np.testing.assert_array_equal(rec.odometry.poses[:, 0], [0.0, 0.05, 0.10, 3.10])
    assert rec.meta["odometry_dropped"] == 4 and rec.meta["odometry_jumps"] == 1
    assert len(rec.scans) == 1


def test_clean_odometry_keeps_a_clean_log_silent(log_file):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = read_carmen(log_file)
    assert rec.meta["odometry_dropped"] == 0 and rec.meta["odometry_jumps"] == 0


@pytest.mark.skipif(not have_data(INTEL), reason="the Intel log is not downloaded")
def test_intel_odometry_has_no_zero_or_backward_stamps():
    with pytest.warns(UserWarning, match="dropped") as caught:
        rec = read_carmen(data_file(INTEL))
    stamps = rec.odometry.stamps
    assert np.all(np.round(stamps * 1e9) > 0) and np.all(np.diff(stamps) > 0)
    assert len(stamps) + rec.meta["odometry_dropped"] == 14541 and rec.meta["odometry_dropped"] > 867
    steps = np.hypot(*np.diff(rec.odometry.poses[:, :2], axis=0).T)
    assert steps.max() < 1.0  # the log had 254 jumps over 1 m once its zero-stamped records sat at t = 0
    assert len(caught) <= 2
