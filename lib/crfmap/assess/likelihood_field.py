"""nav2_amcl's likelihood-field laser model, exactly as nav2 computes it: how well a scan fits a map at a pose.

Maps are scored with it in :mod:`crfmap.assess.localisation`. The model, as read from ros-navigation/navigation2
(main at commit a3a97043ee93, 2026-08-21):

- ``nav2_amcl/src/amcl_node.cpp``, ``convertMap`` (lines 1348-1373): an OccupancyGrid value of exactly 100 is an
  obstacle (``occ_state = +1``), 0 is free, anything else unknown; free and unknown cells play no part in this model.
  In the map nav2 loads from a file crfmap writes (:func:`nav2_lethal`), ``OccupancyGrid.to_int8`` rounds P to
  percent, map_saver's trinary rule writes values >= round(100 * 0.65) black, and nav2_map_server reads black back as
  100 (checked against :func:`crfmap.io.map_server.save_map` / ``load_map`` in the tests). ``convertMap`` keeps the
  map's origin position and ignores its yaw.
- ``nav2_amcl/src/map/map_cspace.cpp``, ``map_update_cspace`` (lines 148-210) with ``CachedDistanceMap`` and
  ``enqueue`` (lines 49-141): ``occ_dist`` [m] is meant as each cell's Euclidean distance to the nearest obstacle
  cell, kept while the distance in cells is <= ``int(max_occ_dist / resolution)``, else ``max_occ_dist``; stored as
  float. :func:`distance_field` computes exactly that. nav2's own brushfire (a cell takes the distance to the
  obstacle its first-popped neighbour came from) is at times above the exact distance, never below
  (``nav2_brushfire`` in the tests ports it line by line).
- ``nav2_amcl/include/nav2_amcl/map/map.hpp`` (lines 121-133) with ``convertMap``: a point (x, y) falls in cell
  ``floor((x - origin_x') / res + 0.5) + size_x / 2`` where ``origin_x' = origin_x + (size_x / 2) * res`` (integer
  halves): AMCL *rounds* to the nearest cell corner index, reading cell i as centred on ``origin_x + i * res``, half a
  cell below where the OccupancyGrid convention (and crfmap) puts it. This module does the same, so a perfect map's
  best pose sits about (res/2, res/2) from the true one; pass ``origin`` shifted by ``+res/2`` in x and y to measure
  without that shift.
- ``nav2_amcl/src/sensors/laser/likelihood_field_model.cpp``, ``sensorFunction`` (lines 49-140): beams ``0, step, 2
  step, ...`` with ``step = max(1, (range_count - 1) // (max_beams - 1))`` (lines 68-73); a beam is skipped if its
  range is ``>= range_max`` (line 92) or NaN (line 97); its end point at the laser pose plus range along ``yaw +
  bearing`` (lines 104-105); ``z`` = that cell's ``occ_dist``, or ``max_occ_dist`` off the map (lines 114-118); ``pz
  = z_hit exp(-z^2 / (2 sigma_hit^2)) + z_rand / range_max`` (lines 121-123, no Gaussian normalisation); the scan's
  weight is ``p = 1 + sum pz^3`` (line 132; not a product of pz), and :func:`LikelihoodField.log_weights` returns
  ``log p``.
- ``nav2_amcl/src/amcl_node.cpp``, ``updateFilter`` (lines 717-743): ``range_max = min(scan range_max,
  laser_max_range)`` when ``laser_max_range > 0``; readings ``<= range_min`` (``max(scan range_min,
  laser_min_range)`` when ``laser_min_range > 0``) become ``range_max`` and so are skipped. With REP 117 ranges (+inf
  no return, -inf too close, NaN invalid) the beams used are the finite ones strictly between range_min and range_max.
  ``LikelihoodFieldModel::sensorUpdate`` updates nothing when ``max_beams < 2`` (likelihood_field_model.cpp line
  146), so :class:`LaserModel` refuses it.
- Parameter defaults (amcl_node.cpp lines 955-987) are :class:`LaserModel`'s.

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
from dataclasses import dataclass
import numpy as np
from scipy import ndimage
from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, check_probability_array
from crfmap.io.map_server import OCCUPIED_THRESH_DEFAULT
from crfmap.recording import ScanSet

LETHAL_VALUE = 100  # amcl_node.cpp convertMap: only this OccupancyGrid value is an obstacle (occ_state +1)
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

    >>> nav2_lethal(np.array([[0.5, 0.644, 0.646, 1.0]])).tolist()
    [[False, False, True, True]]
    """
    values = OccupancyGrid(check_probability_array(probability, "probability")).to_int8()
    written_occupied = values >= int(np.rint(OCCUPIED_THRESH_DEFAULT * 100.0))  # map_server.py, trinary image
    return written_occupied  # read back as LETHAL_VALUE by nav2_map_server, then occ_state +1 in convertMap


def distance_field(lethal, resolution, max_dist=LaserModel.laser_likelihood_max_dist) -> np.ndarray:
    """nav2_amcl's ``occ_dist`` [m] (float32, [y, x]): distance to the nearest ``lethal`` cell, ``max_dist`` beyond
    ``int(max_dist / resolution)`` cells (C's truncation) and everywhere in a map without lethal cells.

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
    """The beams nav2_amcl uses from each scan: ``ranges`` [n, b] (NaN where skipped) at ``bearings`` [b]."""

    ranges: np.ndarray  # (n_scans, n_used) float64 [m], NaN = beam skipped
    bearings: np.ndarray  # (n_used,) [rad] in the laser frame
    range_max: float  # [m] the scan's, or laser_max_range if smaller: the z_rand / range_max term's

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
    """A map as nav2_amcl's likelihood-field model sees it: ``occ_dist`` [y, x] and ``origin``, cell (0, 0)'s corner
    as an OccupancyGrid's (cells are looked up as AMCL does: see the module doc)."""

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
        """``log p`` (n, k) of scan i at each laser pose ``poses[i, k]`` (x, y, yaw in the map frame); ``p = 1 + sum
        over used beams of pz^3`` is the factor AMCL multiplies a particle's weight by."""
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


def _check_origin(origin) -> tuple:
    values = np.asarray(origin, dtype=np.float64).ravel() if np.size(origin) in (2, 3) else None
    if values is None or not np.isfinite(values).all():
        raise InputError("origin", f"expected (x, y) or (x, y, yaw) [m, m, rad], got {origin!r}")
    if values.size == 3 and values[2] != 0:  # convertMap ignores the yaw: such a map would be misread
        raise InputError("origin", f"nav2_amcl ignores a map's yaw; a rotated map (yaw {values[2]:g}) is not supported")
    return float(values[0]), float(values[1])


__all__ = ["LaserModel", "Beams", "LikelihoodField", "LETHAL_VALUE", "nav2_lethal", "distance_field", "beam_indices"]
