"""The live node's core, shared by every middleware: refine maps as they come (:class:`RefineNode`), or map from
scans and tf (:class:`MapNode`).

A message the node cannot use is skipped and logged once per kind with the reason (:class:`BadMessages`); no map is
published from one. :func:`spin` runs a node over a backend, which only moves messages: ``subscribe(topic, kind, qos,
callback)``, ``publisher(topic, kind, qos) -> send(GridMessage)``, ``spin_once(timeout)``, ``close()``; ``kind`` is
'grid', 'metadata', 'scan' or 'tf'."""
from __future__ import annotations

import queue
import sys
import time
from collections import deque
from dataclasses import dataclass

from crfmap.errors import InputError
from crfmap.ros import qos
from crfmap.io.nav2_values import VALUE_MODES, occupancy_values
from crfmap.ros.messages import (BadMessage, check_scan, grid_message, grid_out, occupancy_grid, same_geometry,
                                 scan_message, transforms_of)
from crfmap.ros.tf_buffer import TfBuffer, stamp_seconds
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfmap.mapping import OnlineMapper

SLICE_SECONDS = 0.05  # map mode integrates scans for at most this long before the backend spins again
IDLE_SECONDS = 0.1  # longest wait for messages between two looks at the stop flag


def refine_grid(grid):
    """The default preset's refinement of ``grid`` as nav2 gets it: the map ``crfmap infer IN OUT.yaml`` writes.

    >>> import numpy as np
    >>> from crfmap.grid import OccupancyGrid
    >>> g = OccupancyGrid(np.array([[0.5, 1.0, 0.0, 0.5]]))
    >>> refine_grid(g).shape
    (1, 4)
    """
    return get_preset(DEFAULT_PRESET).refine(grid).nav2_map  # the preset's own solver, as crfmap infer runs it


def log_line(text):
    print(f"crfmap node: {text}", file=sys.stderr, flush=True)


class BadMessages:
    """Skipped messages, counted per (topic, kind); the first of each kind is logged with its reason."""

    def __init__(self, log=log_line):
        self.log = log
        self.counts = {}

    def report(self, topic, exc: BadMessage):
        key = (topic, exc.kind)
        self.counts[key] = self.counts.get(key, 0) + 1
        if self.counts[key] == 1:
            self.log(f"skipping a {topic} message: {exc.reason} [{exc.kind}; further ones are counted, not logged]")

    def summary(self) -> str:
        return ", ".join(f"{n} on {topic} ({kind})" for (topic, kind), n in sorted(self.counts.items())) or "none"


@dataclass
class Subscription:
    topic: str
    kind: str
    profile: qos.Profile
    handler: object


def check_values(values: str) -> str:
    if values not in VALUE_MODES:
        raise InputError("values", f"must be one of {', '.join(VALUE_MODES)}, got {values!r}")
    return values


class RefineNode:
    """Refine the newest map of ``input_topic`` (:func:`refine_grid`) and publish it on ``output_topic`` with the
    input's header and info, at most once per ``period`` [s]. Maps arriving meanwhile replace each other (stale ones
    are dropped, not queued)."""

    def __init__(self, input_topic="/map", output_topic="/map_refined", period=1.0, refine=refine_grid, log=log_line,
                 values="trinary"):
        self.input_topic, self.output_topic = input_topic, output_topic
        self.values = check_values(values)  # trinary: what nav2's costmap reads right (see crfmap.io.nav2_values)
        self.period = float(period)
        self.refine = refine
        self.log = log
        self.bad = BadMessages(log)
        self.subscriptions = [Subscription(input_topic, "grid", qos.MAP, self.on_grid)]
        self.publications = {"output": (output_topic, "grid", qos.MAP)}
        self.publishers = {}
        self.pending = None  # the newest map not yet refined (native message)
        self.received = self.published = 0
        self.last_publish = -float("inf")

    def on_grid(self, native):
        self.received += 1
        self.pending = native  # a newer map replaces one still waiting: stale maps are dropped

    def step(self, now) -> float:
        """Refine and publish the newest map if one waits and the period allows; seconds until the next call."""
        if self.pending is None:
            return IDLE_SECONDS
        wait = self.last_publish + self.period - now
        if wait > 0:
            return wait
        native, self.pending = self.pending, None
        try:
            msg = grid_message(native)
            grid = occupancy_grid(msg)
        except BadMessage as exc:
            self.bad.report(self.input_topic, exc)
            return 0.0
        t0 = time.perf_counter()
        refined = self.refine(grid)
        self.publishers["output"](msg.with_data(occupancy_values(refined, self.values)))
        self.published += 1
        self.last_publish = time.monotonic()
        self.log(f"refined {self.input_topic} ({msg.width} x {msg.height} cells, stamp {stamp_seconds(msg.stamp_ns):.3f} s) "
                 f"in {time.perf_counter() - t0:.2f} s -> {self.output_topic}")
        return self.period

    def summary(self) -> str:
        dropped = self.received - self.published - sum(self.bad.counts.values()) - (self.pending is not None)
        return (f"{self.received} maps received, {self.published} refined and published, {dropped} dropped as stale; "
                f"skipped: {self.bad.summary()}")


