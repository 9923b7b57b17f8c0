"""ROS 2 without a ROS install: the node's topics over Eclipse Cyclone DDS, on ROS 2's wire conventions.

As rmw_cyclonedds_cpp (``create_readwrite_qos``, ``make_fqtopic``): domain ``ROS_DOMAIN_ID`` (default 0); ROS topic
``/map`` is DDS topic ``rt/map`` of type ``nav_msgs::msg::dds_::OccupancyGrid_`` (:mod:`crfmap.ros.dds_types`); samples
XCDR1, little-endian; QoS :func:`dds_qos`. No ``ros_discovery_info``: ROS 2 tools list the topics but not a node name.

>>> ros_topic_name("/map"), ros_topic_name("scan")
('rt/map', 'rt/scan')
"""
from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from types import SimpleNamespace

from crfmap.errors import InputError
from crfmap.ros import qos as ros_qos, dds_types as types
from crfmap.ros.messages import stamp_parts
from crfmap.ros.dds_types import TYPES


def ros_topic_name(topic: str) -> str:
    """The DDS topic of a ROS 2 topic (node namespace '/'): 'rt/' and the name without its leading '/'."""
    return "rt/" + topic.lstrip("/")


def domain_id(value=None) -> int:
    """The DDS domain: ``value``, else ROS_DOMAIN_ID, else 0 (ROS 2 allows 0..232 with the default ports)."""
    raw = value if value is not None else os.environ.get("ROS_DOMAIN_ID", "0") or "0"
    try:
        number = int(raw)
    except (TypeError, ValueError):
        raise InputError("ROS_DOMAIN_ID" if value is None else "--domain", f"must be a whole number, got {raw!r}") from None
    if not 0 <= number <= 232:
        raise InputError("ROS_DOMAIN_ID" if value is None else "--domain", f"must be in 0..232, got {number}")
    return number


def dds_configuration(value=None) -> str | None:
    """The Cyclone DDS configuration ``value`` (default: ``$CYCLONEDDS_URI``), checked; None when unset or empty.

    A comma-separated list of files (``file://`` or paths) and inline XML (``<...>``): a file that is missing or
    unreadable, or text that is neither, is an InputError now, not a ``DDSException`` without reason later.

    >>> dds_configuration("<CycloneDDS/>")
    '<CycloneDDS/>'
    >>> dds_configuration("/no/such/cyclonedds.xml")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: CYCLONEDDS_URI: names /no/such/cyclonedds.xml, which is not a readable file (No such file or directory)
    """
    raw = os.environ.get("CYCLONEDDS_URI") if value is None else value
    if raw is None:
        return None
    if not raw.strip():
        return None  # Cyclone reads an empty one as unset
    for item in (part.strip() for part in raw.split(",")):
        if not item or item.startswith("<"):
            continue  # inline XML: Cyclone parses it (a parse error is caught where the participant is made)
        path = item[len("file://"):] if item.startswith("file://") else item
        if "://" in path:
            raise InputError("CYCLONEDDS_URI", f"{item!r} is neither a file nor inline XML (<CycloneDDS>...)")
        try:
            with open(path, "rb") as f:
                f.read(1)
        except OSError as exc:
            raise InputError("CYCLONEDDS_URI", f"names {path}, which is not a readable file ({exc.strerror or exc})"
                             ) from None
    return raw


@contextlib.contextmanager
def _c_stderr():
    """Inside the block, what C code writes to file descriptor 2 goes to a temporary file; ``.text`` after it."""
    said = SimpleNamespace(text="")
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with tempfile.TemporaryFile() as f:
            os.dup2(f.fileno(), 2)
            try:
                yield said
            finally:
                os.dup2(saved, 2)
                f.seek(0)
                said.text = f.read(65536).decode("utf-8", "replace")
    finally:
        os.close(saved)


def _last_message(text: str) -> str:
    """Cyclone's last log line without its time stamp and thread name.

    >>> _last_message("1796408090.326618 [0]     python: nosuch0: does not match an available interface.\\n")
    'nosuch0: does not match an available interface.'
    """
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    if not lines:
        return ""
    head, _, rest = lines[-1].partition("]")
    return rest.split(":", 1)[1].strip() if rest and ":" in rest else lines[-1]


