"""The closed-loop study (thesis sec. 4.3, issue 37 part 3): runs, the paired table over floors, one run's picture.

Every onboard map kind explores the same scenes with the same seed (:func:`crfstudy.closed_loop.exploration.explore`),
then the navigation task plans on its finished map (:func:`crfstudy.closed_loop.exploration.navigation_task`).
:func:`paired_table` gives each kind's mean per metric and its paired difference to the raw grid with a
bootstrap interval over the scenes (:func:`crfstudy.paired.paired_difference`, seeded). Notebook 11 reads it:
:class:`~crfstudy.closed_loop.exploration.ExploreSettings` (how the robot explores) is taken from here with the
rest, and :func:`warm_up` compiles every onboard map's kernels before the timed runs.

>>> scenes = closed_loop_scenes(n_floors=1, floor_size=(6.0, 5.0), thesis_scenes=())
>>> [label for label, _ in scenes]
['office-0']
"""
from __future__ import annotations

import time

import numpy as np

from crfstudy.paired import paired_difference
from crfmap.errors import InputError
from crfstudy.closed_loop.exploration import ExploreSettings, explore, map_scores, navigation_task
from crfstudy.closed_loop.onboard import ONBOARD_MAPS
from crfmap.world.office import office_floor
from crfmap.world.scenes import make_scene

# metric: (label, lower is better)
METRICS = {
    "scans": ("scans to 95 % (budget if never)", True),
    "distance": ("distance [m]", True),
    "reached": ("reached 95 %", False),
    "collisions": ("collisions", True),
    "failed_plans": ("plans without a frontier", True),
    "plans_into_walls": ("plans into true walls", True),
    "plans_through_free_walls": ("... through walls mapped free", True),
    "seconds": ("compute [s]", True),
    "dangerous_miss_rate": ("dangerous misses (walls called free)", True),
    "wall_iou": ("wall IoU", False),
    "ghosts": ("ghost cells", True),
    "nav_into_walls": ("navigation: paths into walls", True),
    "nav_failed": ("navigation: no path", True),
}


def closed_loop_scenes(n_floors=20, floor_size=(20.0, 15.0), resolution=0.1, first_seed=0,
                       thesis_scenes=("enclosed-train", "enclosed-test", "occluded-train")) -> list:
    """(label, scene) pairs: ``n_floors`` procedural office floors (seeds ``first_seed``...) and the thesis's scenes."""
    if not (isinstance(n_floors, int) and n_floors >= 0):
        raise InputError("n_floors", f"must be a non-negative integer, got {n_floors!r}")
    width, height = floor_size
    floors = [(f"office-{s}", office_floor(width, height, resolution, seed=s))
              for s in range(first_seed, first_seed + n_floors)]
    return floors + [(name, make_scene(name)) for name in thesis_scenes]


def warm_up(scene, kinds=None, seed=0) -> list:
    """Explore ``scene`` for two scans with every kind (None: :data:`ONBOARD_MAPS`): numba compiles (or loads)
    each onboard map's kernels here, so that no kind's compute time in :func:`run_closed_loop` holds a first
    compile. The kinds warmed, in order."""
    kinds = list(ONBOARD_MAPS) if kinds is None else list(kinds)
    for kind in kinds:
        explore(scene, kind, ExploreSettings(robot_radius=None, max_scans=2), seed=seed)
    return kinds


def _record(label, kind, run, scene, radius, n_pairs, settings, seed):
    nav = navigation_task(run.probability, scene, radius, n_pairs=n_pairs, unknown=settings.unknown, seed=seed)
    record = dict(run.summary(), scene=label, kind=kind, reached=float(run.scans_to_goal is not None),
                  seconds=run.map_seconds + run.plan_seconds, nav_into_walls=nav["into_walls"],
                  nav_failed=nav["failed"], nav_pairs=nav["pairs"], nav_length_ratio=nav["length_ratio"])
    record["scans"] = run.scans_to_goal if run.scans_to_goal is not None else settings.max_scans
    record.update(map_scores(run.probability, scene, run.target))
    return record


def run_closed_loop(scenes, kinds=None, settings: ExploreSettings | None = None, seed=0, n_pairs=20,
                    thesis_radius=None, keep=1, progress=None):
    """Explore every scene with every kind: (records, kept) where ``kept[label][kind]`` is the
    :class:`~crfstudy.closed_loop.exploration.ExplorationRun` of the first ``keep`` scenes (for pictures).

    The thesis's scenes are small rooms for a point robot: they run with ``thesis_radius`` (None: the
    scene's own, 0) instead of ``settings.robot_radius``.
    """
    kinds = list(ONBOARD_MAPS) if kinds is None else list(kinds)
    settings = ExploreSettings() if settings is None else settings
    records, kept = [], {}
    for i, (label, scene) in enumerate(scenes):
        here = settings
        if scene.name != "office":
            here = ExploreSettings(**dict(settings.as_dict(), robot_radius=thesis_radius))
        radius = scene.robot_radius if here.robot_radius is None else here.robot_radius
        for kind in kinds:
            t0 = time.perf_counter()
            run = explore(scene, kind, here, seed=seed)
            records.append(_record(label, kind, run, scene, radius, n_pairs, here, seed))
            if i < keep:
                kept.setdefault(label, {})[kind] = run
            if progress:
                progress(f"{label} {kind}: {run.stop} after {run.scans} scans, {time.perf_counter() - t0:.2f} s")
    return records, kept


