"""Localisation on a map: nav2_amcl's likelihood-field laser model, scored on held-out scans.

A map is good for a robot if the robot can find itself on it. nav2 localises with AMCL, whose default laser model scores
a scan at a pose by how far each beam's end point lands from the map's nearest obstacle
(:mod:`crfmap.assess.likelihood_field`). Each held-out scan (the map was *not* built from it) asks two questions
(:data:`METRICS`): does it score higher at its corrected (true) laser pose than at nearby offset poses
(:func:`pose_offsets`)? And does a search maximising the same weight (:func:`search_poses`), started off the true pose
(:func:`start_poses`), come back to it? :func:`compare_localisation` scores several maps on the same scans, offsets and
starting poses, with each metric's paired difference to a reference map (the raw grid) and a bootstrap interval.
"""
from __future__ import annotations
import math
import time
from dataclasses import dataclass, field
import numpy as np
from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.recording import ScanSet
from crfmap.assess.likelihood_field import Beams, LaserModel, LikelihoodField, _check_origin
from crfmap.assess.scansplit import percentile_interval

OFFSET_TRANSLATION = (0.05, 0.30)  # [m] the discrimination offsets' distance from the true pose
OFFSET_ROTATION_DEG = (2.0, 10.0)  # [deg] and their turn
START_TRANSLATION = 0.30  # [m] the pose search starts at most this far from the true pose
START_ROTATION_DEG = 10.0  # [deg] and turned at most this much
FOUND_TRANSLATION = 0.10  # [m] a search ending within this distance ...
FOUND_ROTATION_DEG = 3.0  # [deg] ... and this turn of the true pose found it
DEFAULT_MODEL = LaserModel()  # nav2_amcl's defaults
METRICS = {  # name: higher is better
    "beats_offsets": True,  # mean over scans of the share of offset poses the true pose beats (ties count one half)
    "log_margin": True,  # mean over scans of log p(true) - log p(offset), averaged over the offsets
    "translation_error": False,  # median over scans [m] after the pose search
    "rotation_error": False,  # median over scans [deg] after the pose search
    "found": True,  # share of scans the search ends within FOUND_TRANSLATION and FOUND_ROTATION_DEG
}


def pose_offsets(n_scans, n_offsets, seed=0, translation=OFFSET_TRANSLATION,
                 rotation_deg=OFFSET_ROTATION_DEG) -> np.ndarray:
    """Seeded pose offsets (dx [m], dy [m], dyaw [rad]), (n_scans, n_offsets, 3): a uniform distance in
    ``translation`` [m] in a uniform direction, a uniform turn in ``rotation_deg`` with a random sign.

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

    Every round scores the ``(2 span + 1)^3`` poses ``centre + (i step, j step, k step_deg)``, ``-span <= i, j, k <=
    span``, and moves to the best; when the centre is best (ties keep it) the steps halve. A scan stops once its
    translation step is below ``min_step`` [m], or after ``max_rounds``. The first grid spans +-16 cm and +-6 degrees
    by default and the search walks on from there, so starts 30 cm / 10 degrees off are in reach. Returns (n, 3).
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
    """Per-scan localisation scores of one map on held-out scans; ``summary()`` gives the :data:`METRICS`."""

    scan_index: np.ndarray  # (n,) the scans scored, indices into the ScanSet given to localise
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


def localise(probability, resolution, origin, scans: ScanSet, *, model: LaserModel = DEFAULT_MODEL,
             max_scans=500, n_offsets=16, seed=0) -> LocalisationResult:
    """Score the map ``probability`` [y, x] (cell (0, 0)'s corner at ``origin``) on held-out ``scans``.

    ``scans.laser_poses`` are the corrected (true) laser poses in the map frame. At most ``max_scans`` scans are
    used, evenly spaced; scans with no beam AMCL uses are left out (every pose scores alike). Offsets and starting
    poses depend on ``seed`` and the scans only, so maps scored with one seed are scored on the same poses.

    >>> from crfmap.grid import OccupancyGrid
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
    metric + "_diff_ci": (lo, hi), "scans": n, "seconds": s}}`` for the :data:`METRICS`; intervals are percentile
    bootstrap intervals over scans, the same resamples for every method (``n_boot=0``: none). ``options`` go to
    :func:`localise`; ``seed`` seeds the poses and the resamples. Scans are resampled one by one, but neighbouring
    scans are correlated: thin the set (``max_scans``) to scans seconds apart for intervals that hold.

    >>> from crfmap.grid import OccupancyGrid
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
                entry[m + "_ci"] = percentile_interval(boot[name][m], level)
                entry[m + "_diff_ci"] = percentile_interval(boot[name][m] - boot[reference][m], level)
        entry.update(scans=n, seconds=r.seconds)
        out[name] = entry
    return out


def _statistic(metric, values, axis=None):
    """The METRICS' summary over scans: the median of the errors, the mean of the rest."""
    reduce = np.median if metric in ("translation_error", "rotation_error") else np.mean
    result = reduce(values, axis=axis)
    return float(result) if axis is None else result


def _spread(indices, count):
    """At most ``count`` of ``indices``, evenly spaced (all of them if there are fewer)."""
    if len(indices) <= count:
        return indices
    return indices[np.unique(np.linspace(0, len(indices) - 1, count).round().astype(np.intp))]


def _check_poses(name, poses) -> np.ndarray:
    poses = np.asarray(poses, dtype=np.float64) if np.size(poses) else np.zeros((0, 3))
    if poses.ndim != 2 or poses.shape[1] != 3 or not np.isfinite(poses).all():
        raise InputError(name, f"expected finite (n, 3) x, y, yaw rows, got shape {poses.shape}")
    return poses


def _check_range(name, pair) -> tuple:
    lo, hi = (check_number(name, v, low=0) for v in pair) if np.size(pair) == 2 else (None, None)
    if lo is None or lo > hi:
        raise InputError(name, f"expected (low, high) with 0 <= low <= high, got {pair!r}")
    return lo, hi
__all__ = ["LocalisationResult", "METRICS", "pose_offsets", "start_poses", "search_poses", "localise",
           "compare_localisation"]
