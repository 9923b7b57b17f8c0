"""ROS 2 bag files laid out as each distro's rosbag2 writes them (sqlite3 or MCAP, and metadata.yaml).

rosbags serializes the messages; the files follow ros2/rosbag2's source: ``sqlite_storage.cpp``
(``rosbag2_storage_default_plugins`` on humble, ``rosbag2_storage_sqlite3`` on jazzy), ``mcap_storage.cpp``,
``rosbag2_storage/.../metadata_io.cpp``. What differs between humble and jazzy (metadata version, sqlite3 schema and
tables, MCAP metadata) is tabled in the README (Handing a refined map to nav2, "Bags"); the constants below and each
writer hold it. MCAP files (``mcap`` library): profile ``ros2``, schemas ``ros2msg``, messages ``cdr`` with log time =
publish time, uncompressed chunks, summary and indexes."""
from __future__ import annotations

import sqlite3
from pathlib import Path

import yaml

DISTRO_METADATA_VERSION = {"humble": 5, "jazzy": 9}
DISTRO_DB_SCHEMA = {"humble": 3, "jazzy": 4}
STORAGE_SUFFIX = {"mcap": ".mcap", "sqlite3": ".db3"}

# The CREATE statements of each distro's SqliteStorage::initialize(), verbatim.
_SQL_SCHEMA = ("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);")
_SQL_METADATA = ("CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
                 "metadata TEXT NOT NULL);")
_SQL_MESSAGES = ("CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
                 "timestamp INTEGER NOT NULL, data BLOB NOT NULL);")
_SQL_INDEX = "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
SQLITE_CREATE = {
    "humble": [_SQL_SCHEMA, _SQL_METADATA,
               "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
               "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);",
               _SQL_MESSAGES, _SQL_INDEX],
    "jazzy": [_SQL_SCHEMA, _SQL_METADATA,
              "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
              "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,"
              "type_description_hash TEXT NOT NULL);",
              "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT NULL,"
              "encoding TEXT NOT NULL,encoded_message_definition TEXT NOT NULL,"
              "type_description_hash TEXT NOT NULL);",
              _SQL_MESSAGES, _SQL_INDEX],
}


class Topic:
    """One topic of a bag: name, type, its message definition and hash, offered QoS profiles."""

    def __init__(self, name, msgtype, store, qos):
        self.name, self.msgtype, self.qos = name, msgtype, list(qos)
        self.msgdef, _ = store.generate_msgdef(msgtype, ros_version=2)
        self.type_hash = store.hash_rihs01(msgtype)
        self.count = 0

    def qos_text(self, distro):
        """The offered QoS as the distro's storage plugin stores it: a YAML string (v8 ints, v9 names)."""
        from rosbags.rosbag2.metadata import dump_qos_v8, dump_qos_v9

        if distro == "humble":
            return dump_qos_v8(self.qos)
        return yaml.safe_dump(dump_qos_v9(self.qos), sort_keys=False, default_flow_style=False).strip()


def write_rosbag2(folder: Path, name, messages, topics, storage, distro):
    """Write ``folder/NAME_0.{mcap,db3}`` and ``folder/metadata.yaml`` into the existing empty ``folder``; ``messages``:
    (stamp [ns], topic name, CDR bytes) in time order; ``topics``: {name: :class:`Topic`}, in order."""
    data_name = f"{name}_0{STORAGE_SUFFIX[storage]}"
    for _, topic, _ in messages:
        topics[topic].count += 1
    stamps = [ns for ns, _, _ in messages]
    start, end = (min(stamps), max(stamps)) if stamps else (0, 0)
    metadata = bag_metadata(data_name, storage, distro, list(topics.values()), start, end - start, len(messages))
    if storage == "sqlite3":
        _write_sqlite3(folder / data_name, messages, topics, distro, metadata)
    else:
        _write_mcap(folder / data_name, messages, topics, distro, metadata)
    (folder / "metadata.yaml").write_text(
        yaml.safe_dump({"rosbag2_bagfile_information": metadata}, sort_keys=False, default_flow_style=False),
        encoding="utf-8")


