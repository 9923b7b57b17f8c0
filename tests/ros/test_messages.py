"""Middleware-free messages: reading ROS 1 and ROS 2 message objects, and the checks that make the node skip one."""
import math
from types import SimpleNamespace as NS

import numpy as np
import pytest

from crfmap.ros.messages import (BadMessage, GridMessage, ScanMessage, check_scan, grid_message, grid_out,
                                 occupancy_grid, same_geometry, stamp_ns, transforms_of)


def _grid(**change):
    fields = dict(stamp_ns=7, frame_id="map", map_load_ns=7, resolution=0.05, width=3, height=2,
                  origin=(1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0), data=np.array([-1, 0, 100, 50, 20, -1], np.int8))
    fields.update(change)
    return GridMessage(**fields)


def test_grid_values_become_probabilities_and_back():
    grid = occupancy_grid(_grid())
    assert grid.resolution == 0.05 and grid.origin == (1.0, 2.0, 0.0)
    assert grid.probability[0].tolist() == [0.5, 0.0, 1.0]
    assert grid_out(grid, 7, "map", "percent").data.tolist() == [-1, 0, 100, 50, 20, -1]  # a known 50 stays 50
    assert grid_out(grid, 7, "map").data.tolist() == [-1, 0, 100, -1, 0, -1]  # as nav2 reads the written map


@pytest.mark.parametrize("change, kind", [
    ({"width": 4}, "data length"),
    ({"data": np.zeros(0, np.int8), "width": 0, "height": 0}, "empty map"),
    ({"data": np.zeros(0, np.int8), "width": 5, "height": 0}, "empty map"),
    ({"data": np.zeros(0, np.int8)}, "data length"),  # 0 cells for a 3 x 2 grid
    ({"resolution": float("nan")}, "resolution"),
    ({"resolution": -0.05}, "resolution"),
    ({"resolution": 0.0}, "resolution"),
    ({"origin": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)}, "non-unit quaternion"),
    ({"origin": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0)}, "non-unit quaternion"),
    ({"origin": (math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)}, "origin"),
    ({"data": np.array([-1, 0, 100, 50, 101, -5], np.int8)}, "values"),
])
def test_bad_grids_are_refused_with_their_kind(change, kind):
    with pytest.raises(BadMessage) as info:
        occupancy_grid(_grid(**change))
    assert info.value.kind == kind


def _scan(**change):
    fields = dict(stamp_ns=5, frame_id="laser", angle_min=-1.0, angle_max=1.0, angle_increment=1.0, range_min=0.1,
                  range_max=5.0, ranges=np.ones(3, np.float32))
    fields.update(change)
    return ScanMessage(**fields)


@pytest.mark.parametrize("change, kind", [
    ({"angle_increment": 0.0}, "angle_increment"),
    ({"angle_increment": float("nan")}, "angle_increment"),
    ({"ranges": np.ones(5, np.float32)}, "ranges vs angles"),
    ({"ranges": np.ones(0, np.float32)}, "no ranges"),
    ({"range_max": 0.05}, "range limits"),
])
def test_bad_scans_are_refused_with_their_kind(change, kind):
    check_scan(_scan())
    with pytest.raises(BadMessage) as info:
        check_scan(_scan(**change))
    assert info.value.kind == kind


def test_a_scan_must_keep_the_first_scans_geometry():
    same_geometry(_scan(), _scan())
    for change, kind in (({"ranges": np.ones(4, np.float32), "angle_increment": 0.5}, "beam count"),
                         ({"angle_min": -0.9}, "beam angles"), ({"frame_id": "other"}, "laser frame")):
        with pytest.raises(BadMessage) as info:
            same_geometry(_scan(**change), _scan())
        assert info.value.kind == kind


def test_ros1_and_ros2_messages_read_alike():
    stamp2, stamp1 = NS(sec=3, nanosec=4), NS(secs=3, nsecs=4)
    assert stamp_ns(stamp2) == stamp_ns(stamp1) == 3_000_000_004

    def msg(stamp, data):
        pose = NS(position=NS(x=1.0, y=2.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))
        info = NS(map_load_time=stamp, resolution=np.float32(0.05), width=2, height=1, origin=pose)
        return NS(header=NS(stamp=stamp, frame_id="map"), info=info, data=data)

    a, b = grid_message(msg(stamp2, [-1, 100])), grid_message(msg(stamp1, b"\xff\x64"))  # rospy may hand bytes
    assert a.data.tolist() == b.data.tolist() == [-1, 100] and a.stamp_ns == b.stamp_ns


def test_transforms_keep_the_good_and_report_the_bad():
    def tr(child, w, x=0.0):
        return NS(header=NS(stamp=NS(sec=1, nanosec=0), frame_id="/odom"), child_frame_id=child,
                  transform=NS(translation=NS(x=x, y=0.0, z=0.0), rotation=NS(x=0.0, y=0.0, z=0.0, w=w)))

    good, faults = transforms_of(NS(transforms=[tr("base_link", 1.0), tr("a", 0.0), tr("b", 1.0, x=math.nan)]))
    assert [(t.parent, t.child) for t in good] == [("odom", "base_link")]
    assert [f.kind for f in faults] == ["non-unit quaternion", "transform translation"]


def test_a_map_over_the_cell_limit_is_refused_before_any_work(monkeypatch):
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "5")  # what crfmap --max-cells 5 node ... sets for the run
    with pytest.raises(BadMessage) as info:
        occupancy_grid(_grid())  # 3 x 2 = 6 cells
    assert info.value.kind == "too many cells" and "6 cells" in info.value.reason and "--max-cells" in info.value.reason
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "6")
    assert occupancy_grid(_grid()).shape == (2, 3)


def test_an_origin_beyond_any_map_is_refused():
    with pytest.raises(BadMessage) as info:
        occupancy_grid(_grid(origin=(1e300, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)))
    assert info.value.kind == "geometry"


def test_the_refine_node_logs_an_oversized_map_once_and_stays_up(monkeypatch):
    from crfmap.ros.node import RefineNode

    monkeypatch.setenv("CRFMAP_MAX_CELLS", "5")
    lines, sent = [], []
    node = RefineNode(period=0.0, refine=lambda g: g, log=lines.append)
    node.publishers["output"] = sent.append
    for _ in range(3):  # three oversized maps: skipped, one log line
        node.on_grid(_native(_grid()))
        node.step(0.0)
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "6")
    node.on_grid(_native(_grid()))
    node.step(0.0)  # the node is still up: the next map that fits is refined and published
    assert len(sent) == 1 and sum("too many cells" in line for line in lines) == 1
    assert "3 on /map (too many cells)" in node.summary()


def _native(m):
    """A ROS 2 style message object of a GridMessage."""
    x, y, z, qx, qy, qz, qw = m.origin
    stamp = NS(sec=0, nanosec=m.stamp_ns)
    return NS(header=NS(stamp=stamp, frame_id=m.frame_id),
              info=NS(map_load_time=stamp, resolution=m.resolution, width=m.width, height=m.height,
                      origin=NS(position=NS(x=x, y=y, z=z), orientation=NS(x=qx, y=qy, z=qz, w=qw))),
              data=m.data.tolist())
