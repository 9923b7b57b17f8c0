"""Why the occlusion result does not reproduce: the rows, the four studies, their tables."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfstudy.experiments import occlusion_why as why
from crfmap.grid import OccupancyGrid

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
    row = why.why_row(OBSERVED, TRUTH, seen)
    assert row["mse"] == pytest.approx((0.25 ** 2 + 0.5 ** 2 + 0.2 ** 2 + 0.5 ** 2) / 4)
    assert row["precision_seen"] == row["recall_seen"] == row["walls_kept"] == 1.0
    erased = OccupancyGrid(np.array([[0.4, 0.0, 0.0, 1.0]]))  # the seen wall below 0.5; the unseen one decided
    row = why.why_row(erased, TRUTH, seen)
    assert row["walls_kept"] == 0.0 and row["recall_seen"] == 0.0  # the unseen wall does not count
    assert row["mse"] == pytest.approx(0.6 ** 2 / 4)


def test_sensing_row_counts_unknown_cells_and_seen_wall_evidence():
    row = why.sensing_row(OBSERVED, TRUTH)
    assert row["unknown_fraction"] == 0.5
    assert row["median_p_on_seen_walls"] == 0.75
    assert row["mse_before"] == pytest.approx(why.why_row(OBSERVED, TRUTH, OBSERVED.probability != 0.5)["mse"])
    assert 0.0 <= row["walls_kept"] <= 1.0


def test_without_coupling_lbp_keeps_the_evidence_and_the_default_coupling_erases_the_seen_wall():
    observed, truth = room()
    result = why.why_study(observed, truth, iteration_counts=(1, 2), couplings=(1.0, 10.0))
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
    result = why.why_study(observed, truth, {"same scan": observed}, iteration_counts=(1,), couplings=(2.0,))
    rows = why.schedule_rows(result)
    assert rows[0][:2] == ["before LBP", ""] and rows[0][2] == result["before"]["mse"]
    assert [r[1] for r in rows[1:8]] == ["thesis lower-left", "thesis lower-right", "thesis upper-left",
                                          "thesis upper-right", "sweep lower-left", "flooding lower-left",
                                          "checkerboard lower-left"]
    assert rows[8][1] == "a = 2" and rows[-1] == ["thesis Table 15 (2 iterations, its corner)", "", 0.0623, 1, 0.5]
    (sensing,) = why.sensing_rows(result)
    assert sensing[0] == "same scan" and sensing[1] == pytest.approx(0.5)


def test_a_scan_that_saw_no_wall_or_does_not_fit_the_truth_is_refused():
    observed, truth = room()
    blind = OccupancyGrid(np.where(truth.probability > 0.5, 0.5, observed.probability))
    with pytest.raises(InputError, match="no wall"):
        why.why_study(blind, truth)
    with pytest.raises(InputError, match="observed"):
        why.why_study(OccupancyGrid(np.full((3, 3), 0.5)), truth)
