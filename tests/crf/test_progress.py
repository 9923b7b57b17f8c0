"""A watcher sees every LBP pass up to the iterations run (crfmap infer's bar), on the engine and the plain loops."""
import numpy as np
import pytest

from crfmap.crf import infer
from crfmap.crf.engine.progress import watch


@pytest.mark.parametrize("schedule", ["checkerboard", "flooding"])
def test_the_watcher_sees_the_passes_up_to_max_iter(schedule):
    grid = np.clip(np.random.default_rng(1).random((20, 30)), 0.05, 0.95)
    seen = []
    with watch(lambda done, limit, change: seen.append((done, limit))):
        result = infer(grid, max_iter=40, tol=0.0, schedule=schedule)
    done = [d for d, _ in seen]
    assert done == sorted(done) and done[-1] == result.iterations == 40
    assert {limit for _, limit in seen} == {40}
    seen.clear()
    infer(grid, max_iter=5, tol=0.0, schedule=schedule)  # outside the block: nobody is told
    assert seen == []
