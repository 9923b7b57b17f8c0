"""Bayesian Hilbert maps (Senanayake & Ramos, CoRL 2017): a continuous occupancy map, the ``hilbert`` peer.

P(occupied at x) is a logistic regression on radial-basis features ``phi_j(x) = exp(-gamma |x - c_j|^2)`` with
centres ``c_j`` on a square grid (``feature_spacing`` apart, ``gamma = 1 / (2 length_scale^2)``). The weights have a
diagonal Gaussian posterior ``N(mu, diag(sig))``, learned scan by scan: each scan is one batch whose prior is the
previous batch's posterior (the first prior is N(0, PRIOR_VARIANCE)), and within a batch ``EM_ITERATIONS`` rounds of
the closed-form updates under the Jaakkola-Jordan bound (``lam(xi) = (sigmoid(xi) - 1/2) / (2 xi)``):

- ``sig_j = 1 / (1 / sig0_j + 2 sum_n lam(xi_n) phi_nj^2)``,
  ``mu_j = sig_j (mu0_j / sig0_j + sum_n (y_n - 1/2) phi_nj)``,
- ``xi_n^2 = sum_j phi_nj^2 sig_j + (sum_j phi_nj mu_j)^2``, starting from xi = 1,

exactly as the authors' code (ransalu/Bayesian_Hilbert_Maps, ``BHM2D``: diagonal ``sig``, no bias feature), in
this project's implementation (sparse features, numba), not the authors' program. The mean update keeps only the
precision's diagonal (the authors' choice). A query returns the probit-approximated predictive
``sigmoid(a / sqrt(1 + pi s2 / 8))`` with ``a = phi . mu``, ``s2 = phi^2 . sig``: far from every feature it is 0.5.

Training data per scan: each returned beam's end point (label 1) and free points every ``free_spacing`` metres along
the beam from the sensor up to one spacing before the end (label 0). Features below ``exp(-CUTOFF^2 / 2)`` (beyond
``CUTOFF`` length scales) are dropped, so each point touches only the few dozen centres near it (the authors' dense
kernel matrix would not fit a building).

>>> m = HilbertMap((0.0, 0.0, 2.0, 2.0), feature_spacing=0.5, length_scale=0.3)
>>> m.fit_batch(np.array([[1.5, 1.5], [0.0, 0.0]]), np.array([1.0, 0.0]))
>>> p = m.predict(np.array([[1.5, 1.5], [0.0, 0.0], [9.0, 9.0]]))
>>> bool(p[0] > 0.5 > p[1]), float(p[2])
(True, 0.5)
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from crfmap.checks import check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid

PRIOR_VARIANCE = 10_000.0  # the authors' first prior N(0, 10^4) on every weight
EM_ITERATIONS = 3  # closed-form rounds per batch (scan), as the authors' code
CUTOFF = 4.0  # [length scales] features beyond are dropped (exp(-8) = 3e-4 of the peak)
# Chosen on the Intel log only, as the OctoMap peer's constants (crfmap.assess.peers), then fixed for every recording:
FEATURE_SPACING = 0.075  # [m] between RBF centres
LENGTH_SCALE = 0.025  # [m] RBF width, gamma = 1 / (2 LENGTH_SCALE^2) = 800 / m^2
FREE_SPACING = 0.05  # [m] between free points sampled along a beam


@njit(cache=True, nogil=True)
def _features(points, x0, y0, spacing, nx, ny, inv2l2, reach):
    """Sparse RBF features (CSR: ptr, index, value) of ``points`` [n, 2] on the centre grid."""
    n = points.shape[0]
    side = 2 * reach + 1
    ptr = np.zeros(n + 1, np.int64)
    idx = np.empty(n * side * side, np.int64)
    val = np.empty(n * side * side, np.float64)
    limit = (reach * spacing) ** 2
    k = 0
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        ci = int(math.floor((px - x0) / spacing + 0.5))
        cj = int(math.floor((py - y0) / spacing + 0.5))
        for j in range(max(cj - reach, 0), min(cj + reach + 1, ny)):
            dy = py - (y0 + j * spacing)
            for q in range(max(ci - reach, 0), min(ci + reach + 1, nx)):
                dx = px - (x0 + q * spacing)
                d2 = dx * dx + dy * dy
                if d2 <= limit:
                    idx[k] = j * nx + q
                    val[k] = math.exp(-d2 * inv2l2)
                    k += 1
        ptr[i + 1] = k
    return ptr, idx[:k], val[:k]


@njit(cache=True, nogil=True)
def _lam(xi):
    """Jaakkola-Jordan's lambda(xi) = (sigmoid(xi) - 1/2) / (2 xi) = tanh(xi / 2) / (4 xi); 1/8 at 0."""
    if xi < 1e-6:
        return 0.125
    return math.tanh(0.5 * xi) / (4.0 * xi)


