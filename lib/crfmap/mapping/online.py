"""Online mapping: integrate laser scans one by one, keep the CRF's beliefs fresh around the robot.

Thesis sec. 3.4.4 bounds message passing to a disc around the robot so LBP can run while
mapping. :class:`OnlineMapper` keeps the hit counts of the arctan grid (thesis eq. 16) and the
LBP messages between scans. :meth:`OnlineMapper.integrate` adds one scan's hits (the grid
builder's own ray casting), refreshes the observation of every cell a beam passed, and runs
checkerboard LBP on the cells within ``radius`` of the laser, warm-started from the messages
the previous scans left. :meth:`OnlineMapper.finish` runs LBP on the whole grid to
convergence, which gives the offline result (:func:`crfmap.mapping.builder.build_grid` then
:func:`crfmap.crf.inference.lbp.infer`) when LBP has one fixed point. Hard evidence never arises here: an
arctan observation lies strictly inside (0, 1), and no link table (no all-zero row) makes such a
cell certain (:mod:`crfmap.crf.model.evidence`), so nothing is clamped.

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

from crfmap.checks import check_number
from crfmap.crf.engine.incremental import IncrementalLBP
from crfmap.crf.inference.regions import near_cells
from crfmap.crf.inference.result import LBPResult
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, check_pairing, check_table
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.mapping import builder
from crfmap.recording import ScanSet

DEFAULT_RADIUS = 4.0  # [m] bounded LBP runs on the cells within this distance of the laser
DEFAULT_MAX_ITER = 16  # LBP iterations per scan at most


@njit(cache=True, nogil=True)
def _arctan_observations(cells, occupied, empty):
    """P = 0.5 + atan(occupied - empty) / pi (thesis eq. 16) of the cells (x, y) = ``cells[i]`` a scan touched."""
    out = np.empty(cells.shape[0])
    for i in range(cells.shape[0]):
        x = cells[i, 0]
        y = cells[i, 1]
        out[i] = 0.5 + math.atan(occupied[y, x] - empty[y, x]) / math.pi
    return out


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
    hits : crfmap.mapping.builder.HitCounter
        The grid and the laser's geometry, and the hit counts (fresh, or holding earlier scans);
        :meth:`for_scans` and :meth:`for_sensor` make one.
    hidden, link : 2x2 tables (see :mod:`crfmap.crf.model.potentials`)
    radius : float
        [m] LBP runs on the cells whose centres lie within this distance of the laser.
    max_iter : int
        LBP iterations per scan at most (fewer once the change falls below ``tol``).
    tol : float
        Largest message change that counts as settled.
    dtype : np.float32 or np.float64
    pairing : "receiver" or "oriented"
    margin : None or int
        [cells] With a margin, only cells within ``margin`` cells (Chebyshev distance) of a cell
        some beam has observed send messages, as with ``region=near_known(grid, margin)`` in
        :func:`crfmap.crf.inference.lbp.infer`: gaps and occlusions up to ``margin`` cells deep are filled
        and the unexplored rest stays unknown. None: every cell in the disc sends (the thesis's
        model; with a strong coupling it fills unexplored space with its border's state).
    """

    def __init__(self, hits: builder.HitCounter, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, *, radius=DEFAULT_RADIUS,
                 max_iter=DEFAULT_MAX_ITER, tol=1e-4, dtype=np.float32, pairing="receiver", margin=None):
        if not isinstance(hits, builder.HitCounter):
            raise InputError("hits", f"expected a crfmap.mapping.builder.HitCounter, got {type(hits).__name__}")
        self.hidden = check_table(hidden, "hidden")
        self.link = check_table(link, "link")
        self.pairing = check_pairing(pairing)
        check_number("radius", radius, low=0.0, low_open=True)
        if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
            raise InputError("max_iter", f"must be a positive integer, got {max_iter!r}")
        check_number("tol", tol, low=0.0)
        self.lbp = IncrementalLBP(hits.height, hits.width, self.hidden, self.link, dtype, self.pairing, margin)
        self.hits = hits
        self.radius = float(radius)
        self.max_iter = int(max_iter)
        self.tol = float(tol)
        self.margin = self.lbp.margin
        self.height, self.width = hits.height, hits.width
        self.resolution, self.origin, self.frame_id = hits.resolution, hits.origin, hits.frame_id
        self.n_beams = len(hits.angles)

    # --- construction -----------------------------------------------------------------------------
    @classmethod
    def for_scans(cls, scans: ScanSet, resolution, bounds=None, free_on_no_return=False,
                  max_range_is_no_return=True, **options) -> "OnlineMapper":
        """A mapper for a recording's sensor on the grid :func:`crfmap.mapping.builder.build_grid` would make.

        ``bounds`` None takes the data's bounding box as the builder does, so the final
        :meth:`observations` equal ``build_grid(scans, resolution)`` cell for cell.
        """
        hits = builder.HitCounter.for_scans(scans, resolution, bounds, free_on_no_return, max_range_is_no_return)
        return cls(hits, **options)

    @classmethod
    def for_sensor(cls, bounds, resolution, angle_min, angle_increment, n_beams, range_min, range_max,
                   free_on_no_return=False, max_range_is_no_return=True, **options) -> "OnlineMapper":
        """A mapper for a grid over ``bounds`` (xmin, ymin, xmax, ymax) [m] and a laser's geometry."""
        hits = builder.HitCounter.for_sensor(bounds, resolution, angle_min, angle_increment, n_beams, range_min,
                                             range_max, free_on_no_return, max_range_is_no_return)
        return cls(hits, **options)

    # --- mapping ----------------------------------------------------------------------------------
    @property
    def scans(self) -> int:
        """Scans integrated so far."""
        return self.hits.scans

    def integrate(self, ranges, laser_pose, threads=1) -> ScanUpdate:
        """Add one scan (``ranges`` [m], REP 117) taken at ``laser_pose`` (x, y, yaw) in the map frame."""
        t0 = time.perf_counter()
        cells = self.hits.add_scan(ranges, laser_pose)  # checks its input
        self.lbp.set_observations(cells, _arctan_observations(cells, self.hits.occupied, self.hits.empty))
        disc = self._disc((laser_pose[0] - self.origin[0]) / self.resolution,
                          (laser_pose[1] - self.origin[1]) / self.resolution)
        changes = self.lbp.run(self.max_iter, self.tol, threads, rows=disc)
        last = changes[-1] if changes else 0.0
        return ScanUpdate(time.perf_counter() - t0, len(changes), bool(last < self.tol), self.lbp.senders)

    def _disc(self, u0, v0):
        """(first row, x_from, x_to): cells whose centres lie within ``radius`` of the laser at (u0, v0) [cells]."""
        rc = self.radius / self.resolution
        y_lo = max(int(math.floor(v0 - rc - 0.5)), 0)
        y_hi = min(int(math.ceil(v0 + rc - 0.5)) + 1, self.height)
        ys = np.arange(y_lo, y_hi)
        half = np.sqrt(np.clip(rc * rc - (ys + 0.5 - v0) ** 2, 0.0, None))
        inside = (ys + 0.5 - v0) ** 2 <= rc * rc
        x_from = np.clip(np.ceil(u0 - half - 0.5), 0, self.width).astype(np.int64)
        x_to = np.clip(np.floor(u0 + half - 0.5) + 1, 0, self.width).astype(np.int64)
        x_to = np.where(inside, np.maximum(x_to, x_from), x_from)
        return y_lo, x_from, x_to

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
        changes = np.asarray(self.lbp.run(max_iter, tol, threads), float)
        beliefs = self.beliefs()
        return LBPResult(beliefs=beliefs, iterations=len(changes), max_change=changes,
                         converged=bool(changes.size and changes[-1] < tol), messages=self.messages(),
                         seconds=time.perf_counter() - t0, schedule="checkerboard", kernel="fast")

    # --- reading ------------------------------------------------------------------------------------
    def _grid(self, probability, **meta) -> OccupancyGrid:
        return OccupancyGrid(probability, resolution=self.resolution, origin=self.origin, frame_id=self.frame_id,
                             meta=dict(meta, scans=self.scans))

    def observations(self) -> OccupancyGrid:
        """The arctan grid of every scan so far (what :func:`crfmap.mapping.builder.build_grid` gives)."""
        return self.hits.grid()

    def region(self) -> np.ndarray:
        """Boolean [y, x] mask of the cells allowed to send: near an observed cell (all without a margin).

        ``infer(observations, region=mapper.region())`` is the offline run :meth:`finish` matches.
        """
        if self.margin is None:
            return np.ones((self.height, self.width), bool)
        observed = (self.hits.occupied > 0) | (self.hits.empty > 0)
        return near_cells(observed, self.margin)

    def beliefs(self) -> OccupancyGrid:
        """The current LBP beliefs P(occupied) of every cell."""
        return self._grid(np.clip(self.lbp.beliefs(), 0.0, 1.0), model="crf-online")

    def messages(self) -> np.ndarray:
        """The current messages as probabilities, shape (4, H, W) (see :func:`crfmap.crf.inference.lbp.infer`)."""
        return self.lbp.messages()
