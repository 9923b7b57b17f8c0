"""The denoising notebook's helpers: seed spreads, the paired learning gain, the toolbox model, the figures."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.assess import learn_thesis, mse  # noqa: E402
from crfmap.crf import DEFAULT_HIDDEN, DEFAULT_LINK, infer  # noqa: E402
from crfmap.errors import InputError  # noqa: E402
from crfmap.grid import OccupancyGrid  # noqa: E402
from crfmap.world import noisy_image  # noqa: E402
from crfstudy.experiments import denoising  # noqa: E402

QUICK_LBP = {"schedule": "checkerboard", "max_iter": 200, "tol": 1e-5}


def small_x(n=8):
    """An n x n X: the two diagonals occupied."""
    p = np.eye(n)
    return OccupancyGrid(np.maximum(p, p[::-1]), resolution=1.0)


def test_seed_mses_scores_each_further_scan_with_or_without_lbp():
    truth = small_x()
    noisy = denoising.seed_mses(truth, 0.4, [3, 4])
    assert noisy == [mse(noisy_image(truth, 0.4, seed=s), truth) for s in (3, 4)]
    after = denoising.seed_mses(truth, 0.4, [3, 4], DEFAULT_HIDDEN, DEFAULT_LINK, QUICK_LBP)
    assert after[0] == mse(infer(noisy_image(truth, 0.4, seed=3), **QUICK_LBP).beliefs, truth)
    assert denoising.mean_sd([1.0, 3.0]) == (2.0, 1.0)


def test_learner_name_is_plain_and_refuses_an_unknown_learner():
    assert denoising.learner_name("learn_gradient (converged)") == "gradient learner (converged)"
    with pytest.raises(InputError, match="learn_magic"):
        denoising.learner_name("learn_magic (converged)")


def test_paired_learning_compares_each_run_with_the_defaults_of_its_own_setting():
    truth = small_x()
    train = noisy_image(truth, 0.4, seed=1)
    two = {"schedule": "thesis", "max_iter": 2}
    run = learn_thesis(train, truth, max_rounds=1, lbp_options=QUICK_LBP)
    learned = {"a (converged)": (run, QUICK_LBP), "b (2 iterations)": (run, two)}
    paired, default_mses = denoising.paired_learning(truth, 0.4, [5, 6, 7], learned,
                                                     {"converged": QUICK_LBP, "2 iterations": two})
    assert paired["a (converged)"]["against"] == "default tables, converged"
    assert paired["b (2 iterations)"]["against"] == "default tables, 2 iterations"
    assert paired["b (2 iterations)"]["mean_b"] == pytest.approx(np.mean(default_mses["2 iterations"]))
    ours = denoising.seed_mses(truth, 0.4, [5, 6, 7], run.hidden, run.link, QUICK_LBP)
    assert paired["a (converged)"]["mean_difference"] == pytest.approx(np.mean(ours) - np.mean(default_mses["converged"]))
    (row_a, row_b) = denoising.paired_rows(paired)
    assert row_a[0] == "a (converged)" and row_a[5].count("/") == 2 and 0 <= row_a[6] <= 1


def test_implied_positive_share_recovers_the_share_a_confusion_was_made_with():
    tp, fp, fn, tn = 60, 5, 10, 25  # positives: 70 of 100 cells
    p, r, a = tp / (tp + fp), tp / (tp + fn), (tp + tn) / 100
    assert denoising.implied_positive_share(p, r, a) == pytest.approx(0.7)


def test_the_toolbox_comparison_agrees_with_the_reference_and_summarises_every_seed():
    truth = small_x()
    rows, example = denoising.toolbox_comparison(truth, 0.4, [0, 1], QUICK_LBP)
    assert [r["seed"] for r in rows] == [0, 1] and len(example) == 5
    assert max(r["max_abs_difference"] for r in rows) < 1e-8  # two codes, one fixed point
    columns = denoising.toolbox_columns(rows)
    summary = denoising.toolbox_summary(columns, 0)
    assert summary["seeds"] == 2 and summary["pixel_error_crfmap_mean"] == pytest.approx(columns["crfmap"].mean())
    table = denoising.toolbox_rows(columns, 0.4)
    assert len(table) == 5 and table[2][3] == "0 (itself)" and "sigma 0.4" in table[3][1]


def test_pixel_error_counts_the_cells_on_the_wrong_side_of_one_half():
    occupied = np.array([[True, False], [False, False]])
    assert denoising.pixel_error(np.array([[0.9, 0.6], [0.1, 0.5]]), occupied) == 0.25


def test_the_baselines_keep_the_grid_shape():
    grid = noisy_image(small_x(), 0.4, seed=0)
    makers = denoising.baseline_makers()
    assert "3x3 neighbour mean" in makers
    for make in makers.values():
        assert make(grid).probability.shape == grid.probability.shape


def test_learner_tail_counts_the_last_tenth():
    trace = [{"mse": 1.0 - 0.01 * k, "accepted": k % 2 == 0} for k in range(20)]  # 18 and 19 in the tail
    tail = denoising.learner_tail(trace)
    assert tail["lbp_runs"] == 19 and tail["accepted_in_tail"] == 1
    assert tail["mse_fall_in_tail"] == pytest.approx(0.84 - 0.81)  # best kept before the tail: step 16


def test_the_figures_have_their_panels():
    truth = small_x()
    test, train = noisy_image(truth, 0.4, seed=0), noisy_image(truth, 0.4, seed=1)
    plain = infer(test, **QUICK_LBP)
    assert denoising.truth_figure(truth).axes[0].get_title().startswith("Fig. 20")
    assert denoising.noisy_figure(test, train, truth, 0, 1).axes[1].get_title().startswith("training scan (seed 1)")
    assert denoising.lbp_figure(plain, plain, truth).axes[1].get_title().startswith("thesis schedule")
    fig = denoising.learned_figure({"learn_thesis (converged)": plain, "learn_gradient (converged)": plain}, truth)
    assert fig.axes[1].get_title().startswith("gradient learner (converged)")
    fig = denoising.roc_figure({"a": ([0, 1], [0, 1], 0.5)})
    assert fig.axes[1].get_xlim() == (0, 0.2)
    _, example = denoising.toolbox_comparison(truth, 0.4, [0], QUICK_LBP)
    fig = denoising.toolbox_figure(truth, example, 0)
    titles = [ax.get_title() for ax in fig.axes]
    assert any(t.startswith("log10 |crfmap - reference|") for t in titles)
    assert any(t.startswith("Fig. 21 analogue") for t in titles)
    plt.close("all")
