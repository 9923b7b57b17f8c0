"""The paired ECE on a scan split against the ECE of explicitly resampled blocks."""
import numpy as np
import pytest

from crfmap.assess.calibration import expected_calibration_error
from crfmap.assess.scansplit import ScanSplit, block_resamples
from crfmap.errors import InputError
from crfstudy.calibration import paired_calibration


def test_paired_calibration_matches_ece_of_explicitly_resampled_blocks():
    """Each resample's ECE is the ECE of the cells of the drawn blocks, each repeated as often as drawn."""
    rng = np.random.default_rng(3)
    sp = ScanSplit(*(rng.integers(0, 4, (24, 20)) for _ in range(4)))
    preds = {"raw": sp.raw_probability(), "noisy": np.clip(sp.raw_probability() + rng.normal(0, 0.2, sp.shape), 0, 1)}
    got = paired_calibration(sp, preds, "raw", n_boot=40, block=6, seed=5)
    r = block_resamples(sp, n_boot=40, block=6, seed=5)["all"]
    slow = {}
    for name, p in preds.items():
        values, y = p[r.mask], r.labels
        slow[name] = []
        for draw in r.draws:
            cells = np.concatenate([np.flatnonzero(r.inverse == b).repeat(n) for b, n in enumerate(draw)])
            slow[name].append(expected_calibration_error(values[cells], y[cells]))
        assert got[name]["ece"] == pytest.approx(expected_calibration_error(values, y), abs=1e-12)
    diff = np.array(slow["noisy"]) - np.array(slow["raw"])
    assert got["noisy"]["ece_diff"] == pytest.approx(got["noisy"]["ece"] - got["raw"]["ece"], abs=1e-12)
    assert got["noisy"]["ece_diff_ci"] == pytest.approx(tuple(np.quantile(diff, [0.025, 0.975])), abs=1e-12)
    assert got["noisy"]["ece_ci"] == pytest.approx(tuple(np.quantile(slow["noisy"], [0.025, 0.975])), abs=1e-12)
    sure = 0.05 + 0.9 * sp.labels()  # near the truth: a small ECE; its mirror image a large one
    versus = paired_calibration(sp, {"sure": sure, "wrong": 1 - sure}, "sure", n_boot=40, block=6)
    assert versus["wrong"]["ece_diff_ci"][0] > 0.5  # the paired interval sees the worse one
    assert paired_calibration(sp, preds, "raw", n_boot=0)["noisy"]["ece_ci"] is None
    with pytest.raises(InputError, match="reference"):
        paired_calibration(sp, preds, "certainty")