class MapNode:
    """Map online from ``scan_topic`` and tf, each scan at its stamp once tf covers it (:mod:`crfmap.ros.tf_buffer`);
    publish ``map_topic`` and ``metadata_topic`` at most once per ``period`` [s]. ``bounds`` (xmin, ymin, xmax, ymax)
    [m] and ``resolution`` [m] fix the grid (it does not grow); ``fixed_frame`` None: the tf tree's root at the first
    scan. ``mapper_options`` go to :meth:`crfmap.mapping.OnlineMapper.for_sensor`. ``scan_log``: a file of one line per
    integrated scan (stamp [ns], laser pose x y yaw in the fixed frame), so a published map can be rebuilt exactly."""

    def __init__(self, bounds, resolution=0.05, scan_topic="/scan", map_topic="/map", metadata_topic="/map_metadata",
                 fixed_frame=None, period=1.0, mapper_options=None, log=log_line, max_waiting=1000, scan_log=None,
                 values="trinary"):
        self.bounds = tuple(float(v) for v in bounds)
        self.values = check_values(values)
        self.resolution = float(resolution)
        self.scan_topic, self.map_topic, self.metadata_topic = scan_topic, map_topic, metadata_topic
        self.fixed_frame = fixed_frame
        self.period = float(period)
        self.mapper_options = dict(mapper_options or {})
        self.log = log
        self.bad = BadMessages(log)
        self.subscriptions = [Subscription(scan_topic, "scan", qos.SCAN, self.on_scan),
                              Subscription("/tf", "tf", qos.TF, self.on_tf),
                              Subscription("/tf_static", "tf", qos.TF_STATIC, self.on_tf_static)]
        self.publications = {"map": (map_topic, "grid", qos.MAP), "metadata": (metadata_topic, "metadata", qos.MAP)}
        self.publishers = {}
        self.tf = TfBuffer()
        self.waiting = deque()  # scans in arrival order, until tf covers their stamps
        self.max_waiting = int(max_waiting)
        self.first = None  # the first good scan: the sensor the mapper is made for
        self.mapper = None
        self.received = 0  # well-formed scans
        self.integrated = 0
        self.scan_log = None
        if scan_log is not None:
            try:
                self.scan_log = open(scan_log, "w", buffering=1, encoding="utf-8")  # line-buffered: readable as it grows
            except OSError as exc:
                raise InputError("--scan-log", f"cannot write {scan_log}: {exc.strerror}") from None
        self.published_scans = 0
        self.last_stamp_ns = None
        self.last_publish = -float("inf")

    # --- incoming ---------------------------------------------------------------------------------
    def on_scan(self, native):
        try:
            msg = scan_message(native)
            check_scan(msg)
            if msg.stamp_ns == 0:
                raise BadMessage("zero stamp", "a scan stamped 0 cannot be placed in time (tf2 reads 0 as 'latest')")
            if self.first is not None:
                same_geometry(msg, self.first)
        except BadMessage as exc:
            self.bad.report(self.scan_topic, exc)
            return
        if self.first is None:
            self.first = msg
        self.received += 1
        self.waiting.append(msg)
        if len(self.waiting) > self.max_waiting:
            self.waiting.popleft()
            self.bad.report(self.scan_topic, BadMessage("no tf", f"more than {self.max_waiting} scans wait for tf to "
                                                                 "reach their laser frame; the oldest is dropped"))

    def on_tf(self, native, static=False):
        transforms, faults = transforms_of(native)
        for exc in faults:
            self.bad.report("/tf_static" if static else "/tf", exc)
        for tr in transforms:
            self.tf.add(tr, static)

    def on_tf_static(self, native):
        self.on_tf(native, static=True)

    # --- work -------------------------------------------------------------------------------------
    def _make_mapper(self, scan):
        return OnlineMapper.for_sensor(self.bounds, self.resolution, scan.angle_min, scan.angle_increment,
                                       int(scan.ranges.size), scan.range_min, scan.range_max, **self.mapper_options)

    def _integrate_ready(self, deadline):
        while self.waiting and time.perf_counter() < deadline:
            scan = self.waiting[0]
            status, pose, frame = self.tf.lookup(scan.frame_id, stamp_seconds(scan.stamp_ns), self.fixed_frame)
            if status == "wait":
                return  # later scans wait too: scans are integrated in the order they came
            self.waiting.popleft()
            if status == "never":
                self.bad.report(self.scan_topic, BadMessage("before tf", "stamped before the first transform "
                                                                         "that places its laser frame"))
                continue
            if self.fixed_frame is None:
                self.fixed_frame = frame
                self.log(f"mapping in frame '{frame}' (the root of the tf tree)")
            if self.mapper is None:
                self.mapper = self._make_mapper(self.first)
            try:
                self.mapper.integrate(scan.ranges, pose)
            except InputError as exc:  # e.g. the laser outside the grid's bounds
                self.bad.report(self.scan_topic, BadMessage("outside the map", exc.problem))
                continue
            self.integrated += 1
            self.last_stamp_ns = scan.stamp_ns
            if self.scan_log is not None:
                self.scan_log.write(f"{scan.stamp_ns} {pose[0]!r} {pose[1]!r} {pose[2]!r}\n")

    def step(self, now) -> float:
        """Integrate the scans tf now covers (for a slice of time), publish if due; seconds until the next call."""
        self._integrate_ready(time.perf_counter() + SLICE_SECONDS)
        if self.integrated > self.published_scans and now >= self.last_publish + self.period:
            out = grid_out(self.mapper.nav2_map(), self.last_stamp_ns, self.fixed_frame, self.values)
            self.publishers["map"](out)
            self.publishers["metadata"](out)
            self.published_scans = self.integrated
            self.last_publish = now
        if self.waiting and self.tf.lookup(self.waiting[0].frame_id, stamp_seconds(self.waiting[0].stamp_ns),
                                           self.fixed_frame)[0] != "wait":
            return 0.0  # more scans are ready
        if self.integrated > self.published_scans:
            return max(self.last_publish + self.period - now, 0.0)
        return IDLE_SECONDS

    def finish(self):
        """Converge the whole map (LBP until the preset's tol: its offline refinement of the scans) and publish it."""
        if self.mapper is None:
            return
        result = self.mapper.finish()
        out = grid_out(result.nav2_map, self.last_stamp_ns, self.fixed_frame, self.values)
        self.publishers["map"](out)
        self.publishers["metadata"](out)
        self.log(f"final map ({self.mapper.preset.name} preset, {self.integrated} scans): whole-grid LBP "
                 f"{result.summary()}, {result.seconds:.2f} s -> {self.map_topic}")

    def summary(self) -> str:
        return (f"{self.integrated} scans integrated of {self.received} received, {len(self.waiting)} still waiting "
                f"for tf; skipped: {self.bad.summary()}")

    def close(self):
        if self.scan_log is not None:
            self.scan_log.close()
            self.scan_log = None


