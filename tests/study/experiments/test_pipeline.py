"""The experiment pipeline of sec. 4.1.2: scanning scenes, scoring LBP, learning on train and testing."""
import numpy as np
import pytest

from crfstudy.experiments import pipeline as experiment; from crfmap.assess import metrics; from crfmap.world import scenes
from crfmap.world.reachability import reachable
from crfmap.world.scene import Scene
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.assess.learning import learn_thesis, lbp_mse
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.sim.laser import Laser


def test_truth_bounds_rebuilds_the_same_cells():
    truth = OccupancyGrid(np.zeros((4, 6)), 0.25, origin=(-1.0, 2.0, 0.0))
    xmin, ymin, xmax, ymax = experiment.truth_bounds(truth)
    assert (xmin, ymin) == (-1.0, 2.0)
    assert round((xmax - xmin) / 0.25) == 6 and round((ymax - ymin) / 0.25) == 4
    with pytest.raises(InputError, match="truth"):
        experiment.truth_bounds(OccupancyGrid(np.zeros((2, 2)), 1.0, origin=(0.0, 0.0, 0.3)))


def test_exploring_with_perfect_sensors_sees_every_reachable_cell_correctly():
    scene = scenes.enclosed_boxes("train", size=20)
    observed, recording = experiment.scan_scene(scene, Laser.with_fov(360, 90), drive="explore")
    assert observed.shape == scene.truth.shape and observed.origin == scene.truth.origin
    reach = reachable(scene.truth, scene.start)
    known = observed.probability != 0.5
    assert known[reach].all()
    # every known cell is on the right side of 0.5
    assert np.array_equal(observed.probability[known] > 0.5, scene.occupied[known])
    # occupied cells whose four neighbours are occupied too (box interiors) are never seen
    occ = scene.occupied
    inner = np.zeros_like(occ)
    inner[1:-1, 1:-1] = occ[1:-1, 1:-1] & occ[:-2, 1:-1] & occ[2:, 1:-1] & occ[1:-1, :-2] & occ[1:-1, 2:]
    assert inner.any() and not known[inner].any()
    assert recording.meta["mode"] == "explore"


def test_looking_from_one_place_leaves_the_shadow_of_a_wall_unknown():
    cells = np.zeros((21, 21))
    cells[:, [0, -1]] = cells[[0, -1], :] = 1
    cells[8:13, 6] = 1  # a short wall east of the robot
    scene = Scene("wall", OccupancyGrid(cells, 0.1), start=(0.35, 1.05, 0.0), default_mode="look")
    observed, _ = experiment.scan_scene(scene, Laser.with_fov(360, 720))
    p = observed.probability
    assert p[10, 6] > 0.5  # the wall is seen
    assert (p[10, 8:19] == 0.5).all()  # the cells right behind it are not
    assert p[10, 2] < 0.5  # free cells in front are


def test_evaluate_pipeline_without_coupling_returns_the_observation():
    truth = scenes.occluded_walls("train", size=20).truth
    rng = np.random.default_rng(0)
    observed = OccupancyGrid(rng.choice([0.25, 0.5, 0.75], size=truth.shape))
    flat = np.ones((2, 2))  # a hidden table of ones: neighbours say nothing
    r = experiment.evaluate_pipeline(observed, truth, flat, DEFAULT_LINK)
    assert np.allclose(r.beliefs.probability, observed.probability, atol=1e-5)
    before = experiment.score(observed, truth)
    assert r.metrics.mse == pytest.approx(before.metrics.mse, abs=1e-6)
    assert before.lbp is None and before.as_dict()["converged"] is None
    assert r.as_dict()["converged"] is True