def bag_metadata(data_name, storage, distro, topics, start, duration, count):
    """The ``rosbag2_bagfile_information`` of the distro's ``convert<BagMetadata>::encode``."""
    version = DISTRO_METADATA_VERSION[distro]
    infos = []
    for t in topics:
        meta = {"name": t.name, "type": t.msgtype, "serialization_format": "cdr"}
        if version >= 9:
            from rosbags.rosbag2.metadata import dump_qos_v9

            meta["offered_qos_profiles"] = dump_qos_v9(t.qos)
            meta["type_description_hash"] = t.type_hash
        else:
            meta["offered_qos_profiles"] = t.qos_text(distro)
        infos.append({"topic_metadata": meta, "message_count": t.count})
    out = {
        "version": version,
        "storage_identifier": storage,
        "duration": {"nanoseconds": int(duration)},
        "starting_time": {"nanoseconds_since_epoch": int(start)},
        "message_count": int(count),
        "topics_with_message_count": infos,
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [data_name],
        "files": [{"path": data_name, "starting_time": {"nanoseconds_since_epoch": int(start)},
                   "duration": {"nanoseconds": int(duration)}, "message_count": int(count)}],
    }
    if version >= 9:
        out["custom_data"] = {}
        out["ros_distro"] = distro
    return out


def _write_sqlite3(path, messages, topics, distro, metadata):
    conn = sqlite3.connect(path)
    try:
        for statement in SQLITE_CREATE[distro]:
            conn.execute(statement)
        conn.execute("INSERT INTO schema (schema_version, ros_distro) VALUES (?, ?)", (DISTRO_DB_SCHEMA[distro], distro))
        ids = {}
        for t in topics.values():
            if distro == "humble":
                cur = conn.execute("INSERT INTO topics (name, type, serialization_format, offered_qos_profiles) "
                                   "VALUES (?, ?, ?, ?)", (t.name, t.msgtype, "cdr", t.qos_text(distro)))
            else:
                cur = conn.execute("INSERT INTO topics(name, type, serialization_format, offered_qos_profiles, "
                                   "type_description_hash) VALUES (?, ?, ?, ?, ?)",
                                   (t.name, t.msgtype, "cdr", t.qos_text(distro), t.type_hash))
            ids[t.name] = cur.lastrowid
        if distro != "humble":
            for msgtype in dict.fromkeys(t.msgtype for t in topics.values()):
                t = next(t for t in topics.values() if t.msgtype == msgtype)
                conn.execute("INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition, "
                             "type_description_hash) VALUES (?, ?, ?, ?)", (msgtype, "ros2msg", t.msgdef, t.type_hash))
        conn.executemany("INSERT INTO messages (timestamp, topic_id, data) VALUES (?, ?, ?);",
                         ((ns, ids[name], data) for ns, name, data in messages))
        if distro != "humble":  # SqliteStorage::update_metadata (schema >= 3; Humble's plugin has none)
            conn.execute("INSERT INTO metadata (metadata_version, metadata) VALUES (?, ?)",
                         (metadata["version"], yaml.safe_dump(metadata, sort_keys=False)))
        conn.commit()
    finally:
        conn.close()


def _write_mcap(path, messages, topics, distro, metadata):
    from mcap.writer import CompressionType, Writer

    from importlib.metadata import version

    with open(path, "wb") as f:
        writer = Writer(f, compression=CompressionType.NONE)
        writer.start(profile="ros2", library=f"crfmap {version('crfmap')} (python mcap)")
        if distro == "humble":  # MCAPStorage::ensure_rosdistro_metadata_added, at open
            writer.add_metadata("rosbag2", {"ROS_DISTRO": distro})
        schemas, channels = {}, {}
        for t in topics.values():
            if t.msgtype not in schemas:
                schemas[t.msgtype] = writer.register_schema(t.msgtype, "ros2msg", t.msgdef.encode("utf-8"))
            channel_meta = {"offered_qos_profiles": t.qos_text(distro)}
            if distro != "humble":
                channel_meta["topic_type_hash"] = t.type_hash
            channels[t.name] = writer.register_channel(t.name, "cdr", schemas[t.msgtype], channel_meta)
        for ns, name, data in messages:
            writer.add_message(channels[name], log_time=ns, data=bytes(data), publish_time=ns, sequence=0)
        if distro != "humble":  # MCAPStorage::update_metadata, at close
            writer.add_metadata("rosbag2", {"serialized_metadata": yaml.safe_dump(metadata, sort_keys=False)})
        writer.finish()
