"""Live node rows of ``crfmap bench``: map in -> refined map out over real DDS, and scans per second in map mode.

- ``node-refine-<map>``: the node (``crfmap node refine`` as its own process, Cyclone DDS on
  loopback) gets the Intel map (built at 5 cm) or the Olin map; the row times each map from
  the publisher's write to the refined map's arrival (serialising, transport both ways and the
  refinement), median of ``repeats``.
- ``node-map-olin``: the map mode's core (:class:`crfmap.ros.node.MapNode`, no middleware) fed
  the Olin bag's tf and scans as fast as it takes them: scans per second it sustains, against
  the bag's own scan rate.
- ``memory-infer-default`` / ``memory-node-refine``: peak memory a cell of one map refined with the default preset,
  as ``crfmap infer`` and as the refine node do it (:func:`bench_node_memory`), printed side by side.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from crfstudy.bench.common import INTEL, record
from crfmap.data import data_file, have_data
from crfmap.io.carmen import read_carmen
from crfmap.io.grid_files import load_grid
from crfmap.mapping import build_grid
from crfmap.ros import dds_types, qos
from crfmap.ros.dds import dds_qos, native_message
from crfmap.ros.messages import grid_out
from crfmap.io.bag_reader import read_bag
from crfmap.mapping.builder import scan_bounds
from crfmap.ros.node import MapNode

OLIN_MAP = "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml"
OLIN_BAG = "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2"
LOOPBACK = ('<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>'
            '<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>'
            '<MaxAutoParticipantIndex>30</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers>'
            '</Discovery></Domain></CycloneDDS>')
TIMEOUT = 600.0  # [s] per map, for a loaded machine


def _maps(quick):
    out = {}
    if have_data(INTEL):
        out["intel"] = build_grid(read_carmen(data_file(INTEL)).scans, 0.1 if quick else 0.05)
    if have_data(OLIN_MAP) and not quick:
        out["olin"] = load_grid(data_file(OLIN_MAP))
    return out


def bench_node_refine(quick=False, repeats=3):
    """Rows ``node-refine-intel`` and ``node-refine-olin`` (quick: Intel at 10 cm only)."""
    try:
        import cyclonedds  # noqa: F401
    except ImportError:
        return [record("node-refine", note="skipped: cyclonedds not installed (pip install 'crfmap[ros]')")]
    maps = _maps(quick)
    if not maps:
        return [record("node-refine", note="skipped: the shared data was not found")]
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "cyclonedds.xml"
        config.write_text(LOOPBACK)
        env = dict(os.environ, CYCLONEDDS_URI=config.as_uri(), ROS_DOMAIN_ID=str(200 + os.getpid() % 30))
        previous = {k: os.environ.get(k) for k in ("CYCLONEDDS_URI", "ROS_DOMAIN_ID")}
        os.environ.update({k: env[k] for k in previous})
        log = open(Path(tmp) / "node.log", "w+")
        node = subprocess.Popen([sys.executable, "-m", "crfmap", "node", "refine", "--period", "0"], env=env,
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log)
        try:
            return [_time_refine(name, grid, repeats, node, log) for name, grid in maps.items()]
        finally:
            node.send_signal(signal.SIGTERM)
            node.wait(timeout=TIMEOUT)
            log.close()
            for k, v in previous.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v


def _node_failed(node, log, name, grid):
    """The row saying the node process ended before answering (its last log line), or None while it runs."""
    if node.poll() is None:
        return None
    log.seek(0)
    lines = [line.strip() for line in log.read().splitlines() if line.strip()]
    return record(f"node-refine-{name}", grid.width, np.float64, 1, None,
                  note=f"the node exited with code {node.returncode}: {lines[-1] if lines else 'no output'}")


def _time_refine(name, grid, repeats, node, log):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    participant = DomainParticipant(int(os.environ["ROS_DOMAIN_ID"]))
    writer = DataWriter(participant, Topic(participant, "rt/map", dds_types.OccupancyGrid), qos=dds_qos(qos.MAP))
    reader = DataReader(participant, Topic(participant, "rt/map_refined", dds_types.OccupancyGrid),
                        qos=dds_qos(qos.MAP, reader=True))
    deadline = time.monotonic() + TIMEOUT
    while not writer.get_matched_subscriptions() and time.monotonic() < deadline:
        if (failed := _node_failed(node, log, name, grid)) is not None:
            return failed
        time.sleep(0.05)
    seconds = []
    for k in range(repeats + 1):  # the first loads the kernels
        stamp = 1_700_000_000_000_000_000 + k
        msg = grid_out(grid, stamp, "map")
        t0 = time.perf_counter()
        writer.write(native_message("grid", msg))
        got = None
        while got is None and time.monotonic() < deadline:
            for sample in reader.take(N=4):
                s = sample.header.stamp
                if s.sec * 1_000_000_000 + s.nanosec == stamp:
                    got = time.perf_counter() - t0
            if got is None and (failed := _node_failed(node, log, name, grid)) is not None:
                return failed
            time.sleep(0.001)
        if got is None:
            return record(f"node-refine-{name}", grid.width, np.float64, 1, None, note="timed out")
        if k:
            seconds.append(got)
    return record(f"node-refine-{name}", grid.width, np.float64, 1, None, latency_seconds_median=float(np.median(seconds)),
                  latency_seconds=seconds, shape=list(grid.shape), cells=int(grid.probability.size),
                  note="publisher write -> refined map received, Cyclone DDS loopback, node in its own process")


def bench_node_map(quick=False):
    """Row ``node-map-olin``: scans per second the map mode's core sustains on the Olin bag."""
    if not have_data(OLIN_BAG):
        return [record("node-map-olin", note="skipped: the shared data was not found")]
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    bag = data_file(OLIN_BAG)
    bounds = scan_bounds(read_bag(bag).scans)
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        wanted = {"/scan", "/tf", "/tf_static"}
        messages = [(c.topic, reader.deserialize(raw, c.msgtype))
                    for c, _, raw in reader.messages(connections=[c for c in reader.connections if c.topic in wanted])]
    if quick:
        messages = messages[: len(messages) // 4]

    def run_once():
        node = MapNode(bounds, 0.05, period=1e9, mapper_options={"radius": 4.0, "margin": 3}, log=lambda text: None)
        node.publishers = {"map": lambda msg: None, "metadata": lambda msg: None}
        handlers = {"/scan": node.on_scan, "/tf": node.on_tf, "/tf_static": node.on_tf_static}
        t0 = time.perf_counter()
        for topic, msg in messages:
            handlers[topic](msg)
            if topic == "/scan":
                node.step(time.monotonic())
        while node.step(time.monotonic()) == 0.0:
            pass
        return node.integrated, time.perf_counter() - t0

    run_once()  # loads the kernels
    scans, seconds = run_once()
    stamps = [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for t, m in messages if t == "/scan"]
    bag_rate = (len(stamps) - 1) / (max(stamps) - min(stamps)) if len(stamps) > 1 else None
    return [record("node-map-olin", None, np.float32, 1, None, scans=scans, seconds_total=seconds,
                   scans_per_second=scans / seconds, bag_scans_per_second=bag_rate,
                   beams=int(len(messages and next(m for t, m in messages if t == "/scan").ranges)),
                   note="MapNode core fed the bag's tf and scans (no middleware), OnlineMapper radius 4 m, margin 3")]


_PEAK = (
    "import numpy as np\n"
    "def status(key):\n"
    "    for line in open('/proc/self/status'):\n"
    "        if line.startswith(key):\n"
    "            return int(line.split()[1]) * 1024\n"
    "def peak_since(base):\n"
    "    return status('VmHWM') - base\n"
    "def reset():\n"
    "    open('/proc/self/clear_refs', 'w').write('5')\n"
    "    return status('VmRSS')\n"
    "def building(n):  # a map-like grid: free space, walls, unknown, as P in [0, 1]\n"
    "    rng = np.random.default_rng(0)\n"
    "    p = np.full((n, n), 0.5)\n"
    "    p[n // 8: -n // 8, n // 8: -n // 8] = 0.1\n"
    "    p[::40, :] = 0.9\n"
    "    p[:, ::40] = 0.9\n"
    "    return np.where(rng.random((n, n)) < 0.02, 0.5, p)\n"
)

_INFER = _PEAK + (
    "from crfmap.crf.presets import get_preset\n"
    "from crfmap.grid import OccupancyGrid\n"
    "get_preset().refine(building(64))  # kernels loaded\n"
    "grid = OccupancyGrid(building({n}), 0.05)  # what load_grid gives crfmap infer\n"
    "base = reset()\n"
    "beliefs = get_preset().refine(grid).beliefs  # crfmap infer's work, default preset\n"
    "beliefs.to_int8()  # what the trinary map_server output is made of\n"
    "print(peak_since(base))\n"
)

_NODE = _PEAK + (
    "from types import SimpleNamespace as NS\n"
    "from crfmap.grid import OccupancyGrid\n"
    "from crfmap.ros.dds import native_message\n"
    "from crfmap.ros.messages import grid_out\n"
    "from crfmap.ros.node import RefineNode\n"
    "def native(n):  # the sample as Cyclone DDS hands it over: data a Python list of ints\n"
    "    msg = grid_out(OccupancyGrid(building(n), 0.05), 1, 'map')\n"
    "    stamp = NS(sec=0, nanosec=1)\n"
    "    o = NS(position=NS(x=0.0, y=0.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))\n"
    "    info = NS(map_load_time=stamp, resolution=0.05, width=n, height=n, origin=o)\n"
    "    return NS(header=NS(stamp=stamp, frame_id='map'), info=info, data=msg.data.tolist())\n"
    "def serialise(msg):  # what the dds backend's publisher does with the refined map\n"
    "    native_message('grid', msg).serialize()\n"
    "node = RefineNode(period=0.0, log=lambda text: None)\n"
    "node.publishers = {{'output': serialise}}\n"
    "node.on_grid(native(64)); node.step(1e18)  # kernels loaded (now: after any period)\n"
    "sample = native({n})\n"
    "base = reset()\n"
    "node.on_grid(sample)\n"
    "del sample\n"
    "node.step(1e18)\n"
    "print(peak_since(base))\n"
)


def bench_node_memory(size=4096):
    """Rows ``memory-infer-default`` and ``memory-node-refine``: peak memory per cell of refining one ``size``² map
    with the default preset as ``crfmap infer`` does (beyond its float64 input) and as ``crfmap node refine`` does
    (beyond the received sample, a Python list of ints as Cyclone DDS delivers it; converting, refining, the
    int8 output and the outgoing sample serialised). Each in a child process (Linux: /proc's high-water mark)."""
    rows = []
    for name, code, note in (
            ("memory-infer-default", _INFER, "peak beyond the float64 input: the default preset's refine and the "
                                             "int8 output (crfmap infer's work)"),
            ("memory-node-refine", _NODE, "peak beyond the received DDS sample (a Python list, 8 B a cell): "
                                          "message -> grid -> refine -> int8 -> outgoing sample serialised")):
        out = subprocess.run([sys.executable, "-c", code.format(n=int(size))], capture_output=True, text=True)
        if out.returncode != 0:
            rows.append(record(name, size, np.float64, 1, None, note=f"failed: {out.stderr.strip()[-300:]}"))
            continue
        peak = int(out.stdout.strip().splitlines()[-1])
        rows.append(record(name, size, np.float64, 1, None, peak_bytes=peak, bytes_per_cell=peak / size**2,
                           note=note))
    return rows
