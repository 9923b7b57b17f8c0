"""What the live-node tests share: Cyclone DDS on loopback only, the node as a real process, raw samples.

Every test gets its own DDS domain (from the process id and a counter), so tests of other runs
on the same machine never see each other's topics; Cyclone DDS is restricted to 127.0.0.1 with
unicast discovery (loopback has no multicast).
"""
from __future__ import annotations

import itertools
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np

TIMEOUT = 240.0  # [s] generous: the machine may be loaded; nothing asserts how fast
_domains = itertools.count()

LOOPBACK_CONFIG = """<CycloneDDS><Domain id="any">
<General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General>
<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30</MaxAutoParticipantIndex>
<Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>"""


def loopback_dds(tmp_path, monkeypatch):
    """Set this process's Cyclone DDS to loopback on a fresh domain; returns the environment for child processes."""
    config = tmp_path / "cyclonedds.xml"
    config.write_text(LOOPBACK_CONFIG)
    domain = 1 + (os.getpid() * 7 + next(_domains)) % 230
    monkeypatch.setenv("CYCLONEDDS_URI", config.as_uri())
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    return dict(os.environ)


class NodeProcess:
    """``python -m crfmap node ...`` as a child process, its stderr lines collected as they come."""

    def __init__(self, args, env):
        self.proc = subprocess.Popen([sys.executable, "-m", "crfmap", "node", *args], env=env, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.lines = []
        self._new = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))
            self._new.put(line)

    def wait_for(self, pattern, timeout=TIMEOUT):
        """The first stderr line matching ``pattern`` (searched from the start); fails the test on time-out or exit."""
        deadline = time.monotonic() + timeout
        regex = re.compile(pattern)
        while True:
            for line in list(self.lines):
                if regex.search(line):
                    return line
            if self.proc.poll() is not None and self._new.empty():
                raise AssertionError(f"the node exited ({self.proc.returncode}) before '{pattern}':\n" + self.log())
            try:
                self._new.get(timeout=min(1.0, max(deadline - time.monotonic(), 0.01)))
            except queue.Empty:
                if time.monotonic() > deadline:
                    raise AssertionError(f"no '{pattern}' from the node within {timeout:g} s:\n" + self.log()) from None

    def stop(self, sig=signal.SIGTERM):
        """End the node with ``sig``; its exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout=TIMEOUT)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()

    def log(self):
        return "\n".join(self.lines)


def take_raw(reader, n=64):
    """The serialized payloads (encapsulation header included) of the samples waiting in a Cyclone DDS reader.

    Cyclone DDS's Python binding decodes samples in ``take``; its C layer's ``ddspy_take`` (an internal
    of the binding, used by ``DataReader.take`` itself) hands over the bytes that came off the wire.
    """
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.core import InstanceState, SampleState, ViewState

    samples = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, n)
    assert not isinstance(samples, int), f"ddspy_take failed with {samples}"
    return [bytes(data) for data, info in samples if info.valid_data]


def wait_raw(reader, count=1, timeout=TIMEOUT):
    """At least ``count`` raw payloads from ``reader``, waiting up to ``timeout``."""
    out = []
    deadline = time.monotonic() + timeout
    while len(out) < count:
        out += take_raw(reader)
        if len(out) >= count:
            break
        assert time.monotonic() < deadline, f"{len(out)} of {count} samples within {timeout:g} s"
        time.sleep(0.05)
    return out


def wait_matched(writer, timeout=TIMEOUT):
    """Wait until ``writer`` has a matched reader (the node's)."""
    deadline = time.monotonic() + timeout
    while not writer.get_matched_subscriptions():
        assert time.monotonic() < deadline, "no reader matched the writer"
        time.sleep(0.05)


def rosbags_grid_bytes(msg, topic_kind="grid"):
    """rosbags' CDR of a :class:`crfmap.ros.messages.GridMessage` (an independent serializer), ROS 2 Humble types."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types

    def time_(ns):
        return t["builtin_interfaces/msg/Time"](sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))

    x, y, z, qx, qy, qz, qw = msg.origin
    info = t["nav_msgs/msg/MapMetaData"](
        map_load_time=time_(msg.map_load_ns), resolution=float(msg.resolution), width=int(msg.width),
        height=int(msg.height), origin=t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=x, y=y, z=z),
            orientation=t["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw)))
    if topic_kind == "metadata":
        return bytes(store.serialize_cdr(info, "nav_msgs/msg/MapMetaData"))
    grid = t["nav_msgs/msg/OccupancyGrid"](
        header=t["std_msgs/msg/Header"](stamp=time_(msg.stamp_ns), frame_id=msg.frame_id), info=info,
        data=np.asarray(msg.data, np.int8))
    return bytes(store.serialize_cdr(grid, "nav_msgs/msg/OccupancyGrid"))


def padded(payload: bytes) -> bytes:
    """A payload padded with zeros to a multiple of 4 bytes, as DDSI carries it (rmw_cyclonedds_cpp pads so too)."""
    return payload + b"\0" * (-len(payload) % 4)


def decode_grid(payload):
    """rosbags' reading of an OccupancyGrid payload."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE).deserialize_cdr(payload, "nav_msgs/msg/OccupancyGrid")
