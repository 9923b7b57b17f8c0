"""The simulator and the grid builder (thesis sec. 3.1-3.2, Fig. 11-17): notebook 03's helper.

The notebook makes the scans (``simulate``), the grids (``build_grid``) and reads the recordings
(``read_carmen``, ``read_bag``); this module holds the study machinery around those calls:

- ray casting cell by cell (:func:`cells_until_hit`, :func:`ray_paths`, :func:`tie_rule_paths`,
  :func:`tie_rule_count`), on :func:`line_cells` (the library's ``crfmap.raycast.bresenham_step``, Listing 1's
  Bresenham walk);
- the end points of scans (:func:`scan_end_points`, :func:`end_points`, :func:`in_occupied_cell`,
  :func:`discretisation_share`);
- odometry in the map frame (:func:`odometry_in_map`, :func:`scans_on_odometry`, :func:`motion_summary`);
- timed builds of real recordings (:func:`timed_build`, :func:`recording_summary`, :func:`build_summary`,
  :func:`builder_table`);
- :func:`first_hit`, crfmap's own ray caster (``crfmap.raycast.first_hit_kernel``, which the simulator casts with),
  beside :func:`ray_paths` for the notebook's cross-check;
- the figures (each returns a Figure; the notebook saves it).

>>> occupied = np.zeros((1, 4), dtype=bool); occupied[0, 2] = True
>>> path, hit = cells_until_hit(np.array([[0, 0], [1, 0], [2, 0], [3, 0]]), occupied)
>>> path.tolist(), hit
([[0, 0], [1, 0], [2, 0]], (2, 0))
"""
from __future__ import annotations

import math
import time

import numpy as np
from matplotlib.patches import Circle, Rectangle

from crfmap.errors import InputError
from crfmap.frames import compose
from crfmap.mapping import build_grid
from crfmap.raycast import bresenham_step, first_hit_kernel
from crfmap.recording import ScanSet
from crfstudy.plotting import imshow_extent, show_grid

__all__ = ["builder_table", "build_summary", "cells_until_hit", "discretisation_figure",
           "discretisation_share", "end_points", "first_hit", "in_occupied_cell", "line_cells", "motion_figure",
           "motion_summary", "odometry_in_map", "ray_paths", "raycast_figure", "real_maps_figure", "recording_summary",
           "scan_end_points", "scan_figure", "scans_on_odometry", "tie_rule_count", "tie_rule_figure", "tie_rule_paths",
           "timed_build"]


# ---- ray casting cell by cell ----------------------------------------------------------------------------------------

