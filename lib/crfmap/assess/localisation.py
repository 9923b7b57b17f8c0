"""Localisation on a map: nav2_amcl's likelihood-field laser model, scored on held-out scans.

A map is good for a robot if the robot can find itself on it. nav2 localises with AMCL, whose default
laser model (``laser_model_type: likelihood_field``) scores a scan at a pose by how far each beam's end
point lands from the nearest obstacle of the map. This module computes that model exactly as nav2_amcl
does and asks two questions of each held-out scan (the scans the map was *not* built from):

- discrimination: does the scan score higher at its corrected (true) laser pose than at poses offset by
  5-30 cm and 2-10 degrees (:func:`pose_offsets`)? Reported as the share of offsets the true pose beats
  (ties count one half) and the mean log-weight margin, true minus offset;
- pose search: started from a perturbed pose (up to 30 cm and 10 degrees off), does a coarse-to-fine
  grid search that maximises the same weight (:func:`search_poses`) come back? Reported as the median
  translation [m] and rotation [deg] error and the share of scans found within 10 cm and 3 degrees.

:func:`compare_localisation` scores several maps on the same scans, offsets and starting poses, and gives
each metric's paired difference to a reference map (the raw grid) with a bootstrap interval over scans.

The model, as read from ros-navigation/navigation2 (main at commit a3a97043ee93, 2026-08-21):

- ``nav2_amcl/src/amcl_node.cpp``, ``convertMap`` (lines 1348-1373): an OccupancyGrid value of exactly 100
  is an obstacle (``occ_state = +1``), 0 is free, anything else unknown. The map nav2 loads from a file
  crfmap writes (:func:`nav2_lethal`): ``OccupancyGrid.to_int8`` rounds P to percent, map_saver's trinary
  rule writes values >= round(100 * 0.65) black, and nav2_map_server reads black back as 100 (checked
  against :func:`crfmap.io.map_server.save_map` / ``load_map`` in the tests). Free and unknown cells
  play no part in this model. ``convertMap`` keeps the map's origin position and ignores its yaw.
- ``nav2_amcl/src/map/map_cspace.cpp``, ``map_update_cspace`` (lines 148-210) with ``CachedDistanceMap``
  and ``enqueue`` (lines 49-141): ``occ_dist`` [m] is meant as each cell's Euclidean distance to the
  nearest obstacle cell, kept while the distance in cells is <= ``int(max_occ_dist / resolution)``, else
  ``max_occ_dist``; stored as float. :func:`distance_field` computes exactly that with
  ``scipy.ndimage.distance_transform_edt`` and the same cut. nav2's own brushfire (a priority queue from the
  obstacle cells; a cell takes the distance to the obstacle its first-popped neighbour came from) is not
  always the nearest obstacle: a line-by-line port (``nav2_brushfire`` in the tests) is never below the
  exact distance but above it in 11-13 % of the cells of the Intel maps (raw, default preset, OctoMap at
  0.05 m), by up to 0.17 m. Scored with the port's field instead (Intel, the 455 held-out odd scans),
  every metric moves by at most +0.01 log margin, 4 mm median translation error and 0.7 points of the
  found share, in the same direction for the three maps, and no ordering between them changes.
- ``nav2_amcl/include/nav2_amcl/map/map.hpp`` (lines 121-133) with ``convertMap``: a point (x, y) falls in
  cell ``floor((x - origin_x') / res + 0.5) + size_x / 2`` where ``origin_x' = origin_x + (size_x / 2) * res``
  (integer halves), i.e. AMCL *rounds* to the nearest cell corner index: it reads cell i as centred on
  ``origin_x + i * res``, half a cell below where the OccupancyGrid convention (and crfmap) puts it. This
  module does the same, so a perfect map's best pose sits about (res/2, res/2) from the true one (for
  0.05 m cells, 3.5 cm). Pass ``origin`` shifted by ``+res/2`` in x and y to measure without that shift.
- ``nav2_amcl/src/sensors/laser/likelihood_field_model.cpp``, ``sensorFunction`` (lines 49-140): beams
  ``0, step, 2 step, ...`` with ``step = max(1, (range_count - 1) // (max_beams - 1))`` (lines 68-73);
  a beam is skipped if its range is ``>= range_max`` (max-range readings, line 92) or NaN (line 97);
  its end point at the laser pose plus range along ``yaw + bearing`` (lines 104-105); ``z`` = that
  cell's ``occ_dist``, or ``max_occ_dist`` off the map (lines 114-118);
  ``pz = z_hit exp(-z^2 / (2 sigma_hit^2)) + z_rand / range_max`` (lines 121-123, no Gaussian
  normalisation), and the scan's weight is ``p = 1 + sum pz^3`` (line 132; not a product of pz).
  :func:`LikelihoodField.log_weights` returns ``log p``.
- ``nav2_amcl/src/amcl_node.cpp``, ``updateFilter`` (lines 717-743): ``range_max = min(scan range_max,
  laser_max_range)`` when ``laser_max_range > 0``; readings ``<= range_min`` (``max(scan range_min,
  laser_min_range)`` when ``laser_min_range > 0``) become ``range_max`` and so are skipped. With REP 117
  ranges (+inf no return, -inf too close, NaN invalid) the beams used are the finite ones strictly
  between range_min and range_max. ``LikelihoodFieldModel::sensorUpdate`` updates nothing when
  ``max_beams < 2`` (likelihood_field_model.cpp line 146), so :class:`LaserModel` refuses it.
- Parameter defaults (amcl_node.cpp lines 955-987): ``z_hit`` 0.5, ``z_rand`` 0.5, ``sigma_hit`` 0.2 m,
  ``laser_likelihood_max_dist`` 2.0 m, ``max_beams`` 60, ``laser_max_range`` 100 m,
  ``laser_min_range`` -1 (off): :class:`LaserModel`'s defaults.

>>> p = np.zeros((40, 40)); p[:, 30] = 1.0                  # a wall at x = 1.5 m (5 cm cells)
>>> scans = ScanSet(np.full((1, 3), 1.0, np.float32), -0.1, 0.1, 0.0, 10.0,
...                 np.array([[0.5 - 0.025, 1.0 - 0.025, 0.0]]), np.zeros(1))
>>> field = LikelihoodField.from_probability(p, 0.05)
>>> lw = field.log_weights(Beams.from_scans(scans), np.array([[[0.475, 0.975, 0.0], [0.375, 0.975, 0.0]]]))
>>> (lw[0, 0] > lw[0, 1]).item()                                 # the true pose beats one 10 cm short
True
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, check_probability_array
from crfmap.io.map_server import OCCUPIED_THRESH_DEFAULT
from crfmap.recording import ScanSet

LETHAL_VALUE = 100  # amcl_node.cpp convertMap: only this OccupancyGrid value is an obstacle (occ_state +1)
OFFSET_TRANSLATION = (0.05, 0.30)  # [m] the discrimination offsets' distance from the true pose
OFFSET_ROTATION_DEG = (2.0, 10.0)  # [deg] and their turn
START_TRANSLATION = 0.30  # [m] the pose search starts at most this far from the true pose
START_ROTATION_DEG = 10.0  # [deg] and turned at most this much
FOUND_TRANSLATION = 0.10  # [m] a search ending within this distance ...
FOUND_ROTATION_DEG = 3.0  # [deg] ... and this turn of the true pose found it
METRICS = {  # name: higher is better
    "beats_offsets": True,  # mean over scans of the share of offset poses the true pose beats
    "log_margin": True,  # mean over scans of log p(true) - log p(offset), averaged over the offsets
    "translation_error": False,  # median over scans [m] after the pose search
    "rotation_error": False,  # median over scans [deg] after the pose search
    "found": True,  # share of scans the search ends within FOUND_TRANSLATION and FOUND_ROTATION_DEG
}
CHUNK_ELEMENTS = 2_000_000  # beam end points evaluated at once (bounds the temporary arrays to ~16 MB each)


@dataclass(frozen=True)
class LaserModel:
    """nav2_amcl's likelihood-field parameters, with nav2's defaults (amcl_node.cpp lines 955-987).

    >>> LaserModel().max_beams, LaserModel(sigma_hit=0.1).sigma_hit
    (60, 0.1)
    """

    z_hit: float = 0.5
    z_rand: float = 0.5
    sigma_hit: float = 0.2  # [m]
    laser_likelihood_max_dist: float = 2.0  # [m] distances to obstacles are cut here
    max_beams: int = 60  # beams used per scan (about; see Beams.from_scans)
    laser_max_range: float = 100.0  # [m] <= 0: the scan's own range_max
    laser_min_range: float = -1.0  # [m] <= 0: the scan's own range_min

    def __post_init__(self):
        for name in ("z_hit", "z_rand"):
            check_number(f"model.{name}", getattr(self, name), low=0)
        check_positive("model.sigma_hit", self.sigma_hit)
        check_number("model.laser_likelihood_max_dist", self.laser_likelihood_max_dist, low=0)
        check_int("model.max_beams", self.max_beams, low=2)  # nav2 updates nothing below 2
        check_number("model.laser_max_range", self.laser_max_range)
        check_number("model.laser_min_range", self.laser_min_range)


def nav2_lethal(probability) -> np.ndarray:
    """Boolean [y, x]: the cells nav2_amcl takes for obstacles in the map crfmap writes from ``probability``.

    P is rounded to percent (-1 where exactly 0.5) as :meth:`crfmap.grid.OccupancyGrid.to_int8`, a trinary
    map_server image marks values >= round(100 * 0.65) occupied, nav2's loader reads those back as 100,
    and AMCL's ``convertMap`` makes exactly the 100s obstacles.

    >>> nav2_lethal(np.array([[0.5, 0.644, 0.646, 1.0]])).tolist()
    [[False, False, True, True]]
    """
    values = OccupancyGrid(check_probability_array(probability, "probability")).to_int8()
    written_occupied = values >= int(np.rint(OCCUPIED_THRESH_DEFAULT * 100.0))  # map_server.py, trinary image
    return written_occupied  # read back as LETHAL_VALUE by nav2_map_server, then occ_state +1 in convertMap


def distance_field(lethal, resolution, max_dist=LaserModel.laser_likelihood_max_dist) -> np.ndarray:
    """nav2_amcl's ``occ_dist`` [m] (float32, [y, x]): distance to the nearest ``lethal`` cell, cut at ``max_dist``.

    A cell farther than ``int(max_dist / resolution)`` cells (C's truncation) from every lethal cell gets
    ``max_dist``; so does every cell of a map without lethal cells.

    >>> distance_field(np.array([[True, False, False, False]]), 0.5, max_dist=1.2).tolist()
    [[0.0, 0.5, 1.0, 1.2000000476837158]]
    """
    lethal = np.asarray(lethal)
    if lethal.ndim != 2 or lethal.size == 0 or lethal.dtype != bool:
        raise InputError("lethal", f"expected a non-empty 2-D boolean [y, x] array, got {lethal.dtype} {lethal.shape}")
    resolution = check_positive("resolution", resolution)
    max_dist = check_number("max_dist", max_dist, low=0)
    if not lethal.any():
        return np.full(lethal.shape, max_dist, np.float32)
    cells = ndimage.distance_transform_edt(~lethal)  # [cells] to the nearest lethal cell
    cell_radius = int(max_dist / resolution)  # CachedDistanceMap: an int, so truncated
    return np.where(cells <= cell_radius, cells * resolution, max_dist).astype(np.float32)


@dataclass
class Beams:
    """The beams nav2_amcl uses from each scan: ``ranges`` [n, b] (NaN where skipped) at ``bearings`` [b].

    ``range_max`` is the scan's (or ``laser_max_range`` if smaller), the ``z_rand / range_max`` term's.
    """

    ranges: np.ndarray  # (n_scans, n_used) float64 [m], NaN = beam skipped
    bearings: np.ndarray  # (n_used,) [rad] in the laser frame
    range_max: float  # [m]

    @classmethod
    def from_scans(cls, scans: ScanSet, model: LaserModel = LaserModel()) -> "Beams":
        """Subsample and filter ``scans`` as ``sensorFunction`` and ``updateFilter`` do (see the module doc).

        >>> s = ScanSet(np.array([[1.0, np.inf, 0.01, 2.0, np.nan]], np.float32), 0.0, 0.1, 0.05, 5.0,
        ...             np.zeros((1, 3)), np.zeros(1))
        >>> b = Beams.from_scans(s, LaserModel(max_beams=3))        # step (5 - 1) // (3 - 1) = 2
        >>> b.bearings.round(2).tolist(), b.ranges.tolist()
        ([0.0, 0.2, 0.4], [[1.0, nan, nan]])
        """
        ranges = _scan_ranges(scans)
        used = beam_indices(ranges.shape[1], model.max_beams)
        range_max = float(scans.range_max)
        if model.laser_max_range > 0:
            range_max = min(range_max, float(np.float32(model.laser_max_range)))  # compared as float in nav2
        range_min = float(scans.range_min)
        if model.laser_min_range > 0:
            range_min = max(range_min, float(np.float32(model.laser_min_range)))
        if not (math.isfinite(range_max) and range_max > 0):
            raise InputError("scans.range_max", f"must be a positive finite range (nav2 drops such scans), got "
                             f"{range_max!r}")
        r = ranges[:, used].astype(np.float64)
        with np.errstate(invalid="ignore"):
            keep = (r > range_min) & (r < range_max)  # NaN and +-inf fail both
        bearings = float(scans.angle_min) + used * float(scans.angle_increment)
        return cls(np.where(keep, r, np.nan), bearings, range_max)

    def __len__(self):
        return int(self.ranges.shape[0])

    def usable(self) -> np.ndarray:
        """Boolean (n_scans,): scans with at least one beam AMCL uses."""
        return np.isfinite(self.ranges).any(axis=1)


def beam_indices(n_beams, max_beams=LaserModel.max_beams) -> np.ndarray:
    """Indices of the beams nav2_amcl reads: every ``max(1, (n_beams - 1) // (max_beams - 1))``-th from 0.

    >>> len(beam_indices(180)), len(beam_indices(361)), beam_indices(7, 3).tolist()
    (60, 61, [0, 3, 6])
    """
    n_beams = check_int("n_beams", n_beams, low=1)
    max_beams = check_int("max_beams", max_beams, low=2)
    step = max(1, (n_beams - 1) // (max_beams - 1))
    return np.arange(0, n_beams, step)


@dataclass
class LikelihoodField:
    """A map as nav2_amcl's likelihood-field model sees it: ``occ_dist`` [y, x] and where it lies.

    ``origin`` is the OccupancyGrid origin (cell (0, 0)'s corner, x and y [m]); cells are looked up
    as AMCL does (rounded, see the module doc).
    """

    occ_dist: np.ndarray  # (height, width) float32 [m]
    resolution: float  # [m / cell]
    origin: tuple = (0.0, 0.0)  # (x, y) [m]
    model: LaserModel = LaserModel()

    @classmethod
    def from_probability(cls, probability, resolution, origin=(0.0, 0.0, 0.0),
                         model: LaserModel = LaserModel()) -> "LikelihoodField":
        """The field of the map nav2 loads from ``probability`` [y, x] (see :func:`nav2_lethal`)."""
        resolution = check_positive("resolution", resolution)
        origin = _check_origin(origin)
        occ_dist = distance_field(nav2_lethal(probability), resolution, model.laser_likelihood_max_dist)
        return cls(occ_dist, resolution, origin, model)

    def log_weights(self, beams: Beams, poses) -> np.ndarray:
        """``log p`` of scan i at each laser pose ``poses[i, k]`` (x, y, yaw in the map frame): (n, k).

        ``p = 1 + sum over used beams of pz^3`` is the factor AMCL multiplies a particle's weight by.
        """
        poses = np.asarray(poses, dtype=np.float64)
        if poses.ndim != 3 or poses.shape[0] != len(beams) or poses.shape[2] != 3 or not np.isfinite(poses).all():
            raise InputError("poses", f"expected finite (n_scans={len(beams)}, k, 3) x, y, yaw, got {poses.shape}")
        model = self.model
        height, width = self.occ_dist.shape
        # convertMap moves the origin to the map's centre; MAP_GXWX undoes it with integer halves
        centre_x = self.origin[0] + (width // 2) * self.resolution
        centre_y = self.origin[1] + (height // 2) * self.resolution
        hit_denom = 2.0 * model.sigma_hit * model.sigma_hit
        rand = model.z_rand * (1.0 / beams.range_max)
        flat = self.occ_dist.ravel().astype(np.float64)  # C promotes the float occ_dist to double
        out = np.empty(poses.shape[:2])
        n_beams = max(beams.ranges.shape[1], 1)
        rows = max(1, CHUNK_ELEMENTS // (n_beams * max(poses.shape[1], 1)))
        for a in range(0, len(beams), rows):
            b = min(a + rows, len(beams))
            r = beams.ranges[a:b, None, :]  # (m, 1, beams)
            x, y, yaw = (poses[a:b, :, j, None] for j in range(3))  # (m, k, 1)
            angle = yaw + beams.bearings
            hx = x + r * np.cos(angle)
            hy = y + r * np.sin(angle)
            mi = np.floor((hx - centre_x) / self.resolution + 0.5) + width // 2
            mj = np.floor((hy - centre_y) / self.resolution + 0.5) + height // 2
            on_map = (mi >= 0) & (mi < width) & (mj >= 0) & (mj < height)  # False where the beam is skipped (NaN)
            index = np.where(on_map, mi + mj * width, 0).astype(np.intp)
            z = np.where(on_map, flat[index], model.laser_likelihood_max_dist)
            pz = model.z_hit * np.exp(-(z * z) / hit_denom) + rand
            pz = np.where(np.isnan(r), 0.0, pz)  # skipped beams add nothing
            out[a:b] = np.log1p(np.sum(pz * pz * pz, axis=2))
        return out


def pose_offsets(n_scans, n_offsets, seed=0, translation=OFFSET_TRANSLATION,
                 rotation_deg=OFFSET_ROTATION_DEG) -> np.ndarray:
    """Seeded pose offsets (dx [m], dy [m], dyaw [rad]): (n_scans, n_offsets, 3).

    Each moves by a distance drawn uniformly in ``translation`` [m] in a uniform direction and turns by
    an angle drawn uniformly in ``rotation_deg`` with a random sign.

    >>> d = pose_offsets(2, 5, seed=1)
    >>> d.shape, bool(np.all((np.hypot(d[..., 0], d[..., 1]) >= 0.05) & (np.abs(np.degrees(d[..., 2])) >= 2)))
    ((2, 5, 3), True)
    """
    n_scans, n_offsets = check_int("n_scans", n_scans, low=0), check_int("n_offsets", n_offsets, low=1)
    (t_lo, t_hi), (r_lo, r_hi) = _check_range("translation", translation), _check_range("rotation_deg", rotation_deg)
    rng = np.random.default_rng([check_int("seed", seed, low=0), 0])
    shape = (n_scans, n_offsets)
    distance, direction = rng.uniform(t_lo, t_hi, shape), rng.uniform(-math.pi, math.pi, shape)
    turn = np.radians(rng.uniform(r_lo, r_hi, shape)) * rng.choice([-1.0, 1.0], shape)
    return np.stack([distance * np.cos(direction), distance * np.sin(direction), turn], axis=-1)


def start_poses(true_poses, seed=0, translation=START_TRANSLATION, rotation_deg=START_ROTATION_DEG) -> np.ndarray:
    """Seeded starting poses for the search: each true pose moved up to ``translation`` [m] and turned up to
    ``rotation_deg`` (uniform distance, direction and turn), (n, 3).

    >>> s = start_poses(np.zeros((3, 3)), seed=2)
    >>> bool(np.all(np.hypot(s[:, 0], s[:, 1]) <= 0.3)), bool(np.all(np.abs(s[:, 2]) <= np.radians(10)))
    (True, True)
    """
    true_poses = _check_poses("true_poses", true_poses)
    translation = check_number("translation", translation, low=0)
    rotation_deg = check_number("rotation_deg", rotation_deg, low=0, high=180)
    rng = np.random.default_rng([check_int("seed", seed, low=0), 1])  # not the offsets' stream
    n = len(true_poses)
    distance, direction = rng.uniform(0, translation, n), rng.uniform(-math.pi, math.pi, n)
    turn = np.radians(rng.uniform(-rotation_deg, rotation_deg, n))
    return true_poses + np.column_stack([distance * np.cos(direction), distance * np.sin(direction), turn])


def search_poses(field: LikelihoodField, beams: Beams, starts, step=0.08, step_deg=3.0, span=2,
                 min_step=0.005, max_rounds=80) -> np.ndarray:
    """Coarse-to-fine grid search of each scan's laser pose maximising :meth:`LikelihoodField.log_weights`.

    Every round scores the ``(2 span + 1)^3`` poses ``centre + (i step, j step, k step_deg)``,
    ``-span <= i, j, k <= span``, and moves to the best; when the centre is best (ties keep it) the
    steps halve. A scan stops once its translation step is below ``min_step`` [m] (the angular step
    shrinks alike), or after ``max_rounds``. The first grid spans +-16 cm and +-6 degrees by default, and
    the search walks on from there, so starts 30 cm / 10 degrees off are in reach. Returns (n, 3).
    """
    starts = _check_poses("starts", starts)
    if len(starts) != len(beams):
        raise InputError("starts", f"need one pose per scan ({len(beams)}), got {len(starts)}")
    step, step_deg, min_step = (check_positive(n, v) for n, v in (("step", step), ("step_deg", step_deg),
                                                                     ("min_step", min_step)))
    span, max_rounds = check_int("span", span, low=1), check_int("max_rounds", max_rounds, low=1)
    ticks = np.arange(-span, span + 1, dtype=np.float64)
    grid = np.stack(np.meshgrid(ticks, ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 3)
    grid = grid[np.argsort(np.abs(grid).sum(axis=1), kind="stable")]  # the centre first: argmax keeps it on ties
    centre = starts.copy()
    scale = np.ones(len(starts))  # each scan's step factor, halved when it cannot improve
    base = np.array([step, step, math.radians(step_deg)])
    active = np.flatnonzero(np.isfinite(beams.ranges).any(axis=1))  # a scan with no usable beam stays put
    for _ in range(max_rounds):
        if active.size == 0:
            break
        sub = Beams(beams.ranges[active], beams.bearings, beams.range_max)
        candidates = centre[active, None, :] + grid[None] * (scale[active, None, None] * base)
        best = np.argmax(field.log_weights(sub, candidates), axis=1)
        centre[active] = candidates[np.arange(active.size), best]
        scale[active[best == 0]] *= 0.5
        active = active[scale[active] * step >= min_step]
    centre[:, 2] = np.angle(np.exp(1j * centre[:, 2]))  # yaw back into (-pi, pi]
    return centre


@dataclass
class LocalisationResult:
    """Per-scan localisation scores of one map on held-out scans (see the module doc).

    ``scan_index`` indexes the held-out ScanSet given to :func:`localise`; ``summary()`` gives the
    :data:`METRICS` over scans.
    """

    scan_index: np.ndarray  # (n,) held-out scans scored
    true_log_weight: np.ndarray  # (n,) log p at the corrected laser pose
    offset_log_weight: np.ndarray  # (n, n_offsets) log p at the offset poses
    found_poses: np.ndarray  # (n, 3) where the pose search ended
    start_poses: np.ndarray  # (n, 3) where it began
    translation_error: np.ndarray  # (n,) [m]
    rotation_error: np.ndarray  # (n,) [deg]
    seconds: float = 0.0  # wall time of the distance field, discrimination and search
    per_scan: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        diff = self.true_log_weight[:, None] - self.offset_log_weight
        self.per_scan = {
            "beats_offsets": np.mean((diff > 0) + 0.5 * (diff == 0), axis=1),
            "log_margin": diff.mean(axis=1),
            "translation_error": self.translation_error,
            "rotation_error": self.rotation_error,
            "found": ((self.translation_error <= FOUND_TRANSLATION)
                      & (self.rotation_error <= FOUND_ROTATION_DEG)).astype(np.float64),
        }

    def summary(self) -> dict:
        """{metric: value over the scans} of :data:`METRICS`, and ``scans``."""
        return dict({m: _statistic(m, v) for m, v in self.per_scan.items()}, scans=int(len(self.scan_index)))


def localise(probability, resolution, origin, scans: ScanSet, *, model: LaserModel = LaserModel(),
             max_scans=500, n_offsets=16, seed=0) -> LocalisationResult:
    """Score the map ``probability`` [y, x] (cell (0, 0)'s corner at ``origin``) on held-out ``scans``.

    ``scans.laser_poses`` are the corrected (true) laser poses in the map frame. At most ``max_scans``
    scans are used, evenly spaced over the set; scans with no beam AMCL uses are left out (they carry
    no information: every pose scores alike). Offsets and starting poses depend on ``seed`` and the
    scans only, never on the map, so maps scored with one seed are scored on the same poses.

    >>> from crfmap.recording import ScanSet
    >>> p = np.zeros((40, 40)); p[[5, 34], :] = 1.0; p[:, [5, 34]] = 1.0; p[18:22, 12:14] = 1.0
    >>> angles = np.linspace(-np.pi, np.pi, 90, endpoint=False)
    >>> from crfmap.sim import Laser
    >>> from crfmap.sim.simulator import cast_rays
    >>> truth = OccupancyGrid(p, 0.05)
    >>> laser = Laser.with_fov(360, 90)
    >>> poses = np.array([[0.9, 0.7, 0.3], [1.2, 1.3, -1.0]])
    >>> scans = ScanSet(cast_rays(truth, laser, poses).astype(np.float32), laser.angle_min, laser.angle_increment,
    ...                 laser.range_min, laser.range_max, poses, np.arange(2.0))
    >>> r = localise(p, 0.05, (0.025, 0.025), scans, seed=0)    # origin + res/2: no half-cell shift
    >>> s = r.summary(); s["beats_offsets"], s["found"]
    (1.0, 1.0)
    """
    started = time.perf_counter()
    resolution = check_positive("resolution", resolution)
    origin = _check_origin(origin)
    max_scans = check_int("max_scans", max_scans, low=1)
    seed = check_int("seed", seed, low=0)
    if not isinstance(scans, ScanSet):
        raise InputError("scans", f"expected a crfmap.recording.ScanSet, got {type(scans).__name__}")
    true_poses = _check_poses("scans.laser_poses", scans.laser_poses)
    if len(true_poses) != len(scans):
        raise InputError("scans.laser_poses", f"need one pose per scan ({len(scans)}), got {len(true_poses)}")
    beams = Beams.from_scans(scans, model)
    chosen = _spread(np.flatnonzero(beams.usable()), max_scans)
    if chosen.size == 0:
        raise InputError(scans.source or "scans", "no scan has a beam nav2_amcl would use (all beams are "
                         "no-return, out of range or invalid)")
    beams = Beams(beams.ranges[chosen], beams.bearings, beams.range_max)
    true_poses = true_poses[chosen]
    lfield = LikelihoodField.from_probability(probability, resolution, origin, model)
    offsets = pose_offsets(len(chosen), n_offsets, seed)
    weights = lfield.log_weights(beams, np.concatenate([true_poses[:, None], true_poses[:, None] + offsets], axis=1))
    starts = start_poses(true_poses, seed)
    found = search_poses(lfield, beams, starts)
    translation = np.hypot(found[:, 0] - true_poses[:, 0], found[:, 1] - true_poses[:, 1])
    rotation = np.degrees(np.abs(np.angle(np.exp(1j * (found[:, 2] - true_poses[:, 2])))))
    return LocalisationResult(chosen, weights[:, 0], weights[:, 1:], found, starts, translation, rotation,
                              seconds=time.perf_counter() - started)


def compare_localisation(maps: dict, resolution, origin, scans: ScanSet, reference="raw", n_boot=1000,
                         level=0.95, seed=0, **options) -> dict:
    """Localisation scores of several maps ``{method: P [y, x]}`` on the same held-out scans, paired.

    Returns ``{method: {metric: value, metric + "_ci": (lo, hi), metric + "_diff": value - reference's,
    metric + "_diff_ci": (lo, hi), "scans": n, "seconds": s}}`` for the :data:`METRICS`; intervals are
    percentile bootstrap intervals over scans (scans resampled with replacement, ``n_boot`` times; the
    same resamples for every method, so a difference's interval is paired). ``n_boot=0`` skips them.
    ``options`` go to :func:`localise` (``model``, ``max_scans``, ``n_offsets``); ``seed`` seeds the poses
    and the resamples. Scans are resampled one by one: neighbouring held-out scans are correlated, so
    thin the set (``max_scans``) to scans seconds apart for intervals that hold.

    >>> from crfmap.recording import ScanSet
    >>> p = np.zeros((30, 30)); p[[4, 25], :] = 1.0; p[:, [4, 25]] = 1.0
    >>> thick = np.maximum(p, np.roll(p, 1, axis=0))
    >>> poses = np.array([[0.6, 0.7, 0.2], [0.9, 0.6, 1.0], [0.7, 0.9, -2.0]])
    >>> from crfmap.sim import Laser
    >>> from crfmap.sim.simulator import cast_rays
    >>> laser = Laser.with_fov(360, 60)
    >>> scans = ScanSet(cast_rays(OccupancyGrid(p, 0.05), laser, poses).astype(np.float32), laser.angle_min,
    ...                 laser.angle_increment, laser.range_min, laser.range_max, poses, np.arange(3.0))
    >>> out = compare_localisation({"raw": p, "thick": thick}, 0.05, (0, 0), scans, n_boot=50)
    >>> sorted(out["raw"])[:4], out["raw"]["found_diff"]
    (['beats_offsets', 'beats_offsets_ci', 'beats_offsets_diff', 'beats_offsets_diff_ci'], 0.0)
    """
    if not isinstance(maps, dict) or not maps:
        raise InputError("maps", "expected a non-empty {method: P} dictionary")
    if reference not in maps:
        raise InputError("reference", f"{reference!r} is not one of the maps ({', '.join(map(str, maps))})")
    n_boot = check_int("n_boot", n_boot, low=0)
    level = check_number("level", level, low=0, low_open=True, high=1)
    if level == 1:
        raise InputError("level", "must be below 1")
    shapes = {name: np.shape(p) for name, p in maps.items()}
    if len(set(shapes.values())) != 1:
        raise InputError("maps", f"every map must have one shape (one grid), got {shapes}")
    results = {name: localise(p, resolution, origin, scans, seed=seed, **options) for name, p in maps.items()}
    n = len(results[reference].scan_index)
    resamples = np.random.default_rng([check_int("seed", seed, low=0), 2]).integers(0, n, (n_boot, n))
    alpha = (1 - level) / 2
    boot = {name: {m: _statistic(m, v[resamples], axis=1) for m, v in r.per_scan.items()} if n_boot else {}
            for name, r in results.items()}
    out = {}
    for name, r in results.items():
        entry = {}
        for m, value in r.summary().items():
            if m not in METRICS:
                continue
            entry[m] = value
            entry[m + "_diff"] = value - results[reference].summary()[m]
            if n_boot:
                entry[m + "_ci"] = _interval(boot[name][m], alpha)
                entry[m + "_diff_ci"] = _interval(boot[name][m] - boot[reference][m], alpha)
        entry.update(scans=n, seconds=r.seconds)
        out[name] = entry
    return out


# --- helpers ------------------------------------------------------------------------------


def _statistic(metric, values, axis=None):
    """The METRICS' summary over scans: the median of the errors, the mean of the rest."""
    reduce = np.median if metric in ("translation_error", "rotation_error") else np.mean
    result = reduce(values, axis=axis)
    return float(result) if axis is None else result


def _interval(values, alpha):
    return (float(np.quantile(values, alpha)), float(np.quantile(values, 1 - alpha)))


def _spread(indices, count):
    """At most ``count`` of ``indices``, evenly spaced (all of them if there are fewer)."""
    if len(indices) <= count:
        return indices
    return indices[np.unique(np.linspace(0, len(indices) - 1, count).round().astype(np.intp))]


def _scan_ranges(scans) -> np.ndarray:
    if not isinstance(scans, ScanSet):
        raise InputError("scans", f"expected a crfmap.recording.ScanSet, got {type(scans).__name__}")
    ranges = np.asarray(scans.ranges)
    if ranges.ndim != 2 or ranges.shape[1] == 0 or not np.issubdtype(ranges.dtype, np.floating):
        raise InputError("scans.ranges", f"expected a float (n_scans, n_beams >= 1) array, got {ranges.dtype} "
                         f"{ranges.shape}")
    for name in ("angle_min", "angle_increment", "range_min", "range_max"):
        check_number(f"scans.{name}", getattr(scans, name))
    return ranges


def _check_poses(name, poses) -> np.ndarray:
    poses = np.asarray(poses, dtype=np.float64) if np.size(poses) else np.zeros((0, 3))
    if poses.ndim != 2 or poses.shape[1] != 3 or not np.isfinite(poses).all():
        raise InputError(name, f"expected finite (n, 3) x, y, yaw rows, got shape {poses.shape}")
    return poses


def _check_origin(origin) -> tuple:
    values = np.asarray(origin, dtype=np.float64).ravel() if np.size(origin) in (2, 3) else None
    if values is None or not np.isfinite(values).all():
        raise InputError("origin", f"expected (x, y) or (x, y, yaw) [m, m, rad], got {origin!r}")
    if values.size == 3 and values[2] != 0:  # convertMap ignores the yaw: such a map would be misread
        raise InputError("origin", f"nav2_amcl ignores a map's yaw; a rotated map (yaw {values[2]:g}) is not supported")
    return float(values[0]), float(values[1])


def _check_range(name, pair) -> tuple:
    lo, hi = (check_number(name, v, low=0) for v in pair) if np.size(pair) == 2 else (None, None)
    if lo is None or lo > hi:
        raise InputError(name, f"expected (low, high) with 0 <= low <= high, got {pair!r}")
    return lo, hi


__all__ = ["LaserModel", "Beams", "LikelihoodField", "LocalisationResult", "METRICS", "nav2_lethal",
           "distance_field", "beam_indices", "pose_offsets", "start_poses", "search_poses", "localise",
           "compare_localisation"]