def test_evaluate_pipeline_scores_what_lbp_returns():
    truth = scenes.occluded_walls("test", size=20).truth
    observed = OccupancyGrid(np.where(truth.probability > 0.5, 0.75, 0.25))
    observed.probability[5:9, 5:9] = 0.5
    r = experiment.evaluate_pipeline(observed, truth, lbp_options={"schedule": "thesis", "max_iter": 2})
    expected = metrics.evaluate(r.beliefs, truth)
    assert r.metrics.mse == pytest.approx(expected.mse) and r.metrics.recall == pytest.approx(expected.recall)
    assert r.lbp.schedule == "thesis" and r.lbp.iterations <= 2
    fpr, tpr, area = r.roc(truth)
    assert fpr[0] == 0 and tpr[-1] == 1 and area == pytest.approx(metrics.auc(r.beliefs, truth))


def test_mismatched_grids_are_refused_with_the_input_named():
    a = OccupancyGrid(np.full((3, 3), 0.5))
    b = OccupancyGrid(np.zeros((3, 4)))
    with pytest.raises(InputError, match="truth"):
        experiment.evaluate_pipeline(a, b)
    with pytest.raises(InputError, match="observed"):
        experiment.score(np.zeros((3, 3)), b)


def test_search_finds_the_best_point_of_its_grid_and_the_learner_never_ends_worse():
    scene = scenes.occluded_walls("train", size=20)
    observed, _ = experiment.scan_scene(scene, Laser.with_fov(360, 90))
    strengths, biases = (1.5, 3.0, 10.0), (0.8, 1.0, 1.5)
    hidden, link, table = experiment.search_tables(observed, scene.truth, strengths, biases)
    i, j = np.unravel_index(np.argmin(table), table.shape)
    assert hidden[0, 0] == strengths[i] and link[1, 1] == biases[j]
    assert table[i, j] == pytest.approx(lbp_mse(observed, scene.truth, hidden, link, experiment.TO_CONVERGENCE))
    result = experiment.learn_search_gradient(observed, scene.truth, strengths=strengths, biases=biases, steps=3,
                                              progress=False)
    assert result.mse_after <= table.min() + 1e-12
    assert result.mse_before == pytest.approx(lbp_mse(observed, scene.truth, DEFAULT_HIDDEN, DEFAULT_LINK))
    assert result.mse_after == pytest.approx(lbp_mse(observed, scene.truth, result.hidden, result.link), abs=1e-9)
    assert result.hidden.max() == pytest.approx(10.0) and result.link.max() == pytest.approx(1.0)


def test_train_and_test_applies_the_tables_learned_on_train_to_both_grids():
    grids = {}
    for variant in ("train", "test"):
        scene = scenes.enclosed_boxes(variant, hollow=True, size=20)
        grids[variant] = (experiment.scan_scene(scene, Laser.with_fov(360, 90))[0], scene.truth)
    learners = {"thesis": lambda o, t, opts: learn_thesis(o, t, lbp_options=opts, max_rounds=2, progress=False)}
    settings = {"converged": experiment.TO_CONVERGENCE, "two": experiment.THESIS_TWO_ITERATIONS}
    run = experiment.train_and_test(grids["train"], grids["test"], learners, settings, progress=False)
    assert set(run.learned) == {("converged", "thesis"), ("two", "thesis")}
    assert len(run.results) == 2 * 2 * 2
    for setting, options in settings.items():
        hidden, link = run.tables(setting, "thesis")
        assert np.array_equal(hidden, run.learned[(setting, "thesis")].hidden)
        for env in ("train", "test"):
            direct = experiment.evaluate_pipeline(*grids[env], hidden, link, options)
            assert run.results[(setting, env, "thesis")].metrics.mse == pytest.approx(direct.metrics.mse)
            default = run.results[(setting, env, "default")]
            assert np.array_equal(default.hidden, DEFAULT_HIDDEN) and np.array_equal(default.link, DEFAULT_LINK)
    # the learner only keeps steps that lower the train MSE
    learned = run.learned[("converged", "thesis")]
    assert run.results[("converged", "train", "thesis")].metrics.mse == pytest.approx(learned.mse_after)
    assert learned.mse_after <= run.results[("converged", "train", "default")].metrics.mse + 1e-12
    assert run.before["test"].metrics.mse == pytest.approx(metrics.mse(*grids["test"]))
    with pytest.raises(InputError, match="learners"):
        experiment.train_and_test(grids["train"], grids["test"], {})
