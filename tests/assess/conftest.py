"""Synthetic recordings for the scan-split tests: a laser inside a walled box, every beam hitting a wall."""
import numpy as np
import pytest

from crfmap.recording import ScanSet


def scans_in_a_box(poses, walls, n_beams) -> ScanSet:
    """Scans of ``n_beams`` beams (360 degrees) from ``poses`` (x, y, yaw) inside the walls ``(x0, y0, x1, y1)`` [m]."""
    x0, y0, x1, y1 = walls
    angles = np.linspace(-np.pi, np.pi, n_beams, endpoint=False)
    ranges = np.empty((len(poses), n_beams), np.float32)
    for i, (x, y, yaw) in enumerate(poses):
        a = angles + yaw
        with np.errstate(divide="ignore"):
            tx = np.where(np.cos(a) > 0, (x1 - x) / np.cos(a), (x0 - x) / np.cos(a))
            ty = np.where(np.sin(a) > 0, (y1 - y) / np.sin(a), (y0 - y) / np.sin(a))
        ranges[i] = np.minimum(np.abs(tx), np.abs(ty))
    return ScanSet(ranges, -np.pi, 2 * np.pi / n_beams, 0.01, 5.0, poses, np.arange(len(poses), dtype=float))


@pytest.fixture
def room():
    """A laser near the centre of a 2 m square room, turning a little: 6 scans of 90 beams."""
    rng = np.random.default_rng(0)
    n_scans = 6
    poses = np.column_stack([1 + 0.05 * rng.standard_normal(n_scans), 1 + 0.05 * rng.standard_normal(n_scans),
                             rng.uniform(-0.1, 0.1, n_scans)])
    return scans_in_a_box(poses, (0.05, 0.05, 1.95, 1.95), 90)


@pytest.fixture
def corridor():
    """A laser walking along a 3 m x 1 m corridor: 12 scans of 60 beams."""
    n_scans = 12
    poses = np.column_stack([np.linspace(0.3, 2.7, n_scans), np.full(n_scans, 0.5), np.zeros(n_scans)])
    return scans_in_a_box(poses, (0.05, 0.05, 2.95, 0.95), 60)