@njit(cache=True, nogil=True)
def _fit_batch(ptr, idx, val, y, mu, sig, n_iter, acc_prec, acc_b, mark, batch, touched, mu0, sig0):  # pragma: no cover
    """The authors' closed-form rounds on one batch; ``mu``, ``sig`` (prior in, posterior out) in place.

    ``mark`` (one int per feature, below ``batch`` on entry) finds the batch's features without sorting."""
    n = ptr.size - 1
    m = 0
    for k in range(idx.size):
        f = idx[k]
        if mark[f] != batch:
            mark[f] = batch
            touched[m] = f
            mu0[m] = mu[f]
            sig0[m] = sig[f]
            m += 1
    xi = np.ones(n)
    for _ in range(n_iter):
        for t in range(m):
            acc_prec[touched[t]] = 0.0
            acc_b[touched[t]] = 0.0
        for i in range(n):
            lam2 = 2.0 * _lam(xi[i])
            r = y[i] - 0.5
            for k in range(ptr[i], ptr[i + 1]):
                acc_prec[idx[k]] += lam2 * val[k] * val[k]
                acc_b[idx[k]] += r * val[k]
        for t in range(m):
            f = touched[t]
            sig[f] = 1.0 / (1.0 / sig0[t] + acc_prec[f])
            mu[f] = sig[f] * (mu0[t] / sig0[t] + acc_b[f])
        for i in range(n):
            a = 0.0
            s2 = 0.0
            for k in range(ptr[i], ptr[i + 1]):
                a += val[k] * mu[idx[k]]
                s2 += val[k] * val[k] * sig[idx[k]]
            xi[i] = math.sqrt(s2 + a * a)


@njit(cache=True, nogil=True)
def _predict(ptr, idx, val, mu, sig):  # pragma: no cover - compiled
    n = ptr.size - 1
    out = np.empty(n)
    for i in range(n):
        a = 0.0
        s2 = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            a += val[k] * mu[idx[k]]
            s2 += val[k] * val[k] * sig[idx[k]]
        z = a / math.sqrt(1.0 + math.pi * s2 / 8.0)
        out[i] = 1.0 / (1.0 + math.exp(-z)) if z >= 0 else math.exp(z) / (1.0 + math.exp(z))
    return out


class HilbertMap:
    """A Bayesian Hilbert map over ``bounds`` (xmin, ymin, xmax, ymax) [m], updated one batch at a time."""

    def __init__(self, bounds, feature_spacing=FEATURE_SPACING, length_scale=LENGTH_SCALE,
                 em_iterations=EM_ITERATIONS, prior_variance=PRIOR_VARIANCE):
        try:
            xmin, ymin, xmax, ymax = (float(v) for v in bounds)
        except (TypeError, ValueError):
            raise InputError("bounds", f"expected (xmin, ymin, xmax, ymax) in metres, got {bounds!r}") from None
        if not all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax)) or xmax < xmin or ymax < ymin:
            raise InputError("bounds", f"need finite xmin <= xmax and ymin <= ymax, got {bounds!r}")
        self.spacing = check_positive("feature_spacing", feature_spacing)
        self.length_scale = check_positive("length_scale", length_scale)
        self.prior_variance = check_positive("prior_variance", prior_variance)
        if not (isinstance(em_iterations, (int, np.integer)) and em_iterations >= 1):
            raise InputError("em_iterations", f"must be a positive integer, got {em_iterations!r}")
        self.em_iterations = int(em_iterations)
        self.origin = (xmin, ymin)
        self.nx = int(math.floor((xmax - xmin) / self.spacing + 1e-9)) + 1
        self.ny = int(math.floor((ymax - ymin) / self.spacing + 1e-9)) + 1
        self.mu = np.zeros(self.nx * self.ny)
        self.sig = np.full(self.nx * self.ny, self.prior_variance)
        d = self.mu.size
        self._mark = np.full(d, -1, np.int64)
        self._work = (np.zeros(d), np.zeros(d))
        self._buffers = (np.empty(d, np.int64), np.empty(d), np.empty(d))
        self.batches = 0

    @property
    def gamma(self) -> float:
        """The RBF's gamma [1/m^2] of ``exp(-gamma d^2)`` (the authors' parameter)."""
        return 1.0 / (2.0 * self.length_scale ** 2)

    def features(self, points):
        """CSR (ptr, index, value) of the features of ``points`` [n, 2] (metres)."""
        p = np.ascontiguousarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
            raise InputError("points", f"expected finite (n, 2) coordinates, got shape {p.shape}")
        reach = int(math.ceil(CUTOFF * self.length_scale / self.spacing))
        return _features(p, self.origin[0], self.origin[1], self.spacing, self.nx, self.ny, self.gamma, reach)

    def fit_batch(self, points, labels):
        """One batch (one scan): the posterior so far is the prior; ``labels`` 1 occupied, 0 free."""
        y = np.asarray(labels, dtype=np.float64)
        if y.shape != (len(points),) or not np.all((y == 0) | (y == 1)):
            raise InputError("labels", f"expected {len(points)} labels of 0 or 1")
        ptr, idx, val = self.features(points)
        if idx.size:
            _fit_batch(ptr, idx, val, y, self.mu, self.sig, self.em_iterations, *self._work, self._mark, self.batches,
                       *self._buffers)
        self.batches += 1

    def predict(self, points) -> np.ndarray:
        """P(occupied) at ``points`` [n, 2] (metres)."""
        return _predict(*self.features(points), self.mu, self.sig)