def line_cells(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """Cells (x, y) of the Bresenham line between two cells, both ends included.

    >>> line_cells(0, 0, 3, 1).tolist()
    [[0, 0], [1, 0], [2, 1], [3, 1]]
    """
    ints = []
    for name, v in zip(("x0", "y0", "x1", "y1"), (x0, y0, x1, y1)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            raise InputError(name, f"cell coordinates must be integers, got {v!r}")
        ints.append(int(v))
    x0, y0, x1, y1 = ints
    out = np.empty((max(abs(x1 - x0), abs(y1 - y0)) + 1, 2), dtype=np.int64)
    n = bresenham_step(x0, y0, x1, y1, out)
    return out[:n]


def first_hit(occupied, start, end):
    """(x, y) of the first occupied cell of ``occupied`` ([y, x] bool) seen from cell ``start`` (x, y) towards cell
    ``end``, or None if the ray reaches ``end`` (or leaves the grid) unblocked.

    >>> occ = np.zeros((1, 5), bool); occ[0, 3] = True
    >>> first_hit(occ, (0, 0), (4, 0))
    (3, 0)
    """
    occ = np.asarray(occupied)
    if occ.ndim != 2 or occ.size == 0:
        raise InputError("occupied", f"expected a non-empty 2-D [y, x] array, got shape {occ.shape}")
    x0, y0 = (int(v) for v in start)
    x1, y1 = (int(v) for v in end)
    x, y, hit = first_hit_kernel(occ.astype(np.bool_), x0, y0, x1, y1)
    return (int(x), int(y)) if hit else None


def cells_until_hit(cells, occupied) -> tuple:
    """The ray's cells (x, y) up to and including the first occupied one, and that cell (None if none).

    The robot's own cell (the first) is not tested; a ray leaving the grid stops there, without a hit.
    """
    h, w = occupied.shape
    for i, (x, y) in enumerate(cells[1:], start=1):
        if not (0 <= x < w and 0 <= y < h):
            return cells[:i], None
        if occupied[y, x]:
            return cells[: i + 1], (int(x), int(y))
    return cells, None


def ray_paths(occupied, robot, targets: dict) -> dict:
    """label -> (cells walked, first occupied cell, the library's ``first_hit``) of a ray from ``robot`` to each target."""
    paths = {}
    for label, target in targets.items():
        path, hit = cells_until_hit(line_cells(*robot, *target), occupied)
        paths[label] = (path, hit, first_hit(occupied, robot, target))
    return paths


def tie_rule_paths(occupied, start, end) -> dict:
    """The ray ``start`` -> ``end`` under both tie rules: rule name -> (cells walked, first occupied cell).

    Listing 1's rule (crfmap's) keeps the minor coordinate near the start at a tie; the other rule
    is the same line cast from the target back.
    """
    rules = {
        "tie rule of Listing 1 (crfmap): the minor coordinate stays near the start": line_cells(*start, *end),
        "the other tie rule (the same line cast from the target)": line_cells(*end, *start)[::-1],
    }
    return {name: cells_until_hit(cells, occupied) for name, cells in rules.items()}


def tie_rule_count(truth, scans, laser_range: float) -> tuple:
    """(beams whose two tie rules stop at different cells, beams) over every beam of ``scans`` over ``truth``.

    Each beam is cast from the laser's cell to the cell at ``laser_range`` along it.
    """
    occupied = truth.probability > 0.5
    reach = laser_range / truth.resolution  # [cells]
    differ = n_rays = 0
    for pose in scans.laser_poses:
        fx, fy = truth.world_to_cell(pose[0], pose[1])
        x0, y0 = int(math.floor(fx)), int(math.floor(fy))
        for a in pose[2] + scans.angles:
            x1, y1 = int(math.floor(fx + reach * math.cos(a))), int(math.floor(fy + reach * math.sin(a)))
            _, hit_a = cells_until_hit(line_cells(x0, y0, x1, y1), occupied)
            _, hit_b = cells_until_hit(line_cells(x1, y1, x0, y0)[::-1], occupied)
            differ += hit_a != hit_b
            n_rays += 1
    return int(differ), n_rays


def raycast_figure(occupied, robot, paths: dict):
    """Fig. 11: the rays of :func:`ray_paths` from ``robot``, each cell they pass outlined."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.2), layout="constrained")
    show_grid(ax, occupied.astype(float), "Fig. 11: ray-cast paths from R (crfmap.raycast)", cells=True)
    for (label, (path, hit, _)), colour, offset in zip(paths.items(), ["C0", "C1"], [-0.12, 0.12]):
        for x, y in path[1:]:
            ax.add_patch(Rectangle((x - 0.5 + 0.06, y - 0.5 + 0.06), 0.88, 0.88, fill=False, ec=colour, lw=2.5))
        ax.plot(path[:, 0] + offset, path[:, 1] + offset, "o-", color=colour,
                label=f"{label}: {len(path)} cells, stops at {hit}")
    ax.text(*robot, "R", ha="center", va="center", fontsize=16, weight="bold", color="C3")
    ax.set_xticks(range(occupied.shape[1]))
    ax.set_yticks(range(occupied.shape[0]))
    ax.legend(loc="upper right", bbox_to_anchor=(1.0, -0.15), ncol=2, fontsize="small")
    return fig


def tie_rule_figure(occupied, start, end, paths: dict):
    """Fig. 15: the constructed gap under both tie rules (``paths`` from :func:`tie_rule_paths`)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 3.6), layout="constrained")
    for ax, (name, (path, hit)) in zip(axes, paths.items()):
        show_grid(ax, occupied.astype(float), "", cells=True)
        ax.set_title(name, fontsize=10)
        ax.plot([start[0], end[0]], [start[1], end[1]], "--", color="0.5", lw=1,
                label="the straight line (centre to centre)")
        ax.plot(path[:, 0], path[:, 1], "o-", color="C3" if hit else "C2", lw=2,
                label=f"blocked at {hit}" if hit else f"sees through the gap to {tuple(end)}")
        ax.text(*start, "R", ha="center", va="center", fontsize=14, weight="bold", color="C3")
        ax.legend(loc="upper left", fontsize="small")
        ax.set_xticks(range(occupied.shape[1]))
        ax.set_yticks(range(occupied.shape[0]))
    return fig


