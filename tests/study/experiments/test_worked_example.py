"""The worked example's helpers: the thesis's messages read from infer, its slip, and the figures' panels."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.assess import learn_gradient, learn_pseudolikelihood, learn_thesis, mse  # noqa: E402
from crfmap.crf import infer  # noqa: E402
from crfmap.errors import InputError  # noqa: E402
from crfmap.grid import OccupancyGrid  # noqa: E402
from crfstudy.experiments import worked_example  # noqa: E402

TABLE4 = np.array([[0.9, 0.1], [0.1, 0.9]])
OBSERVATION = {5: 0.6, 6: 0.8, 7: 0.3, 8: 0.4}
LAYOUT_A = {"C1": (0, 0), "C4": (0, 1), "C2": (1, 0), "C3": (1, 1)}


def one_pass():
    grid = worked_example.observed_grid(LAYOUT_A, OBSERVATION)
    return grid, infer(grid, TABLE4, np.eye(2), schedule="thesis", max_iter=1, tol=0.0)


def test_incoming_reads_the_thesis_messages_of_one_pass():
    grid, result = one_pass()
    assert grid[LAYOUT_A["C3"]] == 0.3  # observation 7 on cell C3
    assert worked_example.incoming(result.messages, LAYOUT_A, "C2", "C1") == pytest.approx(0.74)  # Table 6
    assert worked_example.incoming(result.messages, LAYOUT_A, "C4", "C1") == pytest.approx(0.42)
    with pytest.raises(InputError, match="not neighbours"):
        worked_example.incoming(result.messages, LAYOUT_A, "C1", "C3")


def test_the_slip_gives_the_thesis_b1_and_the_correct_value_its_b4():
    b1, d14, b4 = worked_example.slip_beliefs(0.74, 0.42, 0.6, 0.34, 0.4, TABLE4, slip=0.24)
    assert b1 == pytest.approx(0.18648 / (0.18648 + 0.05568))  # the thesis's own product, ~0.77
    assert 0.0 < d14 < 1.0 and b4 == pytest.approx(0.518, abs=1e-3)  # B4 with the slip, not the printed ~0.505
    b1_right, _, _ = worked_example.slip_beliefs(0.74, 0.42, 0.6, 0.34, 0.4, TABLE4, slip=0.26)
    assert b1_right == pytest.approx(0.756, abs=1e-3)


def test_exact_marginals_is_the_reference_one_pass_is_compared_with():
    grid, result = one_pass()
    exact = worked_example.exact_marginals(grid, TABLE4, np.eye(2))
    assert exact.shape == (2, 2) and np.all((exact > 0) & (exact < 1))
    assert not np.allclose(exact, result.beliefs.probability)


def test_table_text_is_one_line_of_three_significant_digits():
    assert worked_example.table_text(np.array([[10.04, 1.0], [1.234, 10.0]])) == "[[10, 1], [1.23, 10]]"


def test_the_figures_have_their_panels():
    grid, result = one_pass()
    fig = worked_example.worked_example_figure(grid, LAYOUT_A, result, [("C2", "C1", 0.74)])
    labels = [t.get_text() for t in fig.axes[1].texts]
    assert "0.740" in labels and fig.axes[0].get_title().startswith("Fig. 18")
    truth = OccupancyGrid(np.eye(4), resolution=1.0)
    observed = truth.with_probability(np.clip(np.eye(4) + 0.2, 0, 1))
    runs = [learn_thesis(observed, truth, TABLE4, np.eye(2), max_rounds=1, lbp_options={"threads": 1}),
            learn_gradient(observed, truth, TABLE4, np.eye(2), steps=1, lbp_options={"threads": 1}),
            learn_pseudolikelihood(observed, truth, TABLE4, np.eye(2), steps=2, lbp_options={"threads": 1})]
    fig = worked_example.learning_trace_figure(*runs)
    assert [ax.get_title() for ax in fig.axes] == ["thesis's learner (alpha = 0.01)", "gradient learner",
                                                   "pseudo-likelihood learner (no LBP inside)"]
    beliefs = {label: observed for label in ("Table 8", "a", "b", "c")}
    fig = worked_example.learning_grids_figure(truth, observed, beliefs)
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles[:2] == ["truth", f"noisy, MSE {mse(observed, truth):.4f}"] and len(titles) == 6
    assert titles[2].startswith("LBP, Table 8: ") and titles[5].startswith("LBP, c: ")
    plt.close("all")
