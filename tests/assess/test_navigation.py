"""Navigation metrics: nav2's reading of the written map, against the file itself and slow per-cell loops."""
import argparse
import math
import re

import numpy as np
import pytest

from crfmap.assess.navigation import (COUNTS, FACE_CAP, GHOST_PASSES, RATIOS, nav2_classes, nav_scores, skeleton_length, wall_shape)
from crfmap.io.nav2_values import nav2_values
from crfmap.assess.comparison import compare
from crfmap.assess.scansplit import GROUPS, ScanSplit, block_resamples, percentile_interval, score
from crfmap.commands.build import save_map_output
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.map_server import load_map
from crfmap.io.nav2_costmap import LETHAL_OBSTACLE, NO_INFORMATION, static_layer_costs
from crfmap.crf.presets import DEFAULT_PRESET as D  # the row of the default preset

# P on and around every edge of the written file's classes: nav2's 0.65 / 0.196 and the percent rounding
EDGES = [0.0, 1.0, 0.5, 0.196, 0.2, 0.204, 0.205, 0.2050001, 0.2051, 0.21, 0.64, 0.645, 0.6450001, 0.6451, 0.65,
         np.nextafter(0.5, 0), np.nextafter(0.5, 1), 0.495, 0.505]


def _random_split(seed, shape=(14, 17), unseen_columns=3):
    rng = np.random.default_rng(seed)
    h1, e1, h2, e2 = (rng.integers(0, 4, shape) for _ in range(4))
    h1[:, :unseen_columns] = e1[:, :unseen_columns] = 0  # never seen by the first half
    return ScanSplit(h1, e1, h2, e2, resolution=0.1)


@pytest.mark.parametrize("loader", ["jazzy", "humble"])
def test_classes_equal_what_nav2_loads_from_the_written_map(tmp_path, loader):
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, (30, 40))
    p.flat[: len(EDGES)] = EDGES
    p[5:8, 5:9] = np.round(rng.uniform(0, 1, (3, 4)), 2)  # exact percents
    # the map crfmap infer writes (its own output function), loaded back by nav2's rules
    args = argparse.Namespace(mode=None, save_occupied_thresh=None, save_free_thresh=None, loader=loader)
    save_map_output(OccupancyGrid(p, resolution=0.05), tmp_path / "map.yaml", args)
    loaded = load_map(tmp_path / "map.yaml", loader=loader).to_int8()
    assert set(np.unique(loaded)) <= {-1, 0, 100}
    assert np.array_equal(nav2_values(p, loader), loaded)
    lethal, free = nav2_classes(p, loader)
    costs = static_layer_costs(loaded)
    assert np.array_equal(lethal, costs == LETHAL_OBSTACLE)
    assert np.array_equal(free, ~lethal & (costs != NO_INFORMATION))


def _naive_counts(sp, p, group, radius):
    """{count: int} by one pass over the cells, with brute-force distances to the lethal cells."""
    v = nav2_values(p)
    height, width = p.shape
    lethal_cells = [(i, j) for i in range(height) for j in range(width) if v[i, j] == 100]
    c = dict.fromkeys(COUNTS, 0)

    def held_out(i, j):  # (observed by the second half, occupied there)
        h2, e2 = int(sp.second_hits[i, j]), int(sp.second_passes[i, j])
        return h2 + e2 > 0, h2 >= e2 and h2 > 0

    for i in range(height):
        for j in range(width):
            h2, e2 = int(sp.second_hits[i, j]), int(sp.second_passes[i, j])
            seen1 = sp.first_hits[i, j] + sp.first_passes[i, j] > 0
            if h2 + e2 == 0 or (group == "seen" and not seen1) or (group == "unseen" and seen1):
                continue
            occupied = h2 >= e2 and h2 > 0
            lethal, free = v[i, j] == 100, v[i, j] == 0
            distance = min((math.hypot(i - a, j - b) * sp.resolution for a, b in lethal_cells), default=math.inf)
            candidate = e2 >= GHOST_PASSES and h2 == 0
            c["occupied"] += occupied
            c["lethal"] += lethal
            c["lethal_hits"] += lethal and occupied
            c["misses"] += free and occupied
            c["far_misses"] += free and occupied and distance > radius
            c["unknown_walls"] += (not lethal and not free) and occupied
            c["ghost_candidates"] += candidate
            c["ghosts"] += candidate and lethal
            c["free"] += free
            sides = [(i + a, j + b) for a, b in ((0, 1), (0, -1), (1, 0), (-1, 0))
                     if 0 <= i + a < height and 0 <= j + b < width]
            if occupied and any(held_out(*s) == (True, False) for s in sides):  # a face the held-out scans saw
                c["face_cells"] += 1
                c["face_offset_cells"] += min(min((math.hypot(i - a, j - b) for a, b in lethal_cells),
                                                  default=math.inf), FACE_CAP)
    return c


