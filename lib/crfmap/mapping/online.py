"""Online mapping: integrate laser scans one by one, keep the CRF's beliefs fresh around the robot.

Thesis sec. 3.4.4 bounds message passing to a disc around the robot so LBP can run while mapping.
:class:`OnlineMapper` keeps the arctan grid's hit counts and the LBP messages between scans: a scan's hits (the
builder's own ray casting) refresh the observations of the cells it touched, then LBP runs on the disc, warm-started.
:meth:`OnlineMapper.finish` is the preset's offline refinement of the same scans when LBP has one fixed point.

The CRF is a preset (:mod:`crfmap.crf.presets`). Hard evidence never arises: every preset's observation lies strictly
inside (0, 1), which no link table (no all-zero row) makes certain, so nothing is clamped.

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
from dataclasses import dataclass, replace

import numpy as np

from crfmap.checks import check_number
from crfmap.crf.engine.incremental import IncrementalLBP
from crfmap.crf.inference.regions import near_cells
from crfmap.crf.inference.result import LBPResult
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.crf.presets import DEFAULT_PRESET, Preset, custom_preset, get_preset
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.mapping import builder
from crfmap.recording import ScanSet

DEFAULT_RADIUS = 4.0  # [m] bounded LBP runs on the cells within this distance of the laser
DEFAULT_MAX_ITER = 16  # LBP iterations per scan at most
PRESET_MARGIN = "preset"  # margin= this: the preset's own margin (None would mean: every cell sends)


def mapper_preset(preset=None, hidden=None, link=None, pairing=None, margin=PRESET_MARGIN) -> Preset:
    """The preset an :class:`OnlineMapper` runs: named or given (None: :data:`~crfmap.crf.presets.DEFAULT_PRESET`),
    or a custom one of ``hidden``/``link``/``pairing``. ``margin`` other than :data:`PRESET_MARGIN` replaces the
    preset's margin [cells] (None: every cell sends).

    >>> mapper_preset().name == DEFAULT_PRESET, mapper_preset("thesis", margin=3).margin
    (True, 3)
    >>> mapper_preset(hidden=[[2, 1], [1, 2]]).name
    'custom'
    """
    tables = hidden is not None or link is not None or pairing is not None
    if tables and preset is not None:
        raise InputError("preset", "hidden/link/pairing make a custom preset of their own: give them or a preset")
    if tables:
        chosen = custom_preset(DEFAULT_HIDDEN if hidden is None else hidden, DEFAULT_LINK if link is None else link,
                               "receiver" if pairing is None else pairing)
    elif isinstance(preset, Preset):
        chosen = preset
    else:
        chosen = get_preset(DEFAULT_PRESET if preset is None else preset)
    if isinstance(margin, str) and margin == PRESET_MARGIN:
        return chosen
    return replace(chosen, margin=margin)  # the preset checks it


@dataclass
class ScanUpdate:
    """What one :meth:`OnlineMapper.integrate` did."""

    seconds: float  # wall time of the whole update (hits, observations, LBP)
    iterations: int  # LBP iterations on the disc
    converged: bool  # whether the last measured change was below tol
    cells: int  # cells in the disc (the senders)


class OnlineMapper:
    """An arctan occupancy grid built scan by scan, with bounded LBP around the robot.

    ``hits`` (:class:`crfmap.mapping.builder.HitCounter`): the grid, the laser's geometry and the hit counts (fresh,
    or holding earlier scans); :meth:`for_scans` and :meth:`for_sensor` make one. ``preset``, ``hidden``, ``link``,
    ``pairing``, ``margin``: the CRF (:func:`mapper_preset`). LBP runs on the cells whose centres lie within
    ``radius`` [m] of the laser, for at most ``max_iter`` iterations per scan (fewer once the largest message change
    falls below ``tol``). ``margin``: as :class:`~crfmap.crf.engine.incremental.IncrementalLBP`'s (None: every cell
    in the disc sends, the thesis's model; :func:`~crfmap.crf.inference.regions.near_known` says why not)."""

    def __init__(self, hits: builder.HitCounter, preset=None, *, hidden=None, link=None, pairing=None,
                 margin=PRESET_MARGIN, radius=DEFAULT_RADIUS, max_iter=DEFAULT_MAX_ITER, tol=1e-4, dtype=np.float32):
        if not isinstance(hits, builder.HitCounter):
            raise InputError("hits", f"expected a crfmap.mapping.builder.HitCounter, got {type(hits).__name__}")
        self.preset = mapper_preset(preset, hidden, link, pairing, margin)
        self.hidden, self.link, self.pairing = self.preset.hidden, self.preset.link, self.preset.pairing
        check_number("radius", radius, low=0.0, low_open=True)
        if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
            raise InputError("max_iter", f"must be a positive integer, got {max_iter!r}")
        check_number("tol", tol, low=0.0)
        self.lbp = IncrementalLBP(hits.height, hits.width, self.hidden, self.link, dtype, self.pairing,
                                  self.preset.margin)
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
        """A mapper for a recording's sensor on the grid :func:`crfmap.mapping.builder.build_grid` would make."""
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
        if len(cells):  # (a scan of no usable beam touches none; Preset.observation refuses an empty row)
            xs, ys = cells[:, 0], cells[:, 1]
            observed = self.preset.observation(hits=self.hits.occupied[ys, xs], passes=self.hits.empty[ys, xs])
            self.lbp.set_observations(cells, np.ascontiguousarray(observed, np.float64))
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

    def finish(self, tol=None, max_iter=None, threads=None) -> LBPResult:
        """LBP on the whole grid from the current messages until ``tol`` (by default the preset's, as
        :meth:`Preset.refine`): the preset's offline refinement."""
        import numba

        tol = self.preset.tol if tol is None else float(tol)
        max_iter = self.preset.max_iter if max_iter is None else int(max_iter)
        threads = numba.get_num_threads() if threads is None else int(threads)
        t0 = time.perf_counter()
        changes = np.asarray(self.lbp.run(max_iter, tol, threads), float)
        beliefs, gated = self._refined()
        return LBPResult(beliefs=beliefs, iterations=len(changes), max_change=changes,
                         converged=bool(changes.size and changes[-1] < tol), messages=self.messages(),
                         seconds=time.perf_counter() - t0, schedule="checkerboard", kernel="fast", gated=gated)

    # --- reading ------------------------------------------------------------------------------------
    def _grid(self, probability, **meta) -> OccupancyGrid:
        return OccupancyGrid(probability, resolution=self.resolution, origin=self.origin, frame_id=self.frame_id,
                             meta=dict(meta, scans=self.scans))

    def observations(self) -> OccupancyGrid:
        """The arctan grid of every scan so far (what :func:`crfmap.mapping.builder.build_grid` gives)."""
        return self.hits.grid()

    def region(self) -> np.ndarray:
        """Boolean [y, x] mask of the cells allowed to send: near an observed cell (all without a margin);
        ``infer(observations, region=mapper.region())`` is the offline run :meth:`finish` matches."""
        if self.margin is None:
            return np.ones((self.height, self.width), bool)
        observed = (self.hits.occupied > 0) | (self.hits.empty > 0)
        return near_cells(observed, self.margin)

    def beliefs(self) -> OccupancyGrid:
        """The current LBP beliefs P(occupied) of every cell, as :meth:`crfmap.crf.presets.Preset.refine` reports them
        (0.5 outside :meth:`region`, then the preset's gate and temperature)."""
        return self._refined()[0]

    def nav2_map(self) -> OccupancyGrid:
        """The map to hand nav2, as ``Preset.refine(...).nav2_map`` (the beliefs, unless the preset has a gate)."""
        beliefs, decided = self._refined()
        return beliefs if decided is None else decided

    def _refined(self) -> tuple:
        """(beliefs, map for nav2 or None): :meth:`Preset.finish` on LBP's beliefs."""
        probability = np.clip(self.lbp.beliefs(), 0.0, 1.0)
        if self.margin is not None:  # cells next to a sender receive messages but are outside the refinement
            probability[~self.region()] = 0.5
        beliefs, decided = self.preset.finish(probability, hits=self.hits.occupied, passes=self.hits.empty)
        grid = self._grid(beliefs, model="crf-online", preset=self.preset.name)
        return grid, None if decided is None else grid.with_probability(decided)

    def messages(self) -> np.ndarray:
        """The current messages as probabilities, shape (4, H, W) (see :func:`crfmap.crf.inference.lbp.infer`)."""
        return self.lbp.messages()
