"""Synthetic recordings for the scan-split tests: a laser inside a walled box, every beam hitting a wall."""
import numpy as np

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
