"""ROS 2 bags as rosbag2 writes them: MCAP and sqlite3, NAME_0 data files, metadata Humble parses, latched /tf_static."""
import sqlite3
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from rosbags.rosbag2 import Reader

from crfmap.errors import InputError
from crfmap.io.bag_reader import read_bag, write_bag

sys.path.insert(0, str(Path(__file__).parent))
from test_bag_reader import make_recording  # noqa: E402

TRANSIENT_LOCAL, VOLATILE = 1, 2  # rmw_qos_durability_policy_t


# --- Humble's rosbag2_storage metadata parser (metadata_io.cpp, yaml-cpp), transcribed --------------
def _as(node, kind, key):
    """yaml-cpp's node.as<T>(): a scalar of the right kind, or a thrown conversion error."""
    if isinstance(node, (dict, list)) or node is None:
        raise ValueError(f"bad conversion of '{key}' to {kind.__name__}: not a scalar")
    if kind is str:
        return str(node)
    if kind is bool:
        if not isinstance(node, bool):
            raise ValueError(f"bad conversion of '{key}' to bool")
        return node
    if isinstance(node, bool) or not isinstance(node, int):
        raise ValueError(f"bad conversion of '{key}' to int")
    return node


def humble_read_metadata(text):
    """What Humble's ``MetadataIo::read_metadata`` does with a metadata.yaml (raises where it throws)."""
    node = yaml.safe_load(text)["rosbag2_bagfile_information"]
    version = _as(node["version"], int, "version")
    meta = {"version": version, "storage_identifier": _as(node["storage_identifier"], str, "storage_identifier")}
    _as(node["duration"]["nanoseconds"], int, "duration")
    _as(node["starting_time"]["nanoseconds_since_epoch"], int, "starting_time")
    _as(node["message_count"], int, "message_count")
    if not isinstance(node["topics_with_message_count"], list):
        raise ValueError("topics_with_message_count is not a sequence")
    meta["topics"] = {}
    for info in node["topics_with_message_count"]:
        topic = info["topic_metadata"]
        name = _as(topic["name"], str, "name")
        _as(topic["type"], str, "type")
        _as(topic["serialization_format"], str, "serialization_format")
        qos = _as(topic["offered_qos_profiles"], str, "offered_qos_profiles") if version >= 4 else ""
        meta["topics"][name] = humble_read_qos(qos)
        _as(info["message_count"], int, "message_count")
    meta["relative_file_paths"] = [_as(p, str, "relative_file_paths") for p in node["relative_file_paths"]]
    if version >= 3:
        _as(node["compression_format"], str, "compression_format")
        _as(node["compression_mode"], str, "compression_mode")
    if version >= 5:
        for f in node["files"]:
            _as(f["path"], str, "path")
            _as(f["starting_time"]["nanoseconds_since_epoch"], int, "starting_time")
            _as(f["duration"]["nanoseconds"], int, "duration")
            _as(f["message_count"], int, "message_count")
    return meta


def humble_read_qos(text):
    """Humble's rosbag2_transport qos.cpp: a YAML list of profiles with integer policies."""
    profiles = yaml.safe_load(text) if text else []
    out = []
    for p in profiles:
        for key in ("history", "depth", "reliability", "durability", "liveliness"):
            _as(p[key], int, key)
        for key in ("deadline", "lifespan", "liveliness_lease_duration"):
            _as(p[key]["sec"], int, key), _as(p[key]["nsec"], int, key)
        _as(p["avoid_ros_namespace_conventions"], bool, "avoid_ros_namespace_conventions")
        out.append(p)
    return out


