"""ROS 2 bags as rosbag2 writes them: MCAP and sqlite3, NAME_0 data files, metadata Humble parses, latched /tf_static."""
import sqlite3

import numpy as np
import pytest
import yaml
from rosbags.rosbag2 import Reader

from crfmap.errors import InputError
from crfmap.io.bag_reader import read_bag
from crfmap.io.bag_writer import write_bag

from test_bag_reader import make_recording  # noqa: E402 (tests/io is on pytest's pythonpath)

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
    assert meta["version"] == 5 and meta["storage_identifier"] == storage  # what Humble writes
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


# --- each distro's storage plugins, their own SQL and MCAP records ---------------------------------
# The queries rosbag2's sqlite3 plugin runs on a bag it reads, copied from its source
# (ros2/rosbag2, humble: rosbag2_storage_default_plugins/src/.../sqlite/sqlite_storage.cpp and
# sqlite_wrapper.cpp; jazzy: rosbag2_storage_sqlite3/src/rosbag2_storage_sqlite3/...).
SQLITE_READ_QUERIES = {
    "humble": [
        "SELECT count(*) FROM sqlite_master WHERE type='table' AND name='schema';",
        "SELECT schema_version from schema;",
        "SELECT ros_distro from schema;",
        "SELECT INSTR(sql, 'offered_qos_profiles') FROM sqlite_master WHERE type='table' AND name='topics';",
        "SELECT name, type, serialization_format, offered_qos_profiles FROM topics ORDER BY id;",
        "SELECT name, type, serialization_format, COUNT(messages.id), MIN(messages.timestamp), "
        "MAX(messages.timestamp), offered_qos_profiles FROM messages JOIN topics on topics.id = messages.topic_id "
        "GROUP BY topics.name;",
        "SELECT data, timestamp, topics.name, messages.id FROM messages JOIN topics ON messages.topic_id = "
        "topics.id WHERE (((timestamp = 0) AND (messages.id >= 0)) OR (timestamp > 0)) "
        "ORDER BY messages.timestamp, messages.id;",
    ],
    "jazzy": [
        "SELECT schema_version from schema;",
        "SELECT ros_distro from schema;",
        "SELECT id, name, type, serialization_format, offered_qos_profiles, type_description_hash FROM topics "
        "ORDER BY id;",
        "SELECT topic_type, encoding, encoded_message_definition, type_description_hash FROM "
        "message_definitions ORDER BY id;",
        "SELECT metadata_version, metadata FROM metadata ORDER BY id;",
        "SELECT messages.topic_id, name, type, serialization_format, COUNT(messages.id), "
        "MIN(messages.timestamp), MAX(messages.timestamp), offered_qos_profiles, type_description_hash "
        "FROM messages JOIN topics on topics.id = messages.topic_id GROUP BY topics.name;",
        "SELECT max(rowid) from messages;",
    ],
}
SQLITE_COLUMNS = {  # table -> columns of each distro's SqliteStorage::initialize()
    "humble": {"schema": ["schema_version", "ros_distro"], "metadata": ["id", "metadata_version", "metadata"],
               "topics": ["id", "name", "type", "serialization_format", "offered_qos_profiles"],
               "messages": ["id", "topic_id", "timestamp", "data"]},
    "jazzy": {"schema": ["schema_version", "ros_distro"], "metadata": ["id", "metadata_version", "metadata"],
              "topics": ["id", "name", "type", "serialization_format", "offered_qos_profiles",
                         "type_description_hash"],
              "message_definitions": ["id", "topic_type", "encoding", "encoded_message_definition",
                                      "type_description_hash"],
              "messages": ["id", "topic_id", "timestamp", "data"]},
}


@pytest.mark.parametrize("distro, schema", [("humble", 3), ("jazzy", 4)])
def test_sqlite3_layout_is_the_distros(tmp_path, distro, schema):
    rec = make_recording()
    write_bag(rec, tmp_path / "run", storage="sqlite3", distro=distro)
    with sqlite3.connect(tmp_path / "run" / "run_0.db3") as db:
        tables = {name for (name,) in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        assert tables == set(SQLITE_COLUMNS[distro])
        for table, columns in SQLITE_COLUMNS[distro].items():
            assert [row[1] for row in db.execute(f"PRAGMA table_info({table})")] == columns, table
        indexes = {name for (name,) in db.execute("SELECT name FROM sqlite_master WHERE type='index'")}
        assert "timestamp_idx" in indexes
        results = [db.execute(q).fetchall() for q in SQLITE_READ_QUERIES[distro]]
        assert db.execute("SELECT schema_version, ros_distro FROM schema").fetchall() == [(schema, distro)]
        n_messages = db.execute("SELECT COUNT(*) FROM messages").fetchone()[0]
        if distro == "humble":
            assert results[3][0][0] > 0  # field_exists("topics", "offered_qos_profiles")
            assert sum(r[3] for r in results[5]) == n_messages and len(results[6]) == n_messages
            assert db.execute("SELECT COUNT(*) FROM metadata").fetchone()[0] == 0  # Humble's plugin fills none
        else:
            topics, definitions, metadata = results[2], results[3], results[4]
            assert all(t[5].startswith("RIHS01_") for t in topics)
            assert {d[0] for d in definitions} == {t[2] for t in topics} and all(d[1] == "ros2msg" for d in definitions)
            (version, text), = metadata
            assert version == 9 and yaml.safe_load(text)["ros_distro"] == "jazzy"
            assert sum(r[4] for r in results[5]) == n_messages
    meta = yaml.safe_load((tmp_path / "run" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["starting_time"]["nanoseconds_since_epoch"] == int(round(min(rec.odometry.stamps) * 1e9)) > 0
    assert meta.get("ros_distro", distro) == distro and "rosbags" not in str(meta)
    assert len(read_bag(tmp_path / "run").scans) == len(rec.scans)


@pytest.mark.parametrize("distro", ["humble", "jazzy"])
def test_mcap_records_are_the_distros(tmp_path, distro):
    from mcap.reader import make_reader  # the reference MCAP reader, independent of rosbags

    write_bag(make_recording(), tmp_path / "run", distro=distro)
    with open(tmp_path / "run" / "run_0.mcap", "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        messages = list(reader.iter_messages())
    assert header.profile == "ros2"
    assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
    for channel in summary.channels.values():
        assert channel.message_encoding == "cdr"
        keys = {"offered_qos_profiles"} | ({"topic_type_hash"} if distro == "jazzy" else set())
        assert set(channel.metadata) == keys, channel.topic
    if distro == "humble":  # MCAPStorage::ensure_rosdistro_metadata_added
        assert metadata == {"rosbag2": {"ROS_DISTRO": "humble"}}
    else:  # MCAPStorage::update_metadata
        assert yaml.safe_load(metadata["rosbag2"]["serialized_metadata"])["ros_distro"] == "jazzy"
    assert messages and all(m.log_time == m.publish_time > 0 for _, _, m in messages)
    assert summary.statistics.message_count == len(messages)