def beam_samples(scans, free_spacing=FREE_SPACING, bounds=None, max_range_is_no_return=True):
    """Per scan, (points [n, 2], labels [n]) as the module docstring says; readings follow REP 117 and no-return beams
    give nothing. With ``bounds`` (xmin, ymin, xmax, ymax), points outside are dropped.

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.array([[1.0]], np.float32), 0.0, 0.0, 0.1, 5.0, np.zeros((1, 3)), np.zeros(1))
    >>> pts, lab = next(iter(beam_samples(s, free_spacing=0.3)))
    >>> pts[:, 0].round(2).tolist(), lab.tolist()
    ([1.0, 0.3, 0.6], [1.0, 0.0, 0.0])
    """
    spacing = check_positive("free_spacing", free_spacing)
    ranges = np.asarray(scans.ranges, dtype=np.float64)
    angles = float(scans.angle_min) + float(scans.angle_increment) * np.arange(ranges.shape[1])
    range_min, range_max = float(np.float32(scans.range_min)), float(np.float32(scans.range_max))
    for r, (x, y, yaw) in zip(ranges, np.asarray(scans.laser_poses, dtype=np.float64)):
        with np.errstate(invalid="ignore"):
            hit = np.isfinite(r) & (r >= range_min) & (r <= range_max)
            if max_range_is_no_return:
                hit &= r != range_max
        rr, a = r[hit], yaw + angles[hit]
        cos, sin = np.cos(a), np.sin(a)
        counts = np.maximum(np.floor(rr / spacing + 1e-9).astype(np.int64) - 1, 0)  # free points at k*spacing < r
        beam = np.repeat(np.arange(rr.size), counts)
        k = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + 1
        t = k * spacing
        points = np.concatenate([np.column_stack([x + rr * cos, y + rr * sin]),
                                 np.column_stack([x + t * cos[beam], y + t * sin[beam]])])
        labels = np.concatenate([np.ones(rr.size), np.zeros(t.size)])
        if bounds is not None:
            xmin, ymin, xmax, ymax = bounds
            keep = (points[:, 0] >= xmin) & (points[:, 0] <= xmax) & (points[:, 1] >= ymin) & (points[:, 1] <= ymax)
            points, labels = points[keep], labels[keep]
        yield points, labels


def hilbert_grid(scans, resolution, bounds, feature_spacing=FEATURE_SPACING, length_scale=LENGTH_SCALE,
                 free_spacing=FREE_SPACING, progress=False):
    """[y, x] P(occupied) at the cell centres of the grid over ``bounds`` after fitting every scan in order."""
    resolution = check_positive("resolution", resolution)
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    width = max(1, int(math.ceil((xmax - xmin) / resolution - 1e-9)))
    height = max(1, int(math.ceil((ymax - ymin) / resolution - 1e-9)))
    model = HilbertMap((xmin, ymin, xmin + width * resolution, ymin + height * resolution), feature_spacing,
                       length_scale)
    batches = beam_samples(scans, free_spacing, bounds=bounds)
    if progress:
        from tqdm.auto import tqdm

        batches = tqdm(batches, total=len(scans.ranges), desc="Hilbert map", unit="scan")
    for points, labels in batches:
        model.fit_batch(points, labels)
    yy, xx = np.mgrid[0:height, 0:width]
    centres = np.column_stack([xmin + (xx.ravel() + 0.5) * resolution, ymin + (yy.ravel() + 0.5) * resolution])
    p = model.predict(centres).reshape(height, width)
    return OccupancyGrid(p, resolution=resolution, origin=(xmin, ymin, 0.0),
                         meta={"model": "hilbert", "feature_spacing": model.spacing, "length_scale": model.length_scale,
                               "gamma": model.gamma, "free_spacing": float(free_spacing), "scans": model.batches})
