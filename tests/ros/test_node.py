"""The node's core without middleware: newest map only, at most once per period, bad messages logged once."""
import numpy as np
import pytest

from crfmap.errors import InputError

from crfmap.ros.node import MapNode, RefineNode, refine_grid
from crfmap.ros.messages import GridMessage
from crfmap.io.nav2_values import nav2_values


def _native(stamp, width=2, data=(0, 100)):
    """A ROS 2-like message object, as a backend hands it over."""
    from types import SimpleNamespace as NS

    t = NS(sec=stamp, nanosec=0)
    pose = NS(position=NS(x=0.0, y=0.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))
    return NS(header=NS(stamp=t, frame_id="map"), data=list(data),
              info=NS(map_load_time=t, resolution=0.05, width=width, height=1, origin=pose))


def _refine_node(period):
    lines, sent = [], []
    node = RefineNode(period=period, refine=lambda grid: grid.with_probability(1 - grid.probability), log=lines.append)
    node.publishers["output"] = sent.append
    return node, lines, sent


def test_only_the_newest_map_is_refined_and_stale_ones_dropped():
    node, _, sent = _refine_node(period=10.0)
    for stamp in (1, 2, 3):
        node.on_grid(_native(stamp))
    assert node.step(100.0) == 10.0
    node.on_grid(_native(4))
    node.on_grid(_native(5))
    assert node.step(node.last_publish + 1.0) > 0  # within the period: nothing yet
    node.step(node.last_publish + 10.0)
    assert [m.stamp_ns // 10**9 for m in sent] == [3, 5]
    assert isinstance(sent[0], GridMessage) and sent[0].data.tolist() == [100, 0]
    assert "5 maps received, 2 refined and published, 3 dropped as stale" in node.summary()


def test_a_bad_map_is_logged_once_and_never_published():
    node, lines, sent = _refine_node(period=0.0)
    for stamp in (1, 2):
        node.on_grid(_native(stamp, width=3))
        node.step(float(stamp))
    node.on_grid(_native(3))
    node.step(3.0)
    skipped = [line for line in lines if line.startswith("skipping")]
    assert len(skipped) == 1 and "2 cells for a 3 x 1 grid" in skipped[0]
    assert [m.stamp_ns // 10**9 for m in sent] == [3]
    assert "2 on /map (data length)" in node.summary()


def test_an_empty_map_is_logged_as_empty_not_as_a_length_fault():
    node, lines, sent = _refine_node(period=0.0)
    node.on_grid(_native(1, width=0, data=()))
    node.step(1.0)
    assert lines == ["skipping a /map message: the map is empty (0 x 1 cells, no data): nothing to refine "
                     "[empty map; further ones are counted, not logged]"]
    assert sent == [] and "1 on /map (empty map)" in node.summary()


def test_refine_grid_is_crfmap_infer_default(tmp_path):
    from crfmap.cli import main
    from crfmap.grid import OccupancyGrid
    from crfmap.io.grid_files import load_grid
    from crfmap.io.npy_grid import save_npy

    rng = np.random.default_rng(0)
    grid = OccupancyGrid(np.where(rng.random((12, 10)) < 0.3, 0.5, rng.random((12, 10))))
    save_npy(grid, tmp_path / "in.npy")
    from crfmap.crf.presets import get_preset
    from crfmap.io.map_server import load_map
    from crfmap.io.nav2_values import nav2_values

    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy")]) == 0
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.yaml")]) == 0
    refined = get_preset().refine(grid)
    # a .npy gets the probabilities, a map for nav2 the gate's decision: what the node publishes
    assert np.array_equal(refined.beliefs.probability, load_grid(tmp_path / "out.npy").probability)
    assert np.array_equal(refine_grid(grid).probability, refined.nav2_map.probability)
    assert not np.array_equal(refined.beliefs.probability, refined.nav2_map.probability)  # the gate moved some cells
    assert np.array_equal(nav2_values(refine_grid(grid)), load_map(tmp_path / "out.yaml").to_int8())


def test_map_node_skips_bad_scans_and_waits_for_tf():
    from types import SimpleNamespace as NS

    lines = []
    node = MapNode((-5, -5, 5, 5), 0.1, log=lines.append)

    def scan(sec, increment=0.5):
        return NS(header=NS(stamp=NS(sec=sec, nanosec=0), frame_id="laser"), angle_min=-0.5, angle_max=0.5,
                  angle_increment=increment, range_min=0.1, range_max=5.0, ranges=[1.0, 2.0, 1.0])

    node.on_scan(scan(1, increment=0.0))
    node.on_scan(scan(0))
    node.on_scan(scan(2))
    assert [line.split("[")[1].split(";")[0] for line in lines] == ["angle_increment", "zero stamp"]
    node.step(0.0)
    assert node.integrated == 0 and len(node.waiting) == 1  # no tf yet


def test_map_node_accounts_for_every_scan_and_logs_the_integrated_ones(tmp_path):
    from types import SimpleNamespace as NS

    from crfmap.mapping import OnlineMapper

    def tf(sec, parent, child, x):
        return NS(transforms=[NS(header=NS(stamp=NS(sec=sec, nanosec=0), frame_id=parent), child_frame_id=child,
                                 transform=NS(translation=NS(x=x, y=0.0, z=0.0),
                                              rotation=NS(x=0.0, y=0.0, z=0.0, w=1.0)))])

    def scan(sec, ranges=(1.0, 2.0, 1.0)):
        return NS(header=NS(stamp=NS(sec=sec, nanosec=0), frame_id="laser"), angle_min=-0.5, angle_max=0.5,
                  angle_increment=0.5, range_min=0.1, range_max=5.0, ranges=list(ranges))

    log = tmp_path / "scans.txt"
    node = MapNode((-5, -5, 5, 5), 0.1, period=0.0, log=lambda line: None, scan_log=log, mapper_options={"margin": 3})
    sent = []
    node.publishers.update(map=sent.append, metadata=lambda msg: None)
    node.on_tf_static(tf(0, "base_link", "laser", 0.1))
    for sec, x in ((1, 0.0), (3, 1.0)):
        node.on_tf(tf(sec, "odom", "base_link", x))
    for sec in (2, 3, 4):
        node.on_scan(scan(sec))
    node.on_scan(scan(5, ranges=(1.0, 2.0)))  # another sensor's geometry: skipped, counted
    while node.step(10.0) == 0.0:  # 0: more scans are ready
        pass
    node.close()
    lines = [line.split() for line in log.read_text().splitlines()]
    assert [int(v[0]) for v in lines] == [2_000_000_000, 3_000_000_000]  # 4 waits for tf
    poses = np.array([[float(c) for c in v[1:]] for v in lines])
    np.testing.assert_allclose(poses, [[0.6, 0.0, 0.0], [1.1, 0.0, 0.0]])
    assert node.summary().startswith("2 scans integrated of 3 received, 1 still waiting for tf; skipped: 1 on /scan")
    # the logged scans rebuild the published map exactly
    mapper = OnlineMapper.for_sensor((-5, -5, 5, 5), 0.1, -0.5, 0.5, 3, 0.1, 5.0, margin=3)
    for pose in poses:
        mapper.integrate(np.array([1.0, 2.0, 1.0], np.float32), pose)
    assert np.array_equal(sent[-1].data, nav2_values(mapper.nav2_map()).reshape(-1))


def _room_recording(n=10, beams=91, seed=3):
    """Scans in a 4 m x 3 m box room (analytic ranges), with their laser poses."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(-2.0, 2.0, beams)
    poses = np.column_stack([rng.uniform(0.8, 3.2, n), rng.uniform(0.8, 2.2, n), rng.uniform(-np.pi, np.pi, n)])
    a = poses[:, 2:3] + angles
    c, s = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (4.0 - poses[:, :1]) / c, np.where(c < 0, -poses[:, :1] / c, np.inf))
        ty = np.where(s > 0, (3.0 - poses[:, 1:2]) / s, np.where(s < 0, -poses[:, 1:2] / s, np.inf))
    return np.minimum(tx, ty).astype(np.float32), angles, poses


class _LoopBackend:
    """A backend without middleware: delivers the given messages in order through spin_once, then stops the node."""

    def __init__(self, messages, stop):
        self.messages, self.stop, self.callbacks, self.sent = list(messages), stop, {}, {}

    def subscribe(self, topic, kind, profile, callback):
        self.callbacks[topic] = callback

    def publisher(self, topic, kind, profile):
        return self.sent.setdefault(topic, []).append

    def spin_once(self, timeout):
        if self.messages:
            topic, msg = self.messages.pop(0)
            self.callbacks[topic](msg)
        elif timeout > 0:  # nothing left and the node waits for nothing: the run is over
            self.stop.set()


@pytest.mark.parametrize("preset", [None, "certainty"])
def test_map_node_final_map_is_the_presets_offline_refinement(tmp_path, preset):
    """The node (default preset, or named) publishes on stop the map the same preset's offline refinement makes of
    the scans it integrated (count_hits at the logged laser poses, then Preset.refine). Tolerance: 2e-3 in P (the
    node's float32 messages and both runs' tol 1e-5), and the published 0..100 values within 1."""
    import threading
    from types import SimpleNamespace as NS

    from crfmap.crf.presets import DEFAULT_PRESET, get_preset
    from crfmap.mapping.builder import count_hits
    from crfmap.recording import ScanSet
    from crfmap.ros.node import spin

    ranges, angles, poses = _room_recording()
    bounds = (-1.0, -1.0, 5.0, 4.0)  # [m] a metre round the room: cells beyond the margin stay unknown

    def tf(sec, pose):
        return NS(transforms=[NS(header=NS(stamp=NS(sec=sec, nanosec=0), frame_id="odom"), child_frame_id="laser",
                                 transform=NS(translation=NS(x=pose[0], y=pose[1], z=0.0),
                                              rotation=NS(x=0.0, y=0.0, z=np.sin(pose[2] / 2), w=np.cos(pose[2] / 2))))])

    def scan(sec, r):
        return NS(header=NS(stamp=NS(sec=sec, nanosec=0), frame_id="laser"), angle_min=float(angles[0]),
                  angle_max=float(angles[-1]), angle_increment=float(angles[1] - angles[0]), range_min=0.05,
                  range_max=8.0, ranges=r.tolist())

    messages = []
    for i, (r, pose) in enumerate(zip(ranges, poses)):  # a still robot per scan: tf just before and at the stamp
        messages += [("/tf", tf(10 * i + 9, pose)), ("/tf", tf(10 * i + 10, pose)), ("/scan", scan(10 * i + 10, r))]
    messages.append(("/tf", tf(10 * len(poses) + 10, poses[-1])))
    options = {"radius": 1.0} if preset is None else {"radius": 1.0, "preset": preset}
    log = tmp_path / "scans.txt"
    lines = []
    node = MapNode(bounds, 0.1, period=0.0, mapper_options=options, log=lines.append, scan_log=log)
    stop = threading.Event()
    backend = _LoopBackend(messages, stop)
    summary = spin(node, backend, stop, log=lambda line: None)
    node.close()
    assert summary.startswith(f"{len(poses)} scans integrated of {len(poses)} received")
    final = backend.sent["/map"][-1]  # a GridMessage, as the node hands it to a backend
    assert final.stamp_ns == node.last_stamp_ns and len(backend.sent["/map"]) >= 2  # per-scan maps, then the final
    assert any(line.startswith(f"final map ({DEFAULT_PRESET if preset is None else preset} preset") for line in lines)

    logged = np.array([[float(v) for v in line.split()[1:]] for line in log.read_text().splitlines()])
    np.testing.assert_allclose(logged, poses, atol=1e-9)  # tf placed each scan where it was taken
    scans = ScanSet(ranges, float(angles[0]), float(angles[1] - angles[0]), 0.05, 8.0, logged,
                    np.arange(len(poses), dtype=float))
    occupied, empty = count_hits(scans, 0.1, bounds=bounds)
    assert occupied.shape == (final.height, final.width)
    offline = get_preset(preset or DEFAULT_PRESET).refine(hits=occupied, passes=empty, dtype=np.float64)
    assert offline.converged
    np.testing.assert_allclose(node.mapper.beliefs().probability, offline.beliefs.probability, atol=2e-3)
    published = final.data.reshape(final.height, final.width).astype(int)
    expected = nav2_values(offline.nav2_map).astype(int)  # what nav2 reads: 100 / 0 / -1
    assert set(np.unique(published)) <= {-1, 0, 100}
    assert np.mean(published != expected) < 1e-3  # only cells within 2e-3 of a threshold may differ
    assert (published == -1).any() and (published == 100).sum() >= 0.9 * (expected == 100).sum() > 0


def test_the_node_publishes_what_nav2_reads_or_percent_when_asked():
    """trinary (default): 100 / 0 / -1 as map_server publishes crfmap infer's file (nav2's costmap makes every value
    below 100 free: a wall at P = 0.9 published as 90 would be driven through); percent: P x 100."""
    from crfmap.grid import OccupancyGrid
    from crfmap.ros.messages import grid_out

    grid = OccupancyGrid(np.array([[0.9, 0.3, 0.1, 0.5]]))
    assert grid_out(grid, 1, "map").data.tolist() == [100, -1, 0, -1]
    assert grid_out(grid, 1, "map", "percent").data.tolist() == [90, 30, 10, -1]
    with pytest.raises(InputError, match="values"):
        RefineNode(values="scale")