def spin(node, backend, stop, log=log_line):
    """Run ``node`` over ``backend`` until ``stop`` (a threading.Event) is set; returns the node's summary, with the
    samples a backend lost in transport (``lost() -> {topic: count}``). Callbacks only queue (some backends call them
    from their own threads), so the node's state needs no lock."""
    inbox = queue.SimpleQueue()
    for sub in node.subscriptions:
        backend.subscribe(sub.topic, sub.kind, sub.profile, lambda msg, h=sub.handler: inbox.put((h, msg)))
        log(f"subscribed to {sub.topic} ({sub.profile.describe()})")
    for name, (topic, kind, profile) in node.publications.items():
        node.publishers[name] = backend.publisher(topic, kind, profile)
        log(f"publishing {topic} ({profile.describe()})")
    wait = 0.0
    while not stop.is_set():
        backend.spin_once(min(max(wait, 0.0), IDLE_SECONDS))
        while True:
            try:
                handler, msg = inbox.get_nowait()
            except queue.Empty:
                break
            handler(msg)
        if stop.is_set():
            break
        wait = node.step(time.monotonic())
    getattr(node, "finish", lambda: None)()  # the map node's converged final map, while the backend still runs
    lost = getattr(backend, "lost", dict)()
    return node.summary() + "".join(f"; lost in transport on {topic}: {n}" for topic, n in lost.items() if n)
