"""The node's core without middleware: newest map only, at most once per period, bad messages logged once."""
import numpy as np

from crfmap.ros.node import MapNode, RefineNode, refine_grid
from crfmap.ros.messages import GridMessage


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


def test_refine_grid_is_crfmap_infer_default(tmp_path):
    from crfmap.cli import main
    from crfmap.grid import OccupancyGrid
    from crfmap.io.grid_files import load_grid
    from crfmap.io.npy_grid import save_npy

    rng = np.random.default_rng(0)
    grid = OccupancyGrid(np.where(rng.random((12, 10)) < 0.3, 0.5, rng.random((12, 10))))
    save_npy(grid, tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy")]) == 0
    assert np.array_equal(refine_grid(grid).probability, load_grid(tmp_path / "out.npy").probability)


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
    assert np.array_equal(sent[-1].data, mapper.beliefs().to_int8().reshape(-1))
