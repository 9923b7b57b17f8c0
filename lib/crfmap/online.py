"""Online mapping: integrate laser scans one by one, keep the CRF's beliefs fresh around the robot.

Thesis sec. 3.4.4 bounds message passing to a disc around the robot so LBP can run while
mapping. :class:`OnlineMapper` keeps the hit counts of the arctan grid (thesis eq. 16) and the
LBP messages between scans. :meth:`OnlineMapper.integrate` adds one scan's hits (the grid
builder's own ray casting), refreshes the observation of every cell a beam passed, and runs
checkerboard LBP on the cells within ``radius`` of the laser, warm-started from the messages
the previous scans left. :meth:`OnlineMapper.finish` runs LBP on the whole grid to
convergence, which gives the offline result (:func:`crfmap.builder.build_grid` then
:func:`crfmap.lbp.infer`) when LBP has one fixed point.

>>> import numpy as np
>>> from crfmap.recording import ScanSet
>>> scans = ScanSet(np.full((2, 3), 2.0, np.float32), -0.5, 0.5, 0.1, 5.0,
...                 np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]), np.array([0.0, 0.1]))
>>> mapper = OnlineMapper.for_scans(scans, resolution=0.1)
>>> update = mapper.integrate(scans.ranges[0], scans.laser_poses[0])
>>> update.iterations > 0, mapper.observations().shape == (mapper.height, mapper.width)
(True, True)
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import builder
from ._lbp_packed import PackedBlock, fast_tables_ok, unary_odds
from .errors import InputError
from .grid import UNKNOWN, OccupancyGrid
from .lbp import DEFAULT_BLOCK, MESSAGE_FLOOR, LBPResult, run_packed
from .potentials import DEFAULT_HIDDEN, DEFAULT_LINK, check_pairing, check_table, directional_tables
from .raycast import _bresenham
from .recording import ScanSet

DEFAULT_RADIUS = 4.0  # [m] bounded LBP runs on the cells within this distance of the laser
DEFAULT_MAX_ITER = 16  # LBP iterations per scan at most


@njit(cache=True, nogil=True)
def _refresh_observations(ranges, angles, pose, range_min, range_max, max_is_no_return, free_range,
                          origin_x, origin_y, resolution, occupied, empty, link, floor, un, buf):
    """Re-derive the observation odds of every cell one scan's beams passed, from the hit counts.

    Walks the same cells as :func:`crfmap.builder._count_hits` (same beam classification, end
    cell and Bresenham line) and sets each one's P = 0.5 + atan(occupied - empty) / pi (thesis
    eq. 16) into the red/black observation planes ``un``.
    """
    height, width = occupied.shape
    u0 = (pose[0] - origin_x) / resolution
    v0 = (pose[1] - origin_y) / resolution
    x0 = int(math.floor(u0))
    y0 = int(math.floor(v0))
    for k in range(ranges.shape[0]):
        kind, length = builder._classify(ranges[k], range_min, range_max, max_is_no_return, free_range)
        if kind == builder._SKIP:
            continue
        a = pose[2] + angles[k]
        x1, y1, _ = builder._end_cell(u0, v0, u0 + length * math.cos(a) / resolution,
                                      v0 + length * math.sin(a) / resolution, width, height)
        n = _bresenham(x0, y0, x1, y1, buf)
        for j in range(n):
            x = buf[j, 0]
            y = buf[j, 1]
            p = 0.5 + math.atan(occupied[y, x] - empty[y, x]) / math.pi
            un[(x + y) & 1, y + 1, (x >> 1) + 1] = unary_odds(p, link, floor)


@dataclass
class ScanUpdate:
    """What one :meth:`OnlineMapper.integrate` did."""

    seconds: float  # wall time of the whole update (hits, observations, LBP)
    iterations: int  # LBP iterations on the disc
    converged: bool  # whether the last measured change was below tol
    cells: int  # cells in the disc (the senders)


class OnlineMapper:
    """An arctan occupancy grid built scan by scan, with bounded LBP around the robot.

    Parameters
    ----------
    geometry : dict
        The grid and sensor geometry as :func:`crfmap.builder` computes it; build a mapper
        with :meth:`for_scans` (or :meth:`for_sensor`) rather than by hand.
    hidden, link : 2x2 tables (see :mod:`crfmap.potentials`)
    radius : float
        [m] LBP runs on the cells whose centres lie within this distance of the laser.
    max_iter : int
        LBP iterations per scan at most (fewer once the change falls below ``tol``).
    tol : float
        Largest message change that counts as settled.
    dtype : np.float32 or np.float64
    pairing : "receiver" or "oriented"
    """

    def __init__(self, geometry, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, *, radius=DEFAULT_RADIUS,
                 max_iter=DEFAULT_MAX_ITER, tol=1e-4, dtype=np.float32, pairing="receiver"):
        self.geometry = dict(geometry)
        g = self.geometry
        self.hidden = check_table(hidden, "hidden")
        self.link = check_table(link, "link")
        self.pairing = check_pairing(pairing)
        tables = directional_tables(self.hidden, self.pairing)
        if not fast_tables_ok(tables):  # pragma: no cover - both pairings qualify
            raise InputError("pairing", "the online mapper needs east/north and west/south to share tables")
        if not (np.isfinite(radius) and radius > 0):
            raise InputError("radius", f"must be a positive number of metres, got {radius!r}")
        if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
            raise InputError("max_iter", f"must be a positive integer, got {max_iter!r}")
        if not (np.isfinite(tol) and tol >= 0):
            raise InputError("tol", f"must be a non-negative number, got {tol!r}")
        self.radius = float(radius)
        self.max_iter = int(max_iter)
        self.tol = float(tol)
        self.height, self.width = int(g["height"]), int(g["width"])
        self.resolution = float(g["resolution"])
        self.origin = (float(g["origin_x"]), float(g["origin_y"]), 0.0)
        self.frame_id = g.get("frame_id", "map")
        self.n_beams = len(g["angles"])
        self.occupied = np.zeros((self.height, self.width), np.int32)
        self.empty = np.zeros_like(self.occupied)
        self._buf = np.empty((self.width + self.height + 2, 2), np.int64)
        self._link = np.ascontiguousarray(self.link.ravel())
        self.packed = PackedBlock(self.height, self.width, dtype, tables, MESSAGE_FLOOR)
        self.packed.set_unary(np.full((self.height, self.width), UNKNOWN), self.link)
        self.scans = 0

    # --- construction -----------------------------------------------------------------------------
    @classmethod
    def for_scans(cls, scans: ScanSet, resolution, extent=None, free_on_no_return=False,
                  max_range_is_no_return=True, **options) -> "OnlineMapper":
        """A mapper for a recording's sensor on the grid :func:`crfmap.builder.build_grid` would make.

        ``extent`` None takes the data's extent as the builder does, so the final
        :meth:`observations` equal ``build_grid(scans, resolution)`` cell for cell.
        """
        g = builder._geometry(scans, resolution, extent, free_on_no_return, max_range_is_no_return)
        g["frame_id"] = getattr(scans, "frame_id", "map") or "map"
        for key in ("ranges", "poses", "source"):
            g.pop(key)
        return cls(g, **options)

    @classmethod
    def for_sensor(cls, extent, resolution, angle_min, angle_increment, n_beams, range_min, range_max,
                   free_on_no_return=False, max_range_is_no_return=True, **options) -> "OnlineMapper":
        """A mapper for a grid over ``extent`` (xmin, ymin, xmax, ymax) [m] and a laser's geometry."""
        try:
            xmin, ymin, xmax, ymax = (float(v) for v in extent)
        except (TypeError, ValueError):
            raise InputError("extent", f"expected (xmin, ymin, xmax, ymax) in metres, got {extent!r}") from None
        centre = np.array([[(xmin + xmax) / 2, (ymin + ymax) / 2, 0.0]])
        probe = ScanSet(np.full((1, int(n_beams)), np.nan, np.float32), angle_min, angle_increment, range_min,
                        range_max, centre, np.zeros(1), source="sensor")
        return cls.for_scans(probe, resolution, extent, free_on_no_return, max_range_is_no_return, **options)

    # --- mapping ----------------------------------------------------------------------------------
    def integrate(self, ranges, laser_pose, threads=1) -> ScanUpdate:
        """Add one scan (``ranges`` [m], REP 117) taken at ``laser_pose`` (x, y, yaw) in the map frame."""
        t0 = time.perf_counter()
        g = self.geometry
        r = np.asarray(ranges)
        if r.shape != (self.n_beams,) or not np.issubdtype(r.dtype, np.floating):
            raise InputError("ranges", f"expected {self.n_beams} floating-point readings, got shape {r.shape} "
                             f"dtype {r.dtype}")
        pose = np.asarray(laser_pose, dtype=np.float64).ravel()
        if pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise InputError("laser_pose", f"expected finite (x, y, yaw), got {laser_pose!r}")
        u0 = (pose[0] - self.origin[0]) / self.resolution
        v0 = (pose[1] - self.origin[1]) / self.resolution
        if not (0 <= u0 < self.width and 0 <= v0 < self.height):
            raise InputError("laser_pose", f"({pose[0]:.3f}, {pose[1]:.3f}) m lies outside the grid")
        r = r.astype(np.float32, copy=False)
        builder._count_hits(r[None, :], g["angles"], pose[None, :], g["range_min"], g["range_max"],
                            g["max_is_no_return"], g["free_range"], g["origin_x"], g["origin_y"], g["resolution"],
                            self.occupied, self.empty, self._buf)
        _refresh_observations(r, g["angles"], pose, g["range_min"], g["range_max"], g["max_is_no_return"],
                              g["free_range"], g["origin_x"], g["origin_y"], g["resolution"], self.occupied,
                              self.empty, self._link, MESSAGE_FLOOR, self.packed.un, self._buf)
        self._set_disc(u0, v0)
        changes = run_packed(self.packed, self.max_iter, self.tol, threads, block=DEFAULT_BLOCK)
        self.scans += 1
        last = changes[-1] if changes else 0.0
        return ScanUpdate(time.perf_counter() - t0, len(changes), bool(last < self.tol), self.packed.active_cells)

    def _set_disc(self, u0, v0):
        """Senders: cells whose centres lie within ``radius`` of the laser at (u0, v0) [cells]."""
        rc = self.radius / self.resolution
        y_lo = max(int(math.floor(v0 - rc - 0.5)), 0)
        y_hi = min(int(math.ceil(v0 + rc - 0.5)) + 1, self.height)
        ys = np.arange(y_lo, y_hi)
        half = np.sqrt(np.clip(rc * rc - (ys + 0.5 - v0) ** 2, 0.0, None))
        inside = (ys + 0.5 - v0) ** 2 <= rc * rc
        x_from = np.clip(np.ceil(u0 - half - 0.5), 0, self.width).astype(np.int64)
        x_to = np.clip(np.floor(u0 + half - 0.5) + 1, 0, self.width).astype(np.int64)
        x_to = np.where(inside, np.maximum(x_to, x_from), x_from)
        self.packed.set_rows(y_lo, x_from, x_to)

    def run(self, scans: ScanSet, progress=False, threads=1) -> np.ndarray:
        """Integrate every scan of ``scans`` in order; returns the seconds each update took."""
        if scans.ranges.shape[1] != self.n_beams:
            raise InputError(scans.source or "scans", f"{scans.ranges.shape[1]} beams per scan, the mapper "
                             f"expects {self.n_beams}")
        seconds = np.empty(len(scans))
        indices = range(len(scans))
        if progress:
            from tqdm.auto import tqdm

            indices = tqdm(indices, desc="online mapping", unit="scan")
        for i in indices:
            seconds[i] = self.integrate(scans.ranges[i], scans.laser_poses[i], threads=threads).seconds
        return seconds

    def finish(self, tol=None, max_iter=1000, threads=None) -> LBPResult:
        """LBP on the whole grid from the current messages until ``tol`` (default: the mapper's)."""
        import numba

        tol = self.tol if tol is None else float(tol)
        threads = numba.get_num_threads() if threads is None else int(threads)
        t0 = time.perf_counter()
        self.packed.set_mask(None)
        changes = np.asarray(run_packed(self.packed, max_iter, tol, threads, block=DEFAULT_BLOCK), float)
        beliefs = self.beliefs()
        return LBPResult(beliefs=beliefs, iterations=len(changes), max_change=changes,
                         converged=bool(changes.size and changes[-1] < tol), messages=self.messages(),
                         seconds=time.perf_counter() - t0, schedule="checkerboard", kernel="fast")

    # --- reading ------------------------------------------------------------------------------------
    def _grid(self, probability, **meta) -> OccupancyGrid:
        return OccupancyGrid(probability, resolution=self.resolution, origin=self.origin, frame_id=self.frame_id,
                             meta=dict(meta, scans=self.scans))

    def observations(self) -> OccupancyGrid:
        """The arctan grid of every scan so far (what :func:`crfmap.builder.build_grid` gives)."""
        p = builder.arctan_probability(self.occupied, self.empty)
        p[(self.occupied == 0) & (self.empty == 0)] = UNKNOWN
        return self._grid(p, model="arctan")

    def beliefs(self) -> OccupancyGrid:
        """The current LBP beliefs P(occupied) of every cell."""
        return self._grid(np.clip(self.packed.beliefs(), 0.0, 1.0), model="crf-online")

    def messages(self) -> np.ndarray:
        """The current messages as probabilities, shape (4, H, W) (see :func:`crfmap.lbp.infer`)."""
        return self.packed.messages(np.full((4, self.height, self.width), 0.5, self.packed.dtype))
