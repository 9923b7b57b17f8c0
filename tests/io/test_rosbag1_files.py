"""ROS 1 bags whose bag-header record is rosbag's: its byte layout, and rosbag's own reindex, append and play query."""
import shutil
import struct
import subprocess
import textwrap
from pathlib import Path

import pytest

from crfmap.io.bag_reader import read_bag
from crfmap.io.bag_writer import write_bag
from crfmap.io.rosbag1_files import BAG_MAGIC, file_header_record, parse_header_fields

from test_bag_reader import make_recording  # noqa: E402 (tests/io is on pytest's pythonpath)

DEBIAN_PYTHON = "/usr/bin/python3"


def _records(data, start):
    """(offset, header fields, data length) of every record from ``start`` to the end."""
    pos, out = start, []
    while pos < len(data):
        (hlen,) = struct.unpack_from("<I", data, pos)
        fields = parse_header_fields(data[pos + 4: pos + 4 + hlen])
        (dlen,) = struct.unpack_from("<I", data, pos + 4 + hlen)
        out.append((pos, fields, dlen))
        pos += 8 + hlen + dlen
    return out


def test_header_record_has_rosbags_layout(tmp_path):
    path = write_bag(make_recording(), tmp_path / "b.bag", fmt="ros1")
    data = path.read_bytes()
    assert data.startswith(BAG_MAGIC)
    (hlen,) = struct.unpack_from("<I", data, 13)
    (dlen,) = struct.unpack_from("<I", data, 17 + hlen)
    # rosbag: data padded to 4096 - header length, so the record is 4096 + its two length fields
    assert hlen + dlen == 4096 and data[21 + hlen: 21 + hlen + dlen] == b" " * dlen
    fields = parse_header_fields(data[17: 17 + hlen])
    assert list(fields) == ["chunk_count", "conn_count", "index_pos", "op"]  # rosbag record's std::map order
    assert fields["op"] == b"\x03"
    records = _records(data, 13)
    assert [r[0] for r in records[:2]] == [13, 13 + 4104]  # the first chunk starts where rosbag expects it
    assert records[1][1]["op"] == b"\x05"
    index_pos = struct.unpack("<Q", fields["index_pos"])[0]
    ops = {pos: f["op"] for pos, f, _ in records}
    assert ops[index_pos] == b"\x07"  # the index starts with connection records ...
    chunk_infos = [f for f in (r[1] for r in records) if f["op"] == b"\x06"]
    assert len(chunk_infos) == struct.unpack("<I", fields["chunk_count"])[0]
    for info in chunk_infos:  # ... and the chunk infos point at chunks
        assert ops[struct.unpack("<Q", info["chunk_pos"])[0]] == b"\x05"
    assert len(read_bag(path).scans) == 5


def test_file_header_record_bytes():
    record = file_header_record(0x0102, 3, 4)
    assert len(record) == 4104 and record[:4] == struct.pack("<I", 69)
    assert record[4:4 + 69] == (b"\x10\x00\x00\x00chunk_count=\x04\x00\x00\x00" b"\x0f\x00\x00\x00conn_count=\x03\x00\x00\x00"
                                b"\x12\x00\x00\x00index_pos=\x02\x01\x00\x00\x00\x00\x00\x00" b"\x04\x00\x00\x00op=\x03")
    assert record[73:77] == struct.pack("<I", 4027)


def _debian_rosbag():
    if not Path(DEBIAN_PYTHON).exists():
        return "no /usr/bin/python3"
    probe = subprocess.run([DEBIAN_PYTHON, "-c", "import rosbag, genpy"], capture_output=True, text=True)
    return None if probe.returncode == 0 else "Debian's python3-rosbag is not installed (apt-get install python3-rosbag)"


ROSBAG_SCRIPT = textwrap.dedent("""
    import shutil, sys
    import genpy, rosbag

    path, work = sys.argv[1], sys.argv[2]
    def count(p, **kw):
        with rosbag.Bag(p) as bag:
            return sum(1 for _ in bag.read_messages(**kw))
    total = count(path)
    play = count(path, start_time=genpy.Time(0, 1))  # rosbag play's query starts at ros::TIME_MIN = 1 ns
    # rosbag reindex: rosbag_main.reindex_op's loop
    shutil.copy(path, work + "/r.bag")
    bag = rosbag.Bag(work + "/r.bag", "a", allow_unindexed=True)
    for _ in bag.reindex():
        pass
    bag.close()
    reindexed = count(work + "/r.bag")
    # append one message to a copy
    shutil.copy(path, work + "/a.bag")
    with rosbag.Bag(path) as bag:
        topic, msg, t = next(bag.read_messages(topics=["/scan"]))
    with rosbag.Bag(work + "/a.bag", "a") as bag:
        bag.write(topic, msg, t + genpy.Duration(100))
    appended = count(work + "/a.bag")
    print(total, play, reindexed, appended)
""")


@pytest.mark.skipif(_debian_rosbag() is not None, reason=str(_debian_rosbag()))
def test_official_rosbag_reindexes_appends_and_plays_everything(tmp_path):
    path = write_bag(make_recording(), tmp_path / "b.bag", fmt="ros1")
    out = subprocess.run([DEBIAN_PYTHON, "-c", ROSBAG_SCRIPT, str(path), str(tmp_path)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    total, play, reindexed, appended = map(int, out.stdout.split())
    assert total > 0 and play == total and reindexed == total and appended == total + 1
    back = read_bag(tmp_path / "a.bag")  # and crfmap reads rosbag's rewritten file
    assert len(back.scans) == 6
    shutil.rmtree(tmp_path, ignore_errors=True)
