"""Notebook 07's helper: the LBP runs' bookkeeping, Table 26's rows, the same-cell scores, the figures and the
online table, on small maps whose answers are known."""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from crfmap.crf import DEFAULT_HIDDEN, DEFAULT_LINK, infer, near_known
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.mapping import OnlineMapper, build_grid
from crfstudy.experiments import intel_office as office
from crfstudy.experiments.office_online import map_online

LBP_OPTIONS = {"tol": 1e-4, "max_iter": 200}
THESIS_OPTIONS = {"schedule": "thesis", "max_iter": 2}


def room_map(unknown_cols=4):
    """A 16 x 20 room: a one-cell wall ring, free inside, the right ``unknown_cols`` columns never seen."""
    p = np.full((16, 20), 0.1)
    p[0, :] = p[-1, :] = p[:, 0] = p[:, -1] = 0.9
    p[:, -unknown_cols:] = UNKNOWN
    return OccupancyGrid(p, resolution=0.1)


@pytest.fixture(scope="module")
def cross_validated():
    grid = room_map()
    predict = office.predictors(DEFAULT_HIDDEN, DEFAULT_LINK, 2, LBP_OPTIONS, THESIS_OPTIONS)
    folds = office.fold_sets(grid.known(), 4, seed=0, block=3)
    experiments = {("full", kind, name): (grid, folds[kind], p) for kind in ("random", "blocks")
                   for name, p in predict.items()}
    return grid, office.cross_validate_all(experiments, range(2))


def test_lbp_run_numbers_count_what_each_run_changed():
    before = room_map()
    runs = {"whole": {}, "near": {"region": near_known(before, 1)}}
    results = {name: infer(before, DEFAULT_HIDDEN, DEFAULT_LINK, **options) for name, options in runs.items()}
    numbers = office.lbp_run_numbers(before, runs, results)
    was_unknown = ~before.known()
    for name, r in results.items():
        p = r.beliefs.probability
        assert numbers[name]["unknown_cells_filled"] == np.count_nonzero(was_unknown & (p != UNKNOWN))
        assert numbers[name]["of_which_occupied"] == np.count_nonzero(was_unknown & (p > 0.5))
        assert numbers[name]["iterations"] == r.iterations and numbers[name]["converged"] == r.converged
    assert numbers["whole"]["cells_updated"] == before.probability.size
    assert numbers["near"]["cells_updated"] == runs["near"]["region"].sum()
    # the near-known region reaches one column into the unseen part: fewer unknown cells filled than on the whole grid
    assert 0 < numbers["near"]["unknown_cells_filled"] < numbers["whole"]["unknown_cells_filled"]
    header, rows = office.lbp_run_table(numbers)
    assert len(header) == len(rows[0]) == 8 and [r[0] for r in rows] == ["whole", "near"]


def test_fold_sets_deal_the_known_cells_randomly_and_in_blocks():
    known = room_map().known()
    folds = office.fold_sets(known, 4, seed=0, block=3)
    assert set(folds) == {"random", "blocks"}
    for f in folds.values():
        assert set(np.unique(f[known])) == {0, 1, 2, 3} and (f[~known] < 0).all()
    assert set(office.fold_sets(known, 4, seed=0)) == {"random"}


def test_table26_starts_with_the_thesis_and_scores_each_cross_validation(cross_validated):
    grid, cv = cross_validated
    header, rows, numbers = office.table26(cv, {"full": "room"}, {"random": "4 random", "blocks": "4 blocks"})
    assert header == office.TABLE26_HEADER and rows[0] == office.THESIS_TABLE26
    assert len(rows) == 1 + len(cv) and rows[1][:3] == ["room", "4 random", office.LBP]
    lbp = numbers[f"full / random / {office.LBP}"]
    assert lbp["folds_run"] == 2 and lbp["held_out"] == cv[("full", "random", office.LBP)].held_out.sum()
    free = numbers[f"full / random / {office.ALL_FREE}"]
    assert free["recall"] == 0.0  # every cell predicted free: no wall found


def test_leave_one_out_check_samples_half_walls_half_free(cross_validated):
    grid, cv = cross_validated
    run = cv[("full", "random", office.LBP)]
    predictor = office.predictors(DEFAULT_HIDDEN, DEFAULT_LINK, 2, LBP_OPTIONS, THESIS_OPTIONS)[office.LBP]
    check = office.leave_one_out_check(grid, run, predictor, n_cells=6, window=5, seed=0)
    assert check["cells"] == 6 and check["window_cells"] == 5
    assert 0.0 <= check["same_label_as_folds"] <= 1.0 and check["mean_abs_difference"] >= 0.0
    assert check == {**office.leave_one_out_check(grid, run, predictor, 6, 5, 0), "seconds": check["seconds"]}


def test_versus_finished_scores_only_the_map_and_lbp_on_seen_cells():
    finished = room_map(unknown_cols=1)
    partial = room_map()
    seen = finished.known() & partial.known()
    predictions = {"as built": partial, "neighbour mean": office.neighbour_mean(partial, 1),
                   "all free": partial.with_probability(np.zeros(partial.shape))}
    header, rows, numbers = office.versus_finished(predictions, finished, {"seen": seen, "gaps": ~seen})
    assert [r[:2] for r in rows] == [["seen", "as built"], ["gaps", "as built"], ["gaps", "neighbour mean"],
                                     ["gaps", "all free"]]
    assert numbers["seen / as built"]["accuracy"] == 1.0  # the partial map agrees with the finished one where seen