# ---- scans and their end points --------------------------------------------------------------------------------------

def scan_end_points(pose, ranges, angles, range_max: float) -> tuple:
    """(end point of each beam, whether it hit): a no-return beam ends on the range circle."""
    ranges = np.asarray(ranges, dtype=np.float64)
    beam_angles = pose[2] + angles
    hit = np.isfinite(ranges)
    ends = pose[:2] + np.where(hit, ranges, range_max)[:, None] * np.c_[np.cos(beam_angles), np.sin(beam_angles)]
    return ends, hit


def scan_figure(truth, pose, ends, hit, range_max: float, title: str):
    """Fig. 13, 14: the ground truth, and one scan over it (hits red, no-returns to the range circle)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13, 5), layout="constrained")
    show_grid(axes[0], truth, "Fig. 13: ground truth (0/1 cells)")
    ax = axes[1]
    show_grid(ax, truth, title)
    for (ex, ey), h in zip(ends, hit):
        ax.plot([pose[0], ex], [pose[1], ey], color="C1" if h else "C0", lw=0.6, alpha=0.8 if h else 0.35)
    ax.plot(ends[hit, 0], ends[hit, 1], ".", color="C3", ms=4, label="end points (hits)")
    ax.add_patch(Circle(pose[:2], range_max, fill=False, ls="--", ec="C0", lw=1))
    ax.plot(*pose[:2], "s", color="C2", ms=8, label="robot R")
    ax.annotate("", xy=pose[:2] + 0.6 * np.array([math.cos(pose[2]), math.sin(pose[2])]), xytext=pose[:2],
                arrowprops=dict(arrowstyle="-|>", color="C2", lw=2))
    ax.plot([], [], color="C0", lw=0.6, alpha=0.5, label="no return (+inf)")
    ax.legend(loc="lower right", fontsize="small")
    ax.set_xlim(imshow_extent(truth)[:2])
    ax.set_ylim(imshow_extent(truth)[2:])
    return fig


def end_points(recording) -> tuple:
    """(x, y) of every returned beam's end point over all scans of ``recording`` (robot + d (cos a, sin a))."""
    s = recording.scans
    a = s.laser_poses[:, 2:3] + s.angles[None]
    r = s.ranges.astype(np.float64)
    ok = np.isfinite(r)
    r = np.where(ok, r, 0.0)
    x = s.laser_poses[:, 0:1] + r * np.cos(a)
    y = s.laser_poses[:, 1:2] + r * np.sin(a)
    return x[ok], y[ok]


def in_occupied_cell(x, y, truth) -> tuple:
    """(whether each point's cell is occupied in ``truth``, its cell x, its cell y); points off the grid are clipped."""
    fx, fy = truth.world_to_cell(x, y)
    ix = np.clip(np.floor(fx).astype(int), 0, truth.width - 1)
    iy = np.clip(np.floor(fy).astype(int), 0, truth.height - 1)
    return truth.probability[iy, ix] > 0.5, ix, iy