def dds_qos(profile: ros_qos.Profile, reader=False):
    """The Cyclone DDS QoS of a :class:`crfmap.ros.qos.Profile`, as rmw_cyclonedds_cpp maps it: reliable (infinite
    blocking) or best effort, volatile or transient local with the durability service keeping the writer's history,
    liveliness automatic, no auto-dispose."""
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration

    depth = profile.reader_depth if reader and profile.reader_depth else profile.depth
    history = Policy.History.KeepLast(depth)
    policies = [
        history,
        Policy.Reliability.Reliable(duration(infinite=True)) if profile.reliable else Policy.Reliability.BestEffort,
        Policy.Liveliness.Automatic(duration(infinite=True)),
        Policy.DataRepresentation(use_cdrv0_representation=True),  # XCDR1, as ROS 2's type support
    ]
    if profile.transient_local:
        policies += [Policy.Durability.TransientLocal,
                     Policy.DurabilityService(cleanup_delay=0, history=history, max_samples=-1, max_instances=-1,
                                              max_samples_per_instance=-1)]
    else:
        policies.append(Policy.Durability.Volatile)
    if not reader:
        policies.append(Policy.WriterDataLifecycle(autodispose=False))
    return Qos(*policies)


def _time(types, ns):
    sec, nanosec = stamp_parts(ns)
    return types.Time(sec=sec, nanosec=nanosec)


def _info(types, msg):
    x, y, z, qx, qy, qz, qw = msg.origin
    return types.MapMetaData(
        map_load_time=_time(types, msg.map_load_ns), resolution=float(msg.resolution), width=int(msg.width),
        height=int(msg.height), origin=types.Pose(position=types.Point(x=x, y=y, z=z),
                                                  orientation=types.Quaternion(x=qx, y=qy, z=qz, w=qw)))


def native_message(kind, msg):
    """The Cyclone DDS sample of a :class:`crfmap.ros.messages.GridMessage` for a 'grid' or 'metadata' topic."""
    if kind == "metadata":
        return _info(types, msg)
    return types.OccupancyGrid(header=types.Header(stamp=_time(types, msg.stamp_ns), frame_id=msg.frame_id),
                               info=_info(types, msg), data=msg.data.astype("int8", copy=False).tolist())


class DdsBackend:
    """The node's middleware over Cyclone DDS (one participant on ``domain``; see the module docstring)."""

    def __init__(self, domain=None):
        try:
            from cyclonedds.core import WaitSet
            from cyclonedds.domain import DomainParticipant
        except ImportError:
            raise InputError("--backend dds", "needs the cyclonedds package (pip install 'crfmap[ros]')") from None
        from cyclonedds.core import DDSException

        number = domain_id(domain)
        configuration = dds_configuration()
        with _c_stderr() as said:  # Cyclone prints its reason for a refused configuration on stderr
            try:
                self.participant = DomainParticipant(number)
            except DDSException:
                self.participant = None
        if self.participant is None:  # the reason in the one error line, not a second line above it
            what = "CYCLONEDDS_URI" if configuration else ("ROS_DOMAIN_ID" if domain is None else "--domain")
            reason = _last_message(said.text) or f"no DDS participant could be made on domain {number}"
            raise InputError(what, f"Cyclone DDS refused it: {reason}")
        if said.text:  # warnings of a participant that works: the user's to see
            sys.stderr.write(said.text)
        self.waitset = WaitSet(self.participant)
        self.readers = []  # (reader, callback, batch)
        self.topics = {}  # reader -> ROS topic, for lost()
        self.keep = []  # writers, topics and conditions stay alive with the backend

    def _topic(self, topic, kind):
        from cyclonedds.topic import Topic

        t = Topic(self.participant, ros_topic_name(topic), TYPES[kind])
        self.keep.append(t)
        return t

    def subscribe(self, topic, kind, profile, callback):
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState
        from cyclonedds.sub import DataReader

        reader = DataReader(self.participant, self._topic(topic, kind), qos=dds_qos(profile, reader=True))
        condition = ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any)
        self.waitset.attach(condition)
        self.keep.append(condition)
        self.readers.append((reader, callback, profile.reader_depth or profile.depth))
        self.topics[reader] = topic
        return reader

    def lost(self) -> dict:
        """{topic: samples lost in transport (DDS sample-lost status) or rejected by a full reader}."""
        out = {}
        for reader, _, _ in self.readers:
            n = reader.get_sample_lost_status().total_count + reader.get_sample_rejected_status().total_count
            out[self.topics[reader]] = out.get(self.topics[reader], 0) + n
        return out

    def publisher(self, topic, kind, profile):
        from cyclonedds.pub import DataWriter

        writer = DataWriter(self.participant, self._topic(topic, kind), qos=dds_qos(profile))
        self.keep.append(writer)
        return lambda msg: writer.write(native_message(kind, msg))

    def spin_once(self, timeout):
        from cyclonedds.sub import InvalidSample
        from cyclonedds.util import duration

        self.waitset.wait(duration(seconds=max(float(timeout), 0.0)))
        for reader, callback, batch in self.readers:
            for sample in reader.take(N=batch):
                # an InvalidSample carries no data: it tells of an instance state change (a publisher left)
                if not isinstance(sample, InvalidSample):
                    callback(sample)

    def close(self):
        self.readers.clear()
        self.topics.clear()
        self.keep.clear()
        self.waitset = None
        self.participant = None  # deleting the participant deletes its entities