@pytest.mark.parametrize("seed", [1, 2])
def test_every_metric_equals_a_per_cell_loop(seed):
    sp = _random_split(seed)
    rng = np.random.default_rng(seed + 10)
    p = rng.uniform(0, 1, sp.shape) ** 2  # few lethal cells: some misses lie far from all of them
    p[rng.uniform(size=sp.shape) < 0.2] = 0.5
    radius = 0.15  # [m] 1.5 cells
    out = nav_scores(sp, {"raw": sp.raw_probability(), "p": p}, n_boot=0, cover_radius=radius)
    for group in GROUPS:
        c = _naive_counts(sp, p, group, radius)
        entry = out["p"][group]
        assert {k: entry[k] for k in COUNTS} == pytest.approx(c)
        assert isinstance(entry["face_cells"], int) and c["face_cells"] > 0
        for metric, (num, den) in RATIOS.items():
            expected = c[num] / c[den] if c[den] else float("nan")
            assert entry[metric] == pytest.approx(expected, nan_ok=True), metric
        assert entry["lethal_recall"] + entry["unknown_rate"] + entry["miss_rate"] == pytest.approx(1.0)
    assert 0 < out["p"]["all"]["far_misses"] < out["p"]["all"]["misses"]  # the radius test is exercised
    never = (sp.first_hits + sp.first_passes) == 0
    v = nav2_values(p)
    turned = [(i, j) for i in range(sp.shape[0]) for j in range(sp.shape[1]) if never[i, j] and v[i, j] == 0]
    shape = out["p"]["map"]
    assert shape["unknown_free"] == len(turned)
    assert shape["unknown_free_observed"] == sum(sp.second_hits[t] + sp.second_passes[t] > 0 for t in turned)
    assert shape["unknown_free_occupied"] == sum(bool(sp.labels()[t]) for t in turned)
    # in the unseen group, the never-seen cells called free are the held-out ones of the map's count
    assert out["p"]["unseen"]["free"] == shape["unknown_free_observed"]
    assert out["p"]["unseen"]["misses"] == shape["unknown_free_occupied"]
    # the raw grid leaves never-seen cells unknown: it turns none free and calls none lethal there
    assert out["raw"]["map"]["unknown_free"] == 0 and out["raw"]["unseen"]["lethal"] == 0
    assert out["raw"]["unseen"]["lethal_recall"] == 0.0 and math.isnan(out["raw"]["unseen"]["lethal_precision"])


def test_resampled_ratios_are_ratios_of_block_sums_one_resample_at_a_time():
    sp = _random_split(3, shape=(40, 48))
    p = np.random.default_rng(4).uniform(0, 1, sp.shape)
    preds = {"raw": sp.raw_probability(), "p": p}
    out = nav_scores(sp, preds, n_boot=30, block=8, seed=5)
    resamples = block_resamples(sp, n_boot=30, block=8, seed=5)
    lethal, free = nav2_classes(p)
    for group in ("all", "unseen"):
        r = resamples[group]
        for metric, (num, den) in (("lethal_precision", ("lethal_hits", "lethal")), ("ghost_rate",
                                                                                       ("ghosts", "ghost_candidates"))):
            values = []
            for k in range(30):
                w = r.draws[k][r.inverse]  # each cell's weight: how often its block was drawn
                cells = {"lethal_hits": lethal & sp.labels(), "lethal": lethal & sp.group("all"),
                         "ghosts": lethal & (sp.second_passes >= 2) & (sp.second_hits == 0),
                         "ghost_candidates": (sp.second_passes >= 2) & (sp.second_hits == 0)}
                n, d = np.sum(w * cells[num][r.mask]), np.sum(w * cells[den][r.mask])
                values.append(n / d if d > 0 else np.nan)
            assert out["p"][group][metric + "_ci"] == pytest.approx(percentile_interval(np.array(values)))


def test_intervals_cover_the_estimate_are_seeded_and_raw_against_raw_is_exactly_zero():
    sp = _random_split(6, shape=(64, 64), unseen_columns=16)
    rng = np.random.default_rng(7)
    preds = {"raw": sp.raw_probability(), "same": sp.raw_probability().copy(), "p": rng.uniform(0, 1, sp.shape)}
    a = nav_scores(sp, preds, n_boot=100, block=8, seed=3)
    b = nav_scores(sp, preds, n_boot=100, block=8, seed=3)
    assert repr(a) == repr(b)  # the same numbers (compared as printed: NaN != NaN)
    for name in ("raw", "p"):
        for group in GROUPS:
            for metric in RATIOS:
                v, (lo, hi) = a[name][group][metric], a[name][group][metric + "_ci"]
                if not math.isnan(v):
                    assert lo <= v <= hi, (name, group, metric)
    for group in GROUPS:
        for metric in RATIOS:
            if not math.isnan(a["same"][group][metric]):
                assert a["same"][group][metric + "_diff"] == 0.0
                assert a["same"][group][metric + "_diff_ci"] == (0.0, 0.0)
    assert a["same"]["map"]["thickness_diff"] == 0.0


