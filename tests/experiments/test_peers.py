"""Notebook 10's peers report: every row of the table is scored and calibrated (no NaN ECE)."""
import numpy as np
import pytest

from crfmap.assess.baselines import all_baselines
from crfmap.assess.calibration import expected_calibration_error
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.model.presets import DEFAULT_PRESET, get_preset
from crfmap.experiments import peers as peer_report


def _split(seed=0, shape=(24, 24)):
    rng = np.random.default_rng(seed)
    walls = np.zeros(shape, bool)
    walls[:, 8] = walls[12, :] = True
    first_hits = np.where(walls, rng.integers(0, 4, shape), rng.integers(0, 2, shape) * (rng.random(shape) < 0.1))
    first_passes = np.where(walls, rng.integers(0, 2, shape), rng.integers(0, 4, shape))
    second_hits = np.where(walls, rng.integers(0, 4, shape), (rng.random(shape) < 0.05).astype(int))
    second_passes = np.where(walls, rng.integers(0, 2, shape), rng.integers(0, 4, shape))
    return ScanSplit(first_hits, first_passes, second_hits, second_passes, resolution=0.1)


def test_score_all_calibrates_every_row_of_the_table():
    sp = _split()
    preds = all_baselines(sp, names=["raw", "mean3x3", "thesis", "graphcut"])
    preds[DEFAULT_PRESET] = get_preset(DEFAULT_PRESET).refine(hits=sp.first_hits, passes=sp.first_passes).beliefs.probability
    preds["octomap"] = np.clip(sp.raw_probability() * 0.9 + 0.05, 0, 1)  # stands in for a peer's map
    # the log-odds row needs scans: any grid of P stands in for it here
    preds["logodds"] = np.where(sp.first_hits > sp.first_passes, 0.8, np.where(sp.first_passes > 0, 0.2, 0.5))
    result = peer_report.score_all(sp, preds, n_boot=10, block=4, seed=0, temperature=0.8)
    rows = set(preds) - {"mean3x3"} | {f"{DEFAULT_PRESET}-T"}  # mean3x3 is no table row
    assert set(result["scores"]) == rows and set(result["calibration"]) == rows
    mask, labels = sp.group("all"), sp.labels()[sp.group("all")]
    for name in ("logodds", "thesis", "graphcut", "raw"):
        assert result["calibration"][name]["ece"] == pytest.approx(expected_calibration_error(preds[name][mask], labels))
    table = peer_report.peer_table("synthetic", result, {"octomap": 1.0})
    ece_column = table["header"].index("ECE")
    eces = {row[0]: row[ece_column] for row in table["rows"]}
    assert set(eces) == rows and all(np.isfinite(v) and 0 <= v <= 1 for v in eces.values()), eces
