"""The maps a robot can carry while it explores, one registry entry each (:data:`ONBOARD_MAPS`).

Every kind is built for a grid (``bounds`` (xmin, ymin, xmax, ymax) [m], ``resolution`` [m/cell]) and
a :class:`~crfmap.sim.laser.Laser`, takes one scan at a time (:meth:`integrate`, ranges [m] at the
laser's pose in the map) and gives its P(occupied) [y, x] for the planner (:meth:`probability`):

- ``"raw"``: the thesis's arctan grid (:class:`~crfmap.mapping.builder.HitCounter`);
- ``"online-crf"``: the default preset's CRF, LBP bounded to a disc around the laser after every scan
  (the online mapper's engine; observations are the preset's, from the hit counts);
- ``"octomap"``: OctoMap's clamped log-odds (:class:`~crfmap.mapping.octomap.OctoMapUpdater`);
- ``"refined-on-arrival"``: the arctan grid refined with the default preset (as ``crfmap infer``) every
  ``every`` scans; cells observed since the last refinement read their raw value until the next.

A new kind is a class with ``__init__(bounds, resolution, laser, **options)``, ``integrate`` and
``probability``, and one line in :data:`ONBOARD_MAPS`.

>>> from crfmap.sim.laser import Laser
>>> m = make_onboard("raw", (0, 0, 1, 1), 0.1, Laser.with_fov(360, 8))
>>> m.integrate(np.full(8, np.inf), (0.55, 0.55, 0.0)); float(m.probability().max())
0.5
"""
from __future__ import annotations

import numpy as np

from crfmap.checks import check_int
from crfmap.crf.presets import DEFAULT_PRESET, Preset, get_preset
from crfmap.errors import InputError
from crfmap.mapping.builder import HitCounter
from crfmap.mapping.octomap import OctoMapUpdater
from crfmap.mapping.online import OnlineMapper


def _counter(bounds, resolution, laser) -> HitCounter:
    return HitCounter.for_sensor(bounds, resolution, laser.angle_min, laser.angle_increment, laser.n_beams,
                                 laser.range_min, laser.range_max)


def _ranges(ranges):
    return np.asarray(ranges, dtype=np.float32)


class RawGrid:
    """The thesis's arctan grid, P = 0.5 + atan(hits - passes) / pi, scan by scan."""

    def __init__(self, bounds, resolution, laser):
        self.hits = _counter(bounds, resolution, laser)

    def integrate(self, ranges, laser_pose) -> None:
        self.hits.add_scan(_ranges(ranges), laser_pose)

    def probability(self) -> np.ndarray:
        return self.hits.grid().probability


class OnlineCRF:
    """A preset's CRF kept fresh around the robot (:class:`~crfmap.mapping.online.OnlineMapper`, the default preset):
    bounded LBP on a disc after every scan; the planner reads its map for nav2 (region, gate), as the node publishes it."""

    def __init__(self, bounds, resolution, laser, preset=DEFAULT_PRESET, **mapper_options):
        self.mapper = OnlineMapper(_counter(bounds, resolution, laser), preset, **mapper_options)
        self.preset = self.mapper.preset

    def integrate(self, ranges, laser_pose) -> None:
        self.mapper.integrate(_ranges(ranges), laser_pose, threads=1)

    def probability(self) -> np.ndarray:
        return self.mapper.nav2_map().probability


class OctoMapGrid:
    """OctoMap's clamped log-odds update with its default parameters, scan by scan."""

    def __init__(self, bounds, resolution, laser, **params):
        self.octomap = OctoMapUpdater.for_sensor(bounds, resolution, laser.angle_min, laser.angle_increment,
                                                 laser.n_beams, laser.range_min, laser.range_max, **params)

    def integrate(self, ranges, laser_pose) -> None:
        self.octomap.add_scan(_ranges(ranges), laser_pose)

    def probability(self) -> np.ndarray:
        return self.octomap.probability()


class RefinedOnArrival:
    """The arctan grid refined with a preset (``crfmap infer``'s default) every ``every`` scans.

    Between refinements the planner reads the last refined map, except the cells scans touched since,
    which read their raw arctan value (a robot does not ignore what it just saw).
    """

    def __init__(self, bounds, resolution, laser, every=10, preset=DEFAULT_PRESET):
        self.every = check_int("every", every, low=1)
        self.preset = preset if isinstance(preset, Preset) else get_preset(preset)
        self.hits = _counter(bounds, resolution, laser)
        self.refined = np.full((self.hits.height, self.hits.width), 0.5)
        self.stale = np.zeros(self.refined.shape, bool)
        self.refinements = 0

    def integrate(self, ranges, laser_pose) -> None:
        cells = self.hits.add_scan(_ranges(ranges), laser_pose)
        self.stale[cells[:, 1], cells[:, 0]] = True
        if self.hits.scans % self.every == 0:
            self.refined = self.preset.refine(hits=self.hits.occupied, passes=self.hits.empty).nav2_map.probability
            self.stale[:] = False
            self.refinements += 1

    def probability(self) -> np.ndarray:
        if not self.stale.any():
            return self.refined
        return np.where(self.stale, self.hits.grid().probability, self.refined)


ONBOARD_MAPS = {"raw": RawGrid, "online-crf": OnlineCRF, "octomap": OctoMapGrid, "refined-on-arrival": RefinedOnArrival}


def make_onboard(kind, bounds, resolution, laser, **options):
    """A fresh onboard map of ``kind`` (a key of :data:`ONBOARD_MAPS`) over ``bounds`` for ``laser``."""
    if kind not in ONBOARD_MAPS:
        raise InputError("onboard", f"unknown map kind {kind!r}; choose one of {', '.join(ONBOARD_MAPS)}")
    return ONBOARD_MAPS[kind](bounds, resolution, laser, **options)
