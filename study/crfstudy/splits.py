"""Harder scan splits than even / odd scans: in time and in space.

Even and odd scans (:func:`crfmap.assess.scansplit.scan_split`) come from nearly the same poses, so
the second half sees almost what the first saw. Here the map's scans and the scoring scans differ
more (each a boolean choice of the scans that build the map; the others score it):

- :func:`temporal_halves`: the first half of the log builds, the second half scores;
- :func:`scan_blocks`: blocks of ``block`` consecutive scans, alternately building and scoring;
- :func:`spatial_tiles`: the robot's position decides: scans taken in the "black" squares of a
  checkerboard of ``tile`` x ``tile`` m build, those taken in the "white" ones score.

:func:`split_by` counts the two halves on one grid (the same grid as :func:`scan_split`), so the
result is a :class:`~crfmap.assess.scansplit.ScanSplit` that :func:`~crfmap.assess.scansplit.score`
scores with the same metrics and spatial-block bootstrap intervals.

>>> temporal_halves(5).astype(int).tolist(), scan_blocks(6, 2).astype(int).tolist()
([1, 1, 1, 0, 0], [1, 1, 0, 0, 1, 1])
>>> spatial_tiles(np.array([[0.5, 0.5, 0], [1.5, 0.5, 0], [1.5, 1.5, 0]]), 1.0).astype(int).tolist()
[1, 0, 1]
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from crfmap.errors import InputError
from crfmap.assess.scansplit import ScanSplit, score
from crfmap.mapping.builder import count_hits, scan_bounds


def temporal_halves(n_scans: int) -> np.ndarray:
    """True for the first half of ``n_scans`` scans (the map), False for the second (the scoring)."""
    n = int(n_scans)
    if n < 2:
        raise InputError("scans", f"need at least 2 scans to split, got {n}")
    return np.arange(n) < (n + 1) // 2


def scan_blocks(n_scans: int, block: int) -> np.ndarray:
    """True for scans in even-numbered blocks of ``block`` consecutive scans."""
    if not (isinstance(block, (int, np.integer)) and block >= 1):
        raise InputError("block", f"must be a positive number of scans, got {block!r}")
    return (np.arange(int(n_scans)) // block) % 2 == 0


def spatial_tiles(laser_poses, tile: float) -> np.ndarray:
    """True for scans whose laser (x, y) lies in a "black" square of a ``tile`` [m] checkerboard."""
    if not (isinstance(tile, (int, float)) and math.isfinite(tile) and tile > 0):
        raise InputError("tile", f"must be a positive size in metres, got {tile!r}")
    p = np.asarray(laser_poses, dtype=np.float64)
    return (np.floor(p[:, 0] / tile) + np.floor(p[:, 1] / tile)) % 2 == 0


def _subset(scans, keep):
    return replace(scans, ranges=np.asarray(scans.ranges)[keep], laser_poses=np.asarray(scans.laser_poses)[keep],
                   stamps=np.asarray(scans.stamps)[keep])


def split_by(scans, first, resolution: float, bounds=None):
    """A :class:`ScanSplit`: the scans where ``first`` is True build the map, the others score it.

    The grid covers every scan (as :func:`crfmap.assess.scansplit.scan_split`) unless ``bounds``
    (xmin, ymin, xmax, ymax) [m] is given.
    """
    keep = np.asarray(first, dtype=bool)
    if keep.shape != (len(scans),):
        raise InputError("first", f"needs one value per scan ({len(scans)}), got shape {keep.shape}")
    if keep.all() or not keep.any():
        raise InputError("first", f"both halves need scans, got {int(keep.sum())} of {len(scans)} in the first")
    if bounds is None:
        xmin, ymin, xmax, ymax = scan_bounds(scans)
        bounds = (round(math.floor(xmin / resolution) * resolution, 9),
                  round(math.floor(ymin / resolution) * resolution, 9), xmax, ymax)
    a, b = _subset(scans, keep), _subset(scans, ~keep)
    h1, e1 = count_hits(a, resolution, bounds=bounds)
    h2, e2 = count_hits(b, resolution, bounds=bounds)
    return ScanSplit(h1, e1, h2, e2, resolution=float(resolution), origin=(float(bounds[0]), float(bounds[1]), 0.0),
                     bounds=tuple(float(v) for v in bounds), source=getattr(scans, "source", ""), first_scans=a)


def harder_splits(scans, resolution: float, block: int = 50, tile: float = 4.0) -> dict:
    """{name: ScanSplit} of the three harder splits of ``scans`` (see the module docstring)."""
    n = len(scans)
    return {"temporal halves": split_by(scans, temporal_halves(n), resolution),
            "scan blocks": split_by(scans, scan_blocks(n, block), resolution),
            "spatial tiles": split_by(scans, spatial_tiles(scans.laser_poses, tile), resolution)}


def headline(scores: dict, method: str, reference: str = "raw", metric: str = "brier") -> dict:
    """{group: {"diff", "ci", "method", "reference"}}: ``method`` minus ``reference`` from a paired :func:`score`."""
    out = {}
    for group, entry in scores[method].items():
        out[group] = {"method": entry[metric], "reference": scores[reference][group][metric],
                      "diff": entry.get(metric + "_diff"), "ci": entry.get(metric + "_diff_ci"),
                      "cells": entry["cells"]}
    return out


def block_sensitivity(split, predictions: dict, blocks, reference: str = "raw", n_boot: int = 200, seed: int = 0,
                      metric: str = "brier") -> dict:
    """{block: {method: {group: (lo, hi)}}}: the paired difference's interval for each bootstrap block side."""
    out = {}
    for b in blocks:
        s = score(split, predictions, n_boot=n_boot, block=int(b), seed=seed, reference=reference, metrics=(metric,))
        out[int(b)] = {m: {g: s[m][g].get(metric + "_diff_ci") for g in s[m]} for m in predictions if m != reference}
    return out