def test_auc_and_nll_by_sklearn_equal_the_scan_split_scores_and_share_their_intervals():
    sp = _random_split(8, shape=(32, 32))
    preds = {"raw": sp.raw_probability(), "p": np.round(np.random.default_rng(9).uniform(0, 1, sp.shape), 1)}
    s = score(sp, preds, n_boot=20, block=8, seed=1, reference="raw")
    out = nav_scores(sp, preds, n_boot=20, block=8, seed=1)
    for group in GROUPS:
        assert out["p"][group]["auc"] == pytest.approx(s["p"][group]["auc"], abs=1e-12)
        assert out["p"][group]["nll"] == pytest.approx(s["p"][group]["logloss"], rel=1e-12)
        assert out["p"][group]["auc_diff_ci"] == s["p"][group]["auc_diff_ci"]
        assert out["p"][group]["nll_ci"] == s["p"][group]["logloss_ci"]


def test_a_one_cell_wall_is_one_thick_a_three_cell_wall_three_and_a_broken_wall_two_pieces():
    thin = np.zeros((9, 50), bool)
    thin[4, 5:45] = True
    s = wall_shape(thin, 0.05)
    assert s["thickness"] == 1.0 and s["components"] == 1 and s["skeleton_m"] == pytest.approx(2.0)
    assert s["components_per_10m"] == pytest.approx(5.0)
    thick = np.zeros((9, 50), bool)
    thick[3:6, 5:45] = True
    assert wall_shape(thick, 0.05)["thickness"] == pytest.approx(3.0, abs=0.15)
    broken = thin.copy()
    broken[4, 24:26] = False
    s = wall_shape(broken, 0.05)
    assert s["components"] == 2 and s["thickness"] == 1.0
    corner = np.zeros((20, 20), bool)
    corner[5, 5:15] = corner[5:15, 5] = True  # an L (skeletonize cuts its corner cell: a diagonal step)
    assert wall_shape(corner, 0.1)["thickness"] == pytest.approx(19 / (16 + math.sqrt(2) + 1))
    diagonal = np.eye(20, dtype=bool)  # cells touching at corners: sqrt 2 of wall per cell
    assert wall_shape(diagonal, 0.1)["thickness"] == pytest.approx(20 / (19 * math.sqrt(2) + 1))
    empty = wall_shape(np.zeros((4, 4), bool), 0.1)
    assert empty["lethal_cells"] == 0 and math.isnan(empty["thickness"])


def _naive_skeleton_length(s):
    """Each pair of 8-neighbours once: 1 side by side, sqrt 2 corner to corner unless a side neighbour joins them."""
    height, width = s.shape
    cells = {(i, j) for i in range(height) for j in range(width) if s[i, j]}
    length = 0.0
    for i, j in cells:
        length += ((i, j + 1) in cells) + ((i + 1, j) in cells)
        for dj in (-1, 1):
            if (i + 1, j + dj) in cells and (i + 1, j) not in cells and (i, j + dj) not in cells:
                length += math.sqrt(2)
    pieces, todo = 0, set(cells)
    while todo:  # flood fill the 8-connected pieces
        pieces += 1
        stack = [todo.pop()]
        while stack:
            i, j = stack.pop()
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    if (i + di, j + dj) in todo:
                        todo.remove((i + di, j + dj))
                        stack.append((i + di, j + dj))
    return length + pieces


@pytest.mark.parametrize("seed", range(4))
def test_skeleton_length_equals_a_loop_over_neighbour_pairs(seed):
    from skimage.morphology import skeletonize

    rng = np.random.default_rng(seed)
    blobs = rng.uniform(size=(30, 30)) < 0.35
    for mask in (skeletonize(blobs), rng.uniform(size=(12, 12)) < 0.3):
        assert skeleton_length(mask) == pytest.approx(_naive_skeleton_length(mask))


