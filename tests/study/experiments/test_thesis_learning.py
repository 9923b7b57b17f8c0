"""The learning experiments of notebooks 05 and 06: rows in the thesis's order, the right numbers in them, the
figures with their axes, why the occlusion result does not reproduce."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.assess.learning import LearningResult  # noqa: E402
from crfmap.crf.inference.lbp import infer  # noqa: E402
from crfstudy.experiments import thesis_learning as tl  # noqa: E402
from crfstudy.experiments.pipeline import TO_CONVERGENCE, metric_row, scan_scene, train_and_test  # noqa: E402
from crfmap.sim.laser import Laser  # noqa: E402
from crfmap.errors import InputError  # noqa: E402
from crfmap.grid import OccupancyGrid  # noqa: E402
from crfmap.world import scenes  # noqa: E402

WEAK = np.array([[2.0, 1.0], [1.0, 2.0]])
BIASED_LINK = np.array([[1.0, 0.0], [0.0, 1.25]])


def fixed(hidden, link):
    """A learner that 'learns' given tables at once (the tables code is what is tested, not learning)."""
    return lambda o, t, opts: LearningResult(np.asarray(hidden, float), np.asarray(link, float), 0.3, 0.2,
                                             trace=[{}, {}, {}], method="fixed")


@pytest.fixture(scope="module")
def run():
    laser = Laser.with_fov(360, 90, range_max=3.0)
    pairs = []
    for variant in ("train", "test"):
        scene = scenes.occluded_walls(variant, size=20)
        observed, recording = scan_scene(scene, laser, drive="look")
        pairs.append((observed, scene.truth, recording))
    learners = {"thesis": fixed(WEAK, np.eye(2)), "search+gradient": fixed(WEAK, BIASED_LINK)}
    settings = {"converged": TO_CONVERGENCE, "two": {"schedule": "thesis", "max_iter": 2}}
    result = train_and_test(pairs[0][:2], pairs[1][:2], learners, settings, progress=False)
    result.recordings = [p[2] for p in pairs]
    return result


THESIS = {"before": [0.1, None, None, None], "default": [0.06, 1, 0.5, 0.97], "learned": [0.05, 1, 0.35, 0.95]}


def test_metrics_table_sets_each_run_beside_the_thesis_row_it_reproduces(run):
    rows = tl.metrics_table(run, "train", THESIS)
    assert len(rows) == 1 + 2 * 3 and all(len(r) == len(tl.METRICS_HEADER) for r in rows)
    assert rows[0] == ["before LBP", "", *metric_row(run.before["train"]), "", *THESIS["before"]]
    by_label = {(r[0], r[1]): r for r in rows[1:]}
    default = by_label[("after LBP, without learning", "two")]
    assert default[2:6] == metric_row(run.results[("two", "train", "default")]) and default[6] == 2
    assert default[7:] == THESIS["default"]
    assert by_label[("after LBP, with learning (thesis's learner)", "converged")][7:] == THESIS["learned"]
    assert by_label[("after LBP, with learning (search + gradient, extra)", "converged")][7:] == [None] * 4
    extra = tl.metrics_table(run, "test", THESIS, extra=[("corner", "lbp", run.results[("two", "test", "default")])])
    assert extra[-1][:2] == ["corner", "lbp"] and extra[-1][7:] == THESIS["default"]


def test_potentials_rows_list_default_thesis_and_ours_with_the_tables_numbers(run):
    rows = tl.potentials_rows(run, [10.3, 1.3, 0.9, 10.2], [1.1, 0, 0, 1.3], tables=(21, 22, 23, 24), tag=" (x)")
    assert rows[0] == ["hidden (Table 21)", "default", 10.0, 1.0, 1.0, 10.0]
    assert rows[1] == ["hidden (Table 22)", "thesis, learned", 10.3, 1.3, 0.9, 10.2]
    assert rows[2] == ["hidden (Table 22)", "ours, thesis learner, converged (x)", 2.0, 1.0, 1.0, 2.0]
    links = [r for r in rows if r[0].startswith("link")]
    assert links[0] == ["link (Table 23)", "default", 1.0, 0.0, 0.0, 1.0]
    assert links[-1] == ["link (Table 24)", "ours, search+gradient learner, two (x)", 1.0, 0.0, 0.0, 1.25]
    assert len(rows) == 2 * (2 + 4)


def test_summaries_hold_every_run_of_the_room_and_the_learned_tables(run):
    summary = tl.results_summary(run, "test")
    assert list(summary) == ["before"] + [f"{n} | {s}" for s in ("converged", "two")
                                          for n in ("default", "thesis", "search+gradient")]
    assert summary["default | converged"] == run.results[("converged", "test", "default")].as_dict()
    learned = tl.learned_summary(run)
    assert learned["search+gradient | two"]["trace_length"] == 3
    np.testing.assert_array_equal(learned["search+gradient | two"]["link"], BIASED_LINK)


def test_same_cells_predictions_add_the_oriented_pairing_of_each_learner(run):
    observed, truth = run.observed["test"], run.truth["test"]
    predictions = tl.same_cells_predictions(run, "test", run.recordings[1].scans, truth, observed)
    assert "raw arctan grid (no LBP)" in predictions and "3x3 neighbour mean" in predictions
    key = "LBP converged, with learning (search + gradient, extra), oriented pairing"
    oriented = infer(observed, WEAK, BIASED_LINK, pairing="oriented", threads=1).beliefs.probability
    np.testing.assert_array_equal(predictions[key].probability, oriented)
    assert predictions["LBP two, without learning"] is run.results[("two", "test", "default")].beliefs
    table = tl.same_cells_table({"m": {"mse": 0.1, "precision_seen": 1.0, "recall_seen": 0.5, "accuracy_seen": 0.9,
                                       "accuracy_unseen": 0.8, "coverage_unseen": 0.7}}, caption="c")
    assert table == {"header": tl.SAME_CELLS_HEADER, "rows": [["m", 0.1, 1.0, 0.5, 0.9, 0.8, 0.7]], "caption": "c"}


def test_make_learners_pass_the_settings_to_each_learner(monkeypatch):
    seen = {}
    monkeypatch.setattr(tl, "learn_thesis", lambda o, t, **kw: seen.setdefault("thesis", kw))
    monkeypatch.setattr(tl, "learn_gradient", lambda o, t, **kw: seen.setdefault("gradient", kw))
    monkeypatch.setattr(tl, "learn_search_gradient", lambda o, t, **kw: seen.setdefault("search", kw))
    for learner in tl.make_learners(7, 9).values():
        learner(None, None, {"max_iter": 2})
    assert seen["thesis"] == {"alpha": 0.01, "max_rounds": 7, "lbp_options": {"max_iter": 2}, "progress": False}
    assert seen["gradient"]["steps"] == seen["search"]["steps"] == 9


# ---- scene panels
def test_draw_marks_the_start_only_with_a_scene():
    scene = scenes.occluded_walls("train", size=20)
    fig, (a, b) = plt.subplots(1, 2)
    tl.draw(a, scene.truth, "with", scene)
    tl.draw(b, scene.truth, "without")
    ((x,), (y,)) = a.lines[0].get_data()
    assert (x, y) == tuple(scene.start[:2]) and not b.lines and a.get_title() == "with"
    plt.close(fig)


def test_landscape_labels_each_cell_and_refuses_a_wrong_shape():
    landscape = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    fig = tl.landscape_figure(landscape, (1.0, 10.0), (0.5, 1.0, 2.0), "title")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.texts] == ["0.100", "0.200", "0.300", "0.400", "0.500", "0.600"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1.0", "10.0"]
    plt.close(fig)
    with pytest.raises(InputError, match="landscape"):
        tl.landscape_figure(landscape.T, (1.0, 10.0), (0.5, 1.0, 2.0), "title")


# ---- why the occlusion result does not reproduce
TRUTH = OccupancyGrid(np.array([[1.0, 0.0, 0.0, 1.0]]))
OBSERVED = OccupancyGrid(np.array([[0.75, 0.5, 0.2, 0.5]]))  # saw the first wall and one free cell


def room(side=8):
    """A wall along row 3 (one cell thick), seen once (P = 0.75) on its left half; free cells seen at 0.2."""
    truth = np.zeros((side, side))
    truth[3, :] = 1.0
    observed = np.full((side, side), 0.5)
    observed[:, : side // 2] = 0.2
    observed[3, : side // 2] = 0.75
    return OccupancyGrid(observed), OccupancyGrid(truth)


def test_why_row_scores_all_cells_for_the_mse_and_the_seen_cells_for_the_rest():
    seen = OBSERVED.probability != 0.5
    row = tl.why_row(OBSERVED, TRUTH, seen)
    assert row["mse"] == pytest.approx((0.25 ** 2 + 0.5 ** 2 + 0.2 ** 2 + 0.5 ** 2) / 4)
    assert row["precision_seen"] == row["recall_seen"] == row["walls_kept"] == 1.0
    erased = OccupancyGrid(np.array([[0.4, 0.0, 0.0, 1.0]]))  # the seen wall below 0.5; the unseen one decided
    row = tl.why_row(erased, TRUTH, seen)
    assert row["walls_kept"] == 0.0 and row["recall_seen"] == 0.0  # the unseen wall does not count
    assert row["mse"] == pytest.approx(0.6 ** 2 / 4)


def test_sensing_row_counts_unknown_cells_and_seen_wall_evidence():
    row = tl.sensing_row(OBSERVED, TRUTH)
    assert row["unknown_fraction"] == 0.5
    assert row["median_p_on_seen_walls"] == 0.75
    assert row["mse_before"] == pytest.approx(tl.why_row(OBSERVED, TRUTH, OBSERVED.probability != 0.5)["mse"])
    assert 0.0 <= row["walls_kept"] <= 1.0


def test_without_coupling_lbp_keeps_the_evidence_and_the_default_coupling_erases_the_seen_wall():
    observed, truth = room()
    result = tl.why_study(observed, truth, iteration_counts=(1, 2), couplings=(1.0, 10.0))
    assert result["seen_wall_cells"] == 4 and result["seen_walls_at_p075_fraction"] == 1.0
    assert result["seen_walls_below_0.5"] == 0
    # [[1, 1], [1, 1]] sends flat messages: the beliefs are the observations
    assert result["coupling"]["a_1"]["mse"] == pytest.approx(result["before"]["mse"])
    assert result["coupling"]["a_1"]["walls_kept"] == 1.0 and result["coupling"]["a_1"]["ising_coupling"] == 0.0
    # ln(10)/2 is deep in the ordered phase: a one-cell line at P = 0.75 yields to the free cells around it
    assert result["coupling"]["a_10"]["walls_kept"] == 0.0
    assert result["coupling"]["a_10"]["ising_coupling"] == pytest.approx(np.log(10) / 2)
    assert list(result["schedules"]) == ["thesis_lower_left", "thesis_lower_right", "thesis_upper_left",
                                         "thesis_upper_right", "sweep_lower_left", "flooding_lower_left",
                                         "checkerboard_lower_left"]
    series = result["iterations"]["checkerboard_lower_left"]
    assert [s["iterations"] for s in series] == [1, 2] and result["sensing"] == {}


def test_tables_list_every_study_and_the_thesis_last():
    observed, truth = room()
    result = tl.why_study(observed, truth, {"same scan": observed}, iteration_counts=(1,), couplings=(2.0,))
    rows = tl.schedule_rows(result)
    assert rows[0][:2] == ["before LBP", ""] and rows[0][2] == result["before"]["mse"]
    assert [r[1] for r in rows[1:8]] == ["thesis lower-left", "thesis lower-right", "thesis upper-left",
                                          "thesis upper-right", "sweep lower-left", "flooding lower-left",
                                          "checkerboard lower-left"]
    assert rows[8][1] == "a = 2" and rows[-1] == ["thesis Table 15 (2 iterations, its corner)", "", 0.0623, 1, 0.5]
    (sensing,) = tl.sensing_rows(result)
    assert sensing[0] == "same scan" and sensing[1] == pytest.approx(0.5)


def test_a_scan_that_saw_no_wall_or_does_not_fit_the_truth_is_refused():
    observed, truth = room()
    blind = OccupancyGrid(np.where(truth.probability > 0.5, 0.5, observed.probability))
    with pytest.raises(InputError, match="no wall"):
        tl.why_study(blind, truth)
    with pytest.raises(InputError, match="observed"):
        tl.why_study(OccupancyGrid(np.full((3, 3), 0.5)), truth)


# ---- the notebooks' figures, tables and summaries
def test_panels_figure_draws_each_grid_in_order_and_refuses_a_wrong_count():
    scene = scenes.occluded_walls("train", size=20)
    fig = tl.panels_figure([(scene.truth, "a", scene), (scene.truth, "b"), (scene.truth, "c"), (scene.truth, "d")],
                           (2, 2), (6, 6))
    assert [ax.get_title() for ax in fig.axes if ax.get_title()] == ["a", "b", "c", "d"]
    assert len(fig.axes[0].lines) == 1 and not fig.axes[1].lines  # only a panel with a scene marks the start
    plt.close(fig)
    single = tl.panels_figure([(scene.truth, "only")])
    assert single.axes[0].get_title() == "only"
    plt.close(single)
    with pytest.raises(InputError, match="panels"):
        tl.panels_figure([(scene.truth, "a")], (1, 2))


def test_roc_figure_has_one_curve_per_grid(run):
    fig = tl.roc_figure(run, "train", "ROC")
    ax = fig.axes[0]
    labels = [line.get_label() for line in ax.lines if not line.get_label().startswith("_")]
    assert ax.get_title() == "ROC" and len(labels) == 1 + 2 + 2  # before, two settings' defaults, two learners
    assert labels[0].startswith("before LBP")
    plt.close(fig)


def test_reading_rows_score_each_reading_before_and_after_lbp(run):
    grid, truth, recording = run.observed["train"], run.truth["train"], run.recordings[0]
    rows, numbers = tl.reading_rows({"look (used)": (grid, recording)}, truth, thesis_mse_before=0.112)
    after = tl.evaluate_pipeline(grid, truth).metrics.mse
    assert rows == [["look (used)", 1, float(np.mean(grid.probability == 0.5)), run.before["train"].metrics.mse,
                     after, 0.112]]
    assert numbers == {"look": {"scans": 1, "unknown_fraction": rows[0][2], "mse_before": rows[0][3],
                                "mse_after_default_lbp": after}}


def test_thesis_pass_from_a_corner_is_two_iterations_of_the_thesis_schedule(run):
    grid, truth = run.observed["train"], run.truth["train"]
    r = tl.thesis_pass_from(grid, truth, "upper-left")
    direct = infer(grid, tl.DEFAULT_HIDDEN, tl.DEFAULT_LINK, schedule=tl.Thesis("upper-left"), max_iter=2)
    assert r.lbp.iterations == 2
    np.testing.assert_array_equal(r.beliefs.probability, direct.beliefs.probability)
    summary = tl.results_summary(run, "train", extra={"corner": r})
    assert list(summary)[-1] == "corner" and summary["corner"] == r.as_dict()


def test_beside_printed_puts_the_printed_text_by_the_kind_of_row(run):
    extra = [("after LBP, without learning", "corner (extra)", run.results[("two", "test", "default")])]
    rows = tl.metrics_table(run, "test", THESIS, extra=extra)
    printed = {"before": "B", "default": "D", "learned": "L"}
    out = tl.beside_printed(rows, printed)
    assert [r[7] for r in out] == ["B", "D", "L", "n/a", "D", "L", "n/a", "D"]
    assert all(len(r) == 8 and r[:7] == row[:7] for r, row in zip(out, rows))


def test_headline_and_the_sec_4_2_check_read_the_run(run):
    line = tl.headline(run, "test")
    assert line.startswith("test: MSE before ") and f"{run.before['test'].metrics.mse:.4f}" in line
    best = min(("thesis", "search+gradient"), key=lambda n: run.results[("converged", "test", n)].metrics.mse)
    assert f"learned ({best})" in line
    kept = tl.lower_mse_without_lower_recall(run)
    for setting, env, name in run.results:
        r, before = run.results[(setting, env, name)].metrics, run.before[env].metrics
        expected = r.mse < before.mse and not (r.recall < before.recall and r.accuracy < before.accuracy)
        assert ((setting, env, name) in kept) == expected


def test_median_beliefs_split_walls_from_free_cells():
    truth = OccupancyGrid(np.array([[1.0, 1.0, 0.0, 0.0]]))
    result = tl.score(OccupancyGrid(np.array([[0.9, 0.7, 0.1, 0.3]])), truth)
    assert tl.median_beliefs(result, truth) == (pytest.approx(0.8), pytest.approx(0.2))


def test_same_cells_scores_score_every_prediction_on_the_same_cells(run):
    observed, truth = run.observed["test"], run.truth["test"]
    scores = tl.same_cells_scores(run, "test", run.recordings[1].scans, truth, observed)
    predictions = tl.same_cells_predictions(run, "test", run.recordings[1].scans, truth, observed)
    assert list(scores) == list(predictions)
    assert scores["raw arctan grid (no LBP)"]["mse"] == pytest.approx(run.before["test"].metrics.mse)


def test_boxes_tables_compare_with_the_grid_before_lbp_and_across_kinds(run):
    rows, worse = tl.hollow_rows(run)
    assert len(rows) == 2 * (1 + 2 * 3) and rows[0][:3] == ["train", "before LBP", ""]
    for (env, setting, name), (mse_worse, _) in worse.items():
        assert mse_worse == (run.results[(setting, env, name)].metrics.mse > run.before[env].metrics.mse)
    boxes = {kind: {"test": (type("S", (), {"truth": run.truth["test"]})(), run.observed["test"], None)}
             for kind in ("filled", "hollow")}
    rows, cross = tl.cross_rows({"filled": run, "hollow": run}, boxes)
    assert [r[:3] for r in rows[:2]] == [["filled TRAIN", "hollow TEST", "thesis"],
                                         ["filled TRAIN", "hollow TEST", "search+gradient"]]
    same = run.results[("converged", "test", "thesis")].metrics.mse
    assert rows[0][4] == rows[0][5] == pytest.approx(same)  # the same run on both sides: the same tables
    assert len(cross) == 4 and tl.run_summary(run)["learned"] == tl.learned_summary(run)


def test_mse_tradeoff_rows_list_only_a_lower_mse_with_something_worse(run):
    for label, env, setting, name, default_mse, mse, worse_on in tl.mse_tradeoff_rows({"x": run}):
        assert label == "x" and name != "default" and mse < default_mse and worse_on
        d, m = run.results[(setting, env, "default")].metrics, run.results[(setting, env, name)].metrics
        assert all(getattr(m, k) < getattr(d, k) for k in worse_on.split(", "))


def test_paired_over_rooms_pairs_each_learned_method_with_default_lbp():
    per_room = [{"LBP, converged": {"mse": m, "recall_seen": 0.5},
                 "LBP, learned on another room (receiver pairing)": {"mse": m - 0.01, "recall_seen": 0.6}}
                for m in (0.1, 0.2, 0.3)]
    run = {"per_room": per_room, "methods": list(per_room[0])}
    pairs = tl.paired_over_rooms(run, seed=0)
    (method,) = pairs
    assert method.startswith("LBP, learned") and pairs[method]["mse"]["wins"] == 3
    assert pairs[method]["recall_seen"]["mean_difference"] == pytest.approx(0.1)
    rows = tl.paired_rows(pairs)
    assert [r[:2] for r in rows] == [[method, "mse"], [method, "recall_seen"]] and rows[0][5] == "3 / 0 / 0"


def test_noisy_rooms_learn_on_another_room_and_score_every_room(monkeypatch):
    seen = {}
    monkeypatch.setattr(tl.rooms, "learn_on_room", lambda kind, seed, **kw: seen.setdefault("learn", (seed, kw))
                        and LearningResult(WEAK, BIASED_LINK, 0.3, 0.2, [], "fixed"))
    metrics = ("precision_seen", "recall_seen", "accuracy_seen", "accuracy_unseen", "coverage_unseen")
    per_room = [{"LBP, converged": {"mse": 0.1 * (s + 1), **dict.fromkeys(metrics, 0.5)}} for s in range(2)]
    monkeypatch.setattr(tl.rooms, "run_rooms", lambda kind, seeds, **kw: seen.setdefault("run", (list(seeds), kw))
                        and {"per_room": per_room, "methods": ["LBP, converged"], "unseen_fraction": [0.1, 0.2],
                             "settings": {}})
    out = tl.noisy_rooms("hollow", 2, 3, laser="L", drive="waypoints")
    assert seen["learn"] == (1000, {"steps": 3, "drive": "waypoints", "laser": "L"})
    assert seen["run"][0] == [0, 1] and seen["run"][1]["learned"] == (WEAK, BIASED_LINK)
    assert out["flat"]["lbp"]["mse"]["mean"] == pytest.approx(0.15) and out["flat"]["rooms"] == 2
    assert out["rows"][0][0] == "LBP, converged" and out["learned"].method == "fixed"


def test_scan_boxes_scan_both_rooms_of_a_kind(monkeypatch):
    calls = []
    monkeypatch.setattr(tl, "scan_scene", lambda scene, laser, drive, seed: calls.append((scene, drive)) or ("g", "r"))
    out = tl.scan_boxes(True, "L", 0)
    assert list(out) == ["train", "test"] and out["test"][1:] == ("g", "r")
    assert [d for _, d in calls] == ["explore", "explore"] and calls[0][0].name == out["train"][0].name


def test_corner_spread_ranges_over_the_thesis_corners():
    row = {"mse": 0.1, "recall_seen": 0.2, "walls_kept": 0.3}
    why = {"schedules": {"thesis_lower_left": row, "thesis_upper_left": dict(row, mse=0.3), "sweep_lower_left": {}}}
    corners, spread = tl.corner_spread(why)
    assert list(corners) == ["lower_left", "upper_left"]
    assert spread["mse"]["min"] == 0.1 and spread["mse"]["argmax"] == "upper_left"


def test_iterations_figure_has_both_panels(run):
    observed, truth = room()
    fig = tl.iterations_figure(tl.why_study(observed, truth, iteration_counts=(1, 2), couplings=(2.0,)))
    assert [ax.get_ylabel() for ax in fig.axes] == ["MSE (all cells)", "seen walls kept (P > 0.5)"]
    assert len(fig.axes[0].lines) == 3 + 1  # three schedules and the grid before LBP
    plt.close(fig)