# --- round trips -----------------------------------------------------------------------------------
@pytest.mark.parametrize("storage, suffix", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_round_trip_names_files_as_rosbag2(tmp_path, storage, suffix):
    rec = make_recording()
    write_bag(rec, tmp_path / "run", storage=storage)
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == ["metadata.yaml", f"run_0{suffix}"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no temporary leftovers
    back = read_bag(tmp_path / "run")
    np.testing.assert_array_equal(back.scans.ranges.view(np.uint32), rec.scans.ranges.view(np.uint32))
    np.testing.assert_allclose(back.laser_mount, rec.laser_mount, atol=1e-12)
    np.testing.assert_array_equal(back.ground_truth.probability, rec.ground_truth.probability)
    meta = yaml.safe_load((tmp_path / "run" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    with Reader(tmp_path / "run") as reader:  # rosbags' own reader agrees with the metadata
        assert reader.message_count == meta["message_count"] == sum(c.msgcount for c in reader.connections) > 0
    assert meta["storage_identifier"] == storage
    assert meta["relative_file_paths"] == [f"run_0{suffix}"] and meta["files"][0]["path"] == f"run_0{suffix}"


@pytest.mark.parametrize("storage, suffix", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_a_bare_data_file_reads_without_metadata(tmp_path, storage, suffix):
    rec = make_recording()
    write_bag(rec, tmp_path / "run", storage=storage)
    bare = tmp_path / f"bare{suffix}"
    bare.write_bytes((tmp_path / "run" / f"run_0{suffix}").read_bytes())
    back = read_bag(bare)
    np.testing.assert_array_equal(back.scans.ranges.view(np.uint32), rec.scans.ranges.view(np.uint32))
    np.testing.assert_allclose(back.laser_mount, rec.laser_mount, atol=1e-12)
    bare.write_bytes(b"not a bag at all " * 100)
    with pytest.raises(InputError, match=f"bare{suffix}"):
        read_bag(bare)


# --- metadata Humble reads -----------------------------------------------------------------------------
@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_default_metadata_is_what_humble_parses(tmp_path, storage):
    write_bag(make_recording(), tmp_path / "run", storage=storage)
    meta = humble_read_metadata((tmp_path / "run" / "metadata.yaml").read_text())
    assert meta["version"] == 8 and meta["storage_identifier"] == storage
    for name in meta["relative_file_paths"]:  # Humble resolves them against the bag folder
        assert (tmp_path / "run" / name).is_file()
    topics = meta["topics"]
    assert set(topics) == {"/scan", "/odom", "/tf", "/tf_static", "/ground_truth_pose", "/cmd_vel", "/map"}
    for name, profiles in topics.items():
        (profile,) = profiles
        latched = name in ("/tf_static", "/map")
        assert profile["durability"] == (TRANSIENT_LOCAL if latched else VOLATILE), name
        assert profile["reliability"] == 1 and profile["history"] == 1  # reliable, keep last
        assert profile["depth"] == (1 if latched else 10)


def test_jazzy_metadata_is_version_9_which_humble_cannot_parse(tmp_path):
    write_bag(make_recording(), tmp_path / "run", distro="jazzy")
    text = (tmp_path / "run" / "metadata.yaml").read_text()
    node = yaml.safe_load(text)["rosbag2_bagfile_information"]
    assert node["version"] == 9
    tf_static = next(t["topic_metadata"] for t in node["topics_with_message_count"]
                     if t["topic_metadata"]["name"] == "/tf_static")
    assert tf_static["offered_qos_profiles"][0]["durability"] == "transient_local"  # Jazzy's list form
    with pytest.raises(ValueError, match="offered_qos_profiles"):
        humble_read_metadata(text)
    assert len(read_bag(tmp_path / "run").scans) == 5


def test_sqlite_topics_table_offers_tf_static_transient_local(tmp_path):
    # Humble's player takes the QoS from the storage's topics table too
    write_bag(make_recording(), tmp_path / "run", storage="sqlite3")
    with sqlite3.connect(tmp_path / "run" / "run_0.db3") as db:
        rows = dict(db.execute("SELECT name, offered_qos_profiles FROM topics").fetchall())
    assert humble_read_qos(rows["/tf_static"])[0]["durability"] == TRANSIENT_LOCAL
    assert humble_read_qos(rows["/scan"])[0]["durability"] == VOLATILE


def test_bad_storage_or_distro(tmp_path):
    with pytest.raises(InputError, match="--storage"):
        write_bag(make_recording(), tmp_path / "run", storage="rosbag")
    with pytest.raises(InputError, match="--distro"):
        write_bag(make_recording(), tmp_path / "run", distro="iron")
    assert not (tmp_path / "run").exists()


def test_ros1_bag_latches_tf_static_and_map(tmp_path):
    from rosbags.rosbag1 import Reader as Reader1

    write_bag(make_recording(), tmp_path / "b.bag", fmt="ros1")
    with Reader1(tmp_path / "b.bag") as reader:
        latching = {c.topic: c.ext.latching for c in reader.connections}
    assert latching["/tf_static"] == latching["/map"] == 1
    assert not latching["/scan"]
    assert len(read_bag(tmp_path / "b.bag").scans) == 5
