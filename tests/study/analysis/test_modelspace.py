"""The model-space search keeps what it computed instead of computing it twice."""
import numpy as np

from crfstudy.analysis import modelspace
from crfmap.assess.scansplit import ScanSplit


def _split(seed=0, shape=(24, 24)):
    rng = np.random.default_rng(seed)
    return ScanSplit(*(rng.integers(0, 3, shape) for _ in range(4)))


def test_phase_diagram_keeps_the_grids_it_refined():
    sp = _split()
    d = modelspace.symmetric_tables(sp, [0.0, 0.3, 0.6], [0.5, 1.0], margin=2, keep=[(0.6, 0.5)], dtype=np.float32)
    assert set(d["beliefs"]) == {d["best"], (0.6, 0.5)}
    for pair, beliefs in d["beliefs"].items():
        again, _ = modelspace.table_refine(sp, *pair, margin=2, dtype=np.float32)
        np.testing.assert_array_equal(beliefs, again)
    assert np.all(d["iterations"] >= 1)


def test_fit_scaled_from_given_scores_equals_the_search():
    sp = _split(1)
    scores = modelspace.scaled_scores(sp, [0.2, 0.35], [0.7, 1.0])
    assert len(scores) == 4 and all(np.isfinite(list(scores.values())))
    best = modelspace.fit_scaled(sp, [0.2, 0.35], [0.7, 1.0])
    assert best == modelspace.fit_scaled(sp, [0.2, 0.35], [0.7, 1.0], scores=scores)
    assert scores[best] == min(scores.values())
