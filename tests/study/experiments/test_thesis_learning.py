"""The learning experiments' tables (notebooks 05, 06): rows in the thesis's order, the right numbers in them."""
import numpy as np
import pytest

from crfmap.assess.learning import LearningResult
from crfmap.crf.inference.lbp import infer
from crfstudy.experiments import thesis_learning as tl
from crfstudy.experiments.pipeline import TO_CONVERGENCE, metric_row, scan_scene, train_and_test
from crfmap.sim.laser import Laser
from crfmap.world import scenes

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