def discretisation_share(recording, truth) -> dict:
    """How many end points ``recording`` has, and the share that lands in a truth-occupied cell."""
    good, _, _ = in_occupied_cell(*end_points(recording), truth)
    return {"end_points": int(good.size), "in_truth_occupied_cell": float(good.mean())}


def discretisation_figure(truth, looks: dict, centre, shares: dict):
    """Fig. 17: the first scan's end points of each look-around (range noise C -> recording), close up.

    Each end point's cell is outlined green when occupied in the truth, blue when not; ``centre`` is
    the middle of the 2 m window; ``shares`` (C -> share over a whole drive) goes into the titles.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(looks), figsize=(12, 6), layout="constrained")
    res = truth.resolution
    gx, gy, _ = truth.origin
    for ax, (noise, rec) in zip(np.atleast_1d(axes), looks.items()):
        x, y = end_points(rec)
        good, ix, iy = in_occupied_cell(x, y, truth)
        first = slice(0, int(np.isfinite(rec.scans.ranges[0]).sum()))  # the first scan only
        show_grid(ax, truth, f"C = {noise:g} m (over the Fig. 16 drive: {100 * shares[noise]:.0f} % of end points "
                             f"in a truth-occupied cell)")
        ax.title.set_fontsize(10)
        for ok, cx, cy in set(zip(good[first].tolist(), ix[first].tolist(), iy[first].tolist())):
            ax.add_patch(Rectangle((gx + cx * res, gy + cy * res), res, res, fill=False, ec="C2" if ok else "C0", lw=2))
        ax.plot(x[first], y[first], ".", color="C3", ms=7, label="end point (robot + d (cos a, sin a))")
        ax.plot([], [], "s", mfc="none", mec="C2", mew=2, ms=10, label="its cell: occupied in the truth")
        ax.plot([], [], "s", mfc="none", mec="C0", mew=2, ms=10, label="its cell: free in the truth")
        ax.legend(loc="lower left", fontsize="small", framealpha=0.9)
        ax.set_xlim(centre[0] - 1.0, centre[0] + 1.0)
        ax.set_ylim(centre[1] - 1.0, centre[1] + 1.0)
    return fig


# ---- odometry ---------------------------------------------------------------------------------------------------------

def odometry_in_map(recording) -> np.ndarray:
    """base_link poses as the odometry reports them, placed in map by map -> odom (the start pose)."""
    return compose(np.asarray(recording.meta["map_to_odom"]), recording.odometry.poses)


def scans_on_odometry(recording) -> ScanSet:
    """The recording's scans re-posed with the odometry's poses: what a builder trusting odometry sees."""
    at = np.searchsorted(recording.odometry.stamps, recording.scans.stamps)
    laser_poses = compose(odometry_in_map(recording)[at], np.asarray(recording.laser_mount))
    s = recording.scans
    return ScanSet(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max, laser_poses, s.stamps,
                   s.frame_id, s.laser_frame_id, s.source + " (odometry poses)")


def motion_summary(recording) -> dict:
    """Steps, true path length and the odometry's position and heading errors (final and largest)."""
    true_xy = recording.true_poses.poses[:, :2]
    odom = odometry_in_map(recording)
    error = np.hypot(*(odom[:, :2] - true_xy).T)
    turn = odom[:, 2] - recording.true_poses.poses[:, 2]
    heading_error = np.degrees(np.abs((turn + np.pi) % (2 * np.pi) - np.pi))
    return {"steps": len(recording.cmd_vel), "path_length_m": float(np.hypot(*np.diff(true_xy, axis=0).T).sum()),
            "final_position_error_m": float(error[-1]), "max_position_error_m": float(error.max()),
            "final_heading_error_deg": float(heading_error[-1])}