def paired_table(records, reference="raw", n_boot=2000, seed=0, level=0.95, metrics=None):
    """(header, rows): per kind and metric the mean over scenes and the paired difference to ``reference``
    with its bootstrap interval over scenes (resampled with replacement, pairs kept). ``metrics``: keys of
    :data:`METRICS` to show (None: all), one row each."""
    kinds = list(dict.fromkeys(r["kind"] for r in records))
    scenes = list(dict.fromkeys(r["scene"] for r in records))
    if reference not in kinds:
        raise InputError("reference", f"{reference!r} is not among the kinds run ({', '.join(kinds)})")
    by = {(r["scene"], r["kind"]): r for r in records}
    header = ["metric"] + [k if k == reference else f"{k} (diff to {reference}, {level:.0%} CI)" for k in kinds]
    rows = []
    for metric in METRICS if metrics is None else metrics:
        label, lower_better = METRICS[metric]
        ref = np.array([by[s, reference][metric] for s in scenes], float)
        row = [label + (" (lower is better)" if lower_better else " (higher is better)"), f"{ref.mean():.4g}"]
        for kind in kinds:
            if kind == reference:
                continue
            vals = np.array([by[s, kind][metric] for s in scenes], float)
            if len(scenes) >= 2:
                d = paired_difference(vals, ref, n_boot=n_boot, seed=seed, level=level, lower_is_better=lower_better)
                lo, hi = d["difference_ci"]
                row.append(f"{vals.mean():.4g} ({d['mean_difference']:+.3g} [{lo:+.3g}, {hi:+.3g}])")
            else:
                row.append(f"{vals.mean():.4g} ({vals.mean() - ref.mean():+.3g})")
        rows.append(row)
    return header, rows


def per_scene_table(records, metrics=("scans", "collisions", "plans_into_walls", "dangerous_miss_rate", "wall_iou")):
    """(header, rows): one row per scene and kind with the stop reason and the chosen metrics."""
    header = ["scene", "kind", "stop"] + [METRICS[m][0] for m in metrics]
    rows = [[r["scene"], r["kind"], r["stop"]] + [r[m] for m in metrics] for r in records]
    return header, rows


def run_figure(scene, runs, title=""):
    """One scene: the truth with every kind's path, then each kind's final map with its path.

    Three panels a row (the truth and four maps in one row were too small to read at the page's width); a spare
    panel holds the paths' legend.
    """
    import matplotlib.pyplot as plt

    from crfstudy.plotting import imshow_extent

    panels = len(runs) + 1
    ncols = min(3, panels)
    nrows = -(-panels // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.4 * ncols, 3.1 * nrows), squeeze=False, layout="constrained")
    axes = axes.flat
    extent = imshow_extent(scene.truth)
    axes[0].imshow(scene.truth.probability, origin="lower", cmap="gray_r", extent=extent, vmin=0, vmax=1)
    for kind, run in runs.items():
        axes[0].plot(run.path[:, 0], run.path[:, 1], lw=0.8, label=kind)
    axes[0].set_title(f"truth and paths {title}".strip(), fontsize=9)
    for ax, (kind, run) in zip(axes[1:], runs.items()):
        ax.imshow(run.probability, origin="lower", cmap="gray_r", extent=extent, vmin=0, vmax=1)
        ax.plot(run.path[:, 0], run.path[:, 1], color="tab:red", lw=0.8)
        ax.plot(*run.path[0], "go", ms=4)
        ax.set_title(f"{kind}: {run.stop}, {run.scans} scans\n{run.collisions} collisions, "
                     f"{run.plans_into_walls} plans into walls", fontsize=9)
    for ax in axes[:panels]:
        ax.set_xticks([]), ax.set_yticks([])
    spare = axes[panels:]
    for ax in spare:
        ax.set_axis_off()
    handles, labels = axes[0].get_legend_handles_labels()
    (spare[0] if len(spare) else axes[0]).legend(handles, labels, title="paths (left panel)", fontsize=9,
                                                 loc="center" if len(spare) else "upper right")
    return fig


def coverage_figure(kept):
    """Coverage against scans for every kept scene and kind."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.2), constrained_layout=True)
    for label, runs in kept.items():
        for kind, run in runs.items():
            ax.plot(np.arange(1, len(run.coverage_trace) + 1), run.coverage_trace, label=f"{label} {kind}", lw=1)
    ax.axhline(0.95, color="k", ls=":", lw=0.8)
    ax.set_xlabel("scans"), ax.set_ylabel("reachable free space observed")
    ax.legend(fontsize=6)
    return fig
