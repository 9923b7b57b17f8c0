"""Online mapping: integrate laser scans one by one, keep the CRF's beliefs fresh around the robot.

Thesis sec. 3.4.4 bounds message passing to a disc around the robot so LBP can run while
mapping. :class:`OnlineMapper` keeps the hit counts of the arctan grid (thesis eq. 16) and the
LBP messages between scans. :meth:`OnlineMapper.integrate` adds one scan's hits (the grid
builder's own ray casting), refreshes the observation of every cell a beam passed, and runs
checkerboard LBP on the cells within ``radius`` of the laser, warm-started from the messages
the previous scans left. :meth:`OnlineMapper.finish` runs LBP on the whole grid to
convergence, which gives the offline result (:func:`crfmap.mapping.builder.build_grid` then
:func:`crfmap.crf.lbp.infer`) when LBP has one fixed point. Hard evidence never arises here: an
arctan observation lies strictly inside (0, 1), and no link table (no all-zero row) makes such a
cell certain (:mod:`crfmap.crf.evidence`), so nothing is clamped.

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

from crfmap.mapping import builder
from crfmap.crf.packed import PackedBlock, fast_tables_ok, unary_odds
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.crf.lbp import DEFAULT_BLOCK, MESSAGE_FLOOR, LBPResult, near_known, run_packed
from crfmap.crf.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, check_pairing, check_table, directional_tables
from crfmap.recording import ScanSet

DEFAULT_RADIUS = 4.0  # [m] bounded LBP runs on the cells within this distance of the laser
DEFAULT_MAX_ITER = 16  # LBP iterations per scan at most


@njit(cache=True, nogil=True)
def _refresh_observations(cells, occupied, empty, link, floor, un, known, near, margin):
    """Re-derive the observation odds of the cells a scan touched, from their hit counts.

    Sets each cell's P = 0.5 + atan(occupied - empty) / pi (thesis eq. 16) into the red/black
    observation planes ``un``. With ``margin`` >= 0, a cell observed for the first time marks
    every cell within ``margin`` (Chebyshev distance) in the red/black planes ``near``, as
    :func:`crfmap.crf.lbp.near_known` does for a whole grid.
    """
    height, width = occupied.shape
    for i in range(cells.shape[0]):
        x = cells[i, 0]
        y = cells[i, 1]
        p = 0.5 + math.atan(occupied[y, x] - empty[y, x]) / math.pi
        un[(x + y) & 1, y + 1, (x >> 1) + 1] = unary_odds(p, link, floor)
        if margin >= 0 and known[y, x] == 0:
            known[y, x] = 1
            for ny in range(max(y - margin, 0), min(y + margin + 1, height)):
                for nx in range(max(x - margin, 0), min(x + margin + 1, width)):
                    near[(nx + ny) & 1, ny + 1, (nx >> 1) + 1] = 1


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
    hidden, link : 2x2 tables (see :mod:`crfmap.crf.potentials`)
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
        :func:`crfmap.crf.lbp.infer`: gaps and occlusions up to ``margin`` cells deep are filled
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
        tables = directional_tables(self.hidden, self.pairing)
        if not fast_tables_ok(tables):  # pragma: no cover - both pairings qualify
            raise InputError("pairing", "the online mapper needs east/north and west/south to share tables")
        if not (np.isfinite(radius) and radius > 0):
            raise InputError("radius", f"must be a positive number of metres, got {radius!r}")
        if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
            raise InputError("max_iter", f"must be a positive integer, got {max_iter!r}")
        if not (np.isfinite(tol) and tol >= 0):
            raise InputError("tol", f"must be a non-negative number, got {tol!r}")
        if margin is not None and not (isinstance(margin, (int, np.integer)) and margin >= 0):
            raise InputError("margin", f"must be None or a non-negative whole number of cells, got {margin!r}")
        self.hits = hits
        self.radius = float(radius)
        self.max_iter = int(max_iter)
        self.tol = float(tol)
        self.margin = None if margin is None else int(margin)
        self.height, self.width = hits.height, hits.width
        self.resolution, self.origin, self.frame_id = hits.resolution, hits.origin, hits.frame_id
        self.n_beams = len(hits.angles)
        self._link = np.ascontiguousarray(self.link.ravel())
        self.packed = PackedBlock(self.height, self.width, dtype, tables, MESSAGE_FLOOR)
        self.packed.set_unary(np.full((self.height, self.width), UNKNOWN), self.link)
        # with a margin: cells ever observed, and the cells near them (the only senders), packed
        self._known = np.zeros((self.height, self.width) if margin is not None else (0, 0), np.uint8)
        self._near = np.zeros(self.packed.un.shape if margin is not None else (2, 1, 1), np.uint8)

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
        _refresh_observations(cells, self.hits.occupied, self.hits.empty, self._link, MESSAGE_FLOOR, self.packed.un,
                              self._known, self._near, -1 if self.margin is None else self.margin)
        self._set_disc((laser_pose[0] - self.origin[0]) / self.resolution,
                       (laser_pose[1] - self.origin[1]) / self.resolution)
        changes = run_packed(self.packed, self.max_iter, self.tol, threads, block=DEFAULT_BLOCK)
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
        self.packed.set_rows(y_lo, x_from, x_to, act=None if self.margin is None else self._near)

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
        if self.margin is None:
            self.packed.set_mask(None)
        else:
            self.packed.set_packed_mask(self._near)
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
        """The arctan grid of every scan so far (what :func:`crfmap.mapping.builder.build_grid` gives)."""
        return self.hits.grid()

    def region(self) -> np.ndarray:
        """Boolean [y, x] mask of the cells allowed to send: near an observed cell (all without a margin).

        ``infer(observations, region=mapper.region())`` is the offline run :meth:`finish` matches.
        """
        if self.margin is None:
            return np.ones((self.height, self.width), bool)
        observed = (self.hits.occupied > 0) | (self.hits.empty > 0)
        # near_known dilates the cells that are not 0.5; mark every observed one so
        return near_known(np.where(observed, 1.0, UNKNOWN), self.margin)

    def beliefs(self) -> OccupancyGrid:
        """The current LBP beliefs P(occupied) of every cell."""
        return self._grid(np.clip(self.packed.beliefs(), 0.0, 1.0), model="crf-online")

    def messages(self) -> np.ndarray:
        """The current messages as probabilities, shape (4, H, W) (see :func:`crfmap.crf.lbp.infer`)."""
        return self.packed.messages(np.full((4, self.height, self.width), 0.5, self.packed.dtype))