def motion_figure(truth, runs: dict, maps: dict, map_errors: dict):
    """Fig. 16: true path and odometry per noise level C (``runs``: C -> recording), then the maps built."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(13, 10), layout="constrained")
    for ax, (noise, rec) in zip(axes[0], runs.items()):
        true_xy = rec.true_poses.poses[:, :2]
        show_grid(ax, truth, f"Fig. 16: C = {noise}: true path and odometry")
        ax.plot(*true_xy.T, color="C2", lw=2, label="true path")
        ax.plot(*odometry_in_map(rec)[:, :2].T, color="C3", lw=1.2, ls="--", label="odometry")
        ax.plot(*true_xy[0], "o", color="k", label="start")
        ax.legend(loc="lower right", fontsize="small")
    for ax, (name, grid) in zip(axes[1], maps.items()):
        show_grid(ax, grid, f"{name} (arctan model; MSE vs truth {map_errors[name]:.4f})")
    return fig


# ---- the builder on real recordings -----------------------------------------------------------------------------------

def timed_build(scans, resolution: float, model: str, repeats: int) -> tuple:
    """(grid, median seconds of ``repeats`` builds) after one untimed build, which compiles (or loads) numba."""
    build_grid(scans, resolution, model=model)
    seconds = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        grid = build_grid(scans, resolution, model=model)
        seconds.append(time.perf_counter() - t0)
    return grid, float(np.median(seconds))


def recording_summary(label: str, recording) -> dict:
    """A recording's size: scans, beams per scan, recorded seconds, laser mount and where its poses come from."""
    s = recording.scans
    return {"label": label, "scans": len(s), "beams_per_scan": int(s.ranges.shape[1]),
            "recording_seconds": float(s.stamps[-1] - s.stamps[0]), "mount": list(recording.laser_mount),
            "pose_source": recording.meta.get("pose_source", "corrected poses")}


def build_summary(grid, seconds: float, summary: dict) -> dict:
    """One timed build of a recording (``summary`` from :func:`recording_summary`): speed, shape, known and occupied cells."""
    return {"seconds": seconds, "scans_per_second": summary["scans"] / seconds, "shape": list(grid.shape),
            "real_time_factor": summary["recording_seconds"] / seconds, "beams_used": grid.meta["beams_used"],
            "known_fraction": float(grid.known().mean()), "occupied_cells": int((grid.probability > 0.5).sum())}


def builder_table(rows: dict) -> tuple:
    """(header, rows) of the real-data builds: one row per recording summary (entries that are dicts)."""
    header = ["recording", "scans x beams", "recorded [s]", "grid (H x W)", "arctan [ms]", "log-odds [ms]",
              "real-time factor (arctan)", "occupied cells arctan / log-odds", "cells with an occupied hit"]
    table = [[r["label"], f'{r["scans"]} x {r["beams_per_scan"]}', r["recording_seconds"],
              "{} x {}".format(*r["arctan"]["shape"]), 1000 * r["arctan"]["seconds"], 1000 * r["logodds"]["seconds"],
              r["arctan"]["real_time_factor"], f'{r["arctan"]["occupied_cells"]} / {r["logodds"]["occupied_cells"]}',
              r["cells_with_an_occupied_hit"]] for r in rows.values() if isinstance(r, dict)]
    return header, table


def real_maps_figure(recordings: dict, grids: dict, builder_numbers: dict, resolution: float):
    """Both models' maps of each recording (``recordings``: key -> (label, recording)), the laser's path on top."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(recordings), 2, figsize=(12, 6 * len(recordings)), layout="constrained")
    for row_axes, (key, (label, rec)) in zip(axes, recordings.items()):
        for ax, model in zip(row_axes, ("arctan", "logodds")):
            name = "arctan (thesis eq. 16)" if model == "arctan" else "log-odds (Prob. Robotics ch. 9)"
            show_grid(ax, grids[key, model], f"{label}\n{name}, {resolution:g} m, "
                                             f"{1000 * builder_numbers[key][model]['seconds']:.0f} ms")
            ax.plot(*rec.scans.laser_poses[:, :2].T, color="C3", lw=0.5, alpha=0.7)
    return fig