def test_compare_scores_every_row_for_navigation_on_the_same_resamples():
    sp = _random_split(11, shape=(24, 24))
    out = compare(sp, n_boot=10, block=8, seed=2, methods=["raw", "mean3x3", D], keep_beliefs=True)
    assert set(out["_nav"]) == {"raw", "mean3x3", D}
    for name in ("raw", "mean3x3"):  # rows without a gate: nav2 reads their beliefs, scored once
        assert out["_nav"][name]["all"]["auc_ci"] == out[name]["all"]["auc_ci"]
    # the gated default: Brier and the rest on its beliefs, nav2's reading on its gated map
    assert not np.array_equal(out["_maps"][D], out["_beliefs"][D])
    on_map = score(sp, out["_maps"], n_boot=10, block=8, seed=2, metrics=("auc",))
    assert out["_nav"][D]["all"]["auc_ci"] == on_map[D]["all"]["auc_ci"] != out[D]["all"]["auc_ci"]
    alone = nav_scores(sp, compare(sp, n_boot=0, methods=["raw", "mean3x3", D], keep_beliefs=True,
                                   nav=False)["_maps"], n_boot=10, block=8, seed=2)
    assert alone[D]["seen"]["miss_rate_diff_ci"] == out["_nav"][D]["seen"]["miss_rate_diff_ci"]
    assert "_nav" not in compare(sp, n_boot=0, methods=["raw"], nav=False)


def test_bad_input_is_named():
    sp = _random_split(12)
    raw = sp.raw_probability()
    for bad, word in ((np.zeros((3, 3)), "shape"), (np.full(sp.shape, 1.5), "[0, 1]"),
                      (np.where(raw > 0.5, np.nan, raw), "[0, 1]")):
        with pytest.raises(InputError, match="p:.*" + re.escape(word)):
            nav_scores(sp, {"raw": raw, "p": bad}, n_boot=0)
    with pytest.raises(InputError, match="reference"):
        nav_scores(sp, {"p": raw}, n_boot=0)
    with pytest.raises(InputError, match="predictions"):
        nav_scores(sp, {}, n_boot=0)
    with pytest.raises(InputError, match="split"):
        nav_scores(raw, {"raw": raw})
    with pytest.raises(InputError, match="n_boot"):
        nav_scores(sp, {"raw": raw}, n_boot=-1)
    with pytest.raises(InputError, match="cover_radius"):
        nav_scores(sp, {"raw": raw}, cover_radius=float("nan"))
    with pytest.raises(InputError, match="probability"):
        nav2_values(np.full((2, 2), -0.1))
    with pytest.raises(InputError, match="probability"):
        nav2_values(np.zeros(4))
    with pytest.raises(InputError, match="loader"):
        nav2_values(raw, loader="foxy")
    with pytest.raises(InputError, match="lethal"):
        wall_shape(np.zeros((3, 3)), 0.05)
    with pytest.raises(InputError, match="resolution"):
        wall_shape(np.zeros((3, 3), bool), 0.0)


def test_face_offset_measures_how_far_the_maps_walls_sit_from_the_observed_face():
    """A wall face seen by the held-out scans: a map with its lethal cells on the face scores 0, one moved a cell
    back 1, one without walls the cap; against the face mask found by brute force."""
    from crfmap.assess.navigation import FACE_CAP, held_out_face

    h, w = 20, 24
    zeros = np.zeros((h, w), int)
    second_hits, second_passes = zeros.copy(), zeros.copy()
    second_passes[:, :10] = 3  # the robot's side, free
    second_hits[:, 10:12] = 2  # a two-cell-thick wall; its face is column 10
    sp = ScanSplit(second_hits.copy(), second_passes.copy(), second_hits, second_passes, resolution=0.05)
    occupied, free = sp.labels(), sp.group("all") & ~sp.labels()
    brute = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            brute[y, x] = occupied[y, x] and any(0 <= y + dy < h and 0 <= x + dx < w and free[y + dy, x + dx]
                                                 for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)))
    assert np.array_equal(held_out_face(sp), brute) and brute[:, 10].all() and brute.sum() == h

    def lethal_at(column):
        p = np.full((h, w), 0.5)
        p[:, :10] = 0.05
        if column is not None:
            p[:, column] = 0.95
        return p

    got = nav_scores(sp, {"raw": lethal_at(10), "back": lethal_at(11), "far": lethal_at(20), "none": lethal_at(None)},
                     n_boot=20, block=5)
    assert got["raw"]["all"]["face_offset"] == 0.0
    assert got["back"]["all"]["face_offset"] == 1.0 and got["back"]["all"]["face_offset_diff_ci"] == (1.0, 1.0)
    assert got["far"]["all"]["face_offset"] == got["none"]["all"]["face_offset"] == FACE_CAP
    assert got["raw"]["all"]["face_cells"] == h and got["back"]["all"]["face_offset_cells"] == float(h)