def test_same_cells_scores_every_method_on_common_cells(cross_validated):
    grid, cv = cross_validated
    gaps = grid.known()
    gap_predictions = {"lbp": cv[("full", "random", office.LBP)].predicted,
                       "free": grid.with_probability(np.zeros(grid.shape))}
    out = office.same_cells(cv, grid, gap_predictions, gaps, "lbp", seed=0)
    assert set(out) == {"cross_validation", "gaps"} and set(out["cross_validation"]) == {"random", "blocks"}
    random = out["cross_validation"]["random"]
    assert set(random["methods"]) == {office.LBP, office.LBP_THESIS, office.NEIGHBOURS, office.ALL_FREE}
    rows = office.same_cells_rows(out["cross_validation"], {"random": "r", "blocks": "b"})
    assert len(rows) == 8 and rows[0][0] == "r" and rows[0][-1] == ""  # LBP is the reference: no difference to it
    assert rows[1][-1].startswith(("+", "-"))


def test_the_figures_have_their_panels(cross_validated):
    grid, cv = cross_validated
    robot = np.array([1.0, 0.8, 0.0])
    fig = office.map_figure(grid, "map", path=np.array([[0.5, 0.5, 0.0], [1.0, 0.8, 0.0]]), robot=robot, radius=0.5)
    assert fig.axes[0].get_title() == "map" and len(fig.axes[0].lines) == 2  # path and robot
    plt.close(fig)
    results = {f"run {k}": infer(grid, max_iter=k + 1) for k in range(5)}
    fig = office.lbp_figure(grid, results, robot, 0.5, zoom=0.4)
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert len(panels) == 6 and panels[0].get_xlim() == pytest.approx((0.6, 1.4))
    plt.close(fig)
    fig = office.roc_figure(cv, {"random": "4 random", "blocks": "4 blocks"})
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["Fig. 44: held-out cells, 4 random", "Fig. 44: held-out cells, 4 blocks"]
    plt.close(fig)


def test_online_figure_and_table_from_a_short_stream():
    import importlib.util

    # the box-room scans of office_online's tests (tests/study/experiments is no package: load the file)
    spec = importlib.util.spec_from_file_location("office_online_tests", Path(__file__).with_name(
        "test_office_online.py"))
    scans_module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scans_module)
    stream = scans_module.room_scans(n=6)
    mapper = OnlineMapper.for_scans(stream, 0.1, preset="thesis")
    run, numbers = office.map_online_timed(mapper, stream, [3, 6], log_seconds=2.5)
    assert sorted(run.snapshots) == [3, 6] and numbers["seconds_total"] > 0
    near = OnlineMapper.for_scans(stream, 0.1, preset="thesis", margin=2)
    run_near = map_online(near, stream, [3, 6])
    fig = office.online_figure(stream, [3, 6], run.snapshots, run_near.snapshots, mapper.radius, mapper.max_iter, 2)
    assert len([ax for ax in fig.axes if ax.get_title()]) == 6
    plt.close(fig)
    hidden = np.array([[2.0, 1.0], [1.0, 2.0]])
    comparisons, offline = office.online_against_offline(stream, 0.1, hidden, near, 1e-6)
    assert set(comparisons) == {"versus_offline", "near_versus_offline", "default_table_offline"}
    assert offline.shape == build_grid(stream, 0.1).shape
    online = {"scans": 6, **numbers, "near_observations": numbers, **comparisons}
    header, rows = office.online_table(online, mapper.max_iter, 2, hidden, 2.5)
    assert len(rows) == 7 and all(len(r) == len(header) for r in rows)
    assert rows[3][0] == "online + finish(), hidden [[2.0, 1.0], [1.0, 2.0]]"
    assert rows[3][-1] == comparisons["versus_offline"]["max_abs_belief_difference"]


def test_paper_numbers_take_each_number_from_its_place():
    table = {f"full / {kind} / {name}": {"precision": k} for k, (kind, name) in enumerate(
        [("random", office.LBP), ("random", office.LBP_THESIS), ("random", office.NEIGHBOURS),
         ("random", office.ALL_FREE), ("blocks", office.LBP), ("blocks", office.NEIGHBOURS)])}
    run = {"unknown_cells_filled": 7, "of_which_occupied": 3, "iterations": 12, "converged": True}
    numbers = {"full_map": {"occupied_fraction_of_known": 0.05}, "table26": table,
               "fig43": {"1: bounded disc (thesis sec. 3.4.4)": run,
                         "2: unbounded (whole grid)": dict(run, iterations=500, converged=False)},
               "partial_vs_finished": {"seen in the partial map / partial map as built": {"recall": 0.7},
                                       "seen in the partial map / partial map after LBP (near known)": {"recall": 0.6}}}
    online = {"observed_occupied_fraction_still_occupied": 0.3, "never_observed_cells_given_a_state": 99,
              "real_time_factor": 1000.0, "ms_per_scan_median": 2.0, "scans": 910,
              "default_table_offline": {"converged": False, "iterations": 250}}
    paper = office.paper_numbers(numbers, online)
    assert paper["lbp2_random"] == {"precision": 1} and paper["neighbour_blocks"] == {"precision": 5}
    assert (paper["partial_seen_recall_before"], paper["partial_seen_recall_after"]) == (0.7, 0.6)
    assert (paper["bounded_unknown_made_occupied"], paper["unbounded_iterations"]) == (3, 500)
    assert (paper["online_scans"], paper["default_offline_iterations"]) == (910, 250)
