"""The command line's ROS-facing options: map modes and what nav2 sees (build), bag storage and distro (simulate, convert)."""
import numpy as np
import pytest
import yaml

from crfmap.cli import main
from crfmap.io.map_server import load_map
from crfmap.io.nav2_costmap import nav2_counts

@pytest.mark.parametrize("loader", ["humble", "jazzy"])
def test_build_writes_a_trinary_map_and_says_what_nav2_sees(small_log, tmp_path, capsys, loader):
    out = tmp_path / "map.yaml"
    assert main(["build", str(small_log), str(out), "--resolution", "0.1", "--loader", loader]) == 0
    line = capsys.readouterr().out.strip()
    values = load_map(out, loader=loader).to_int8()
    c = nav2_counts(values)
    assert c["occupied"] > 0 and "\n" not in line
    assert f"{c['occupied']} occupied, {c['free']} free, {c['unknown']} unknown cells under nav2's defaults" in line
    assert yaml.safe_load(out.read_text())["mode"] == "trinary"
    assert main(["build", str(small_log), str(tmp_path / "exact.npy"), "--resolution", "0.1"]) == 0
    assert "not a nav2 map" in capsys.readouterr().out
    p = np.load(tmp_path / "exact.npy")
    assert c["occupied"] == (np.rint(p * 100) >= 65).sum()  # the .npy holds what the map was made of


def test_build_scale_mode_and_save_thresholds(small_log, tmp_path, capsys):
    out = tmp_path / "s.yaml"
    assert main(["build", str(small_log), str(out), "--resolution", "0.1", "--mode", "scale",
                 "--save-occupied-thresh", "0.65", "--save-free-thresh", "0.196"]) == 0
    doc = yaml.safe_load(out.read_text())
    assert (doc["mode"], doc["occupied_thresh"], doc["free_thresh"]) == ("scale", 0.65, 0.196)
    assert main(["build", str(small_log), str(tmp_path / "bad.yaml"), "--save-free-thresh", "0.9"]) == 2
    assert "free_thresh" in capsys.readouterr().err


def test_simulate_sqlite3_jazzy_and_ros1_refuses_storage(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "x", str(out), "--storage", "sqlite3", "--distro", "jazzy", "--mode", "look",
                 "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["metadata.yaml", "sim_0.db3"]
    assert yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]["version"] == 9
    assert main(["simulate", "x", str(tmp_path / "s.bag"), "--format", "ros1", "--storage", "mcap", "--quiet"]) == 2
    assert "--storage" in capsys.readouterr().err
    assert main(["convert", str(out), str(tmp_path / "conv")]) == 0
    assert sorted(p.name for p in (tmp_path / "conv").iterdir()) == ["conv_0.mcap", "metadata.yaml"]


def _log_times(path):
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return [(c.topic, t) for c, t, _ in reader.messages()]


def test_simulate_start_time_sets_the_first_stamp_and_refuses_zero(tmp_path, capsys):
    out = tmp_path / "s.bag"
    assert main(["simulate", "x", str(out), "--format", "ros1", "--mode", "look", "--quiet", "--beams", "8",
                 "--start-time", "1234.5"]) == 0
    times = _log_times(out)
    assert min(t for _, t in times) == 1_234_500_000_000
    assert main(["simulate", "x", str(tmp_path / "z.bag"), "--format", "ros1", "--quiet", "--start-time", "0"]) == 2
    err = capsys.readouterr().err
    assert "--start-time" in err and len(err.strip().splitlines()) == 1


def test_convert_drops_zero_stamped_odometry_with_one_warning(tmp_path, capsys):
    log = tmp_path / "c.log"
    log.write_text("FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 0.30 pippo 0.30\n"
                   "ODOM 0 0 0 0 0 0 0.10 pippo 0.10\nODOM 5 5 0 0 0 0 0 pippo 0\n"
                   "ODOM 0.01 0 0 0 0 0 0.35 pippo 0.35\n")
    assert main(["convert", str(log), str(tmp_path / "c.bag")]) == 0
    assert capsys.readouterr().err.splitlines() == [  # one line, naming the log
        "crfmap convert: warning: c.log: dropped 1 of 3 ODOM records with a zero or non-increasing timestamp "
        "(corrupt odometry)"]
    odom = [t for topic, t in _log_times(tmp_path / "c.bag") if topic == "/odom"]
    assert odom == [100_000_000, 350_000_000]


@pytest.mark.parametrize("stamps, said", [
    ((0, 0, 0, 0), "every scan is stamped 0"),
    ((5, 5, 6, 6), "2 of 4 scans repeat a stamp at another pose"),
])
def test_convert_stamps_scans_by_their_order_when_their_stamps_cannot_place_them(tmp_path, capsys, stamps, said):
    """A log whose FLASER stamps are all 0 or repeat converts, stamped by scan order (one warning), poses kept."""
    from crfmap.commands.convert import ORDER_PERIOD
    from crfmap.io.bag_reader import read_bag
    from crfmap.sim.simulator import START_TIME

    log = tmp_path / "z.log"
    log.write_text("".join(f"FLASER 3 1.0 2.0 3.0 {0.5 * i} 0 0 {0.5 * i} 0 0 {t} host {t}\n"
                           for i, t in enumerate(stamps)))
    assert main(["convert", str(log), str(tmp_path / "z.bag")]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == [f"crfmap convert: warning: {log}: {said}, so tf cannot place them; stamped by their "
                                f"order instead, {START_TIME:.0f} s + {ORDER_PERIOD:g} s per scan"]
    scans = read_bag(tmp_path / "z.bag").scans
    np.testing.assert_allclose(scans.stamps - START_TIME, ORDER_PERIOD * np.arange(4), atol=1e-6)
    np.testing.assert_allclose(scans.laser_poses[:, 0], [0.0, 0.5, 1.0, 1.5], atol=1e-9)


def test_a_recording_tf_cannot_hold_is_refused_naming_its_source_without_numpy_reprs(tmp_path):
    from crfmap.errors import InputError
    from crfmap.io.bag_writer import write_bag
    from crfmap.recording import Recording, ScanSet

    scans = ScanSet(np.ones((2, 3), np.float32), -0.5, 0.5, 0.1, 5.0, np.array([[0.0, 0, 0], [1.0, 0, 0]]),
                    np.array([7.0, 7.0]), source="odd.log")
    with pytest.raises(InputError) as refused:
        write_bag(Recording(scans), tmp_path / "odd.bag", fmt="ros1")
    assert str(refused.value).startswith("odd.log: 1 scans share a stamp") and "scans 0 and 1, 7 s" in str(refused.value)
    assert "np." not in str(refused.value)


def test_write_bag_shows_its_progress_when_asked(tmp_path, capsys):
    from crfmap.io.bag_reader import read_bag
    from crfmap.io.bag_writer import write_bag
    from crfmap.recording import Recording, ScanSet

    scans = ScanSet(np.ones((3, 4), np.float32), -0.5, 0.3, 0.1, 5.0, np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]]),
                    np.array([1.0, 2.0, 3.0]))
    write_bag(Recording(scans), tmp_path / "quiet.bag", fmt="ros1")
    assert capsys.readouterr().err == ""
    write_bag(Recording(scans), tmp_path / "shown.bag", fmt="ros1", progress=True)
    assert "writing bag" in capsys.readouterr().err
    np.testing.assert_array_equal(read_bag(tmp_path / "shown.bag").scans.ranges, read_bag(tmp_path / "quiet.bag").scans.ranges)
