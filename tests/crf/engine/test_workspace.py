"""infer's reusable buffers (crfmap.crf.engine.workspace): reused only when free, never changing a result."""
import numpy as np

from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.engine import workspace
from crfmap.crf.inference.lbp import infer

RNG = np.random.default_rng(13)


def test_buffers_are_reused_only_once_nothing_else_holds_them():
    shape = (1024, 1024)
    assert np.prod(shape) >= workspace.WORKSPACE_MIN_CELLS
    a = workspace.beliefs_buffer(shape)
    b = workspace.beliefs_buffer(shape)
    assert a is not b  # ``a`` still held
    view = b[3:5]
    del b
    assert workspace.beliefs_buffer(shape) is not view.base  # a view holds its buffer too
    c = workspace.beliefs_buffer(shape)
    c_id = id(c)
    del c, view
    assert id(workspace.beliefs_buffer(shape)) == c_id  # free now: the same buffer again
    assert workspace.beliefs_buffer((8, 8)) is not workspace.beliefs_buffer((8, 8))  # small: always new
    workspace.release_workspace()
    assert workspace._CACHE == {}


def test_results_of_successive_calls_do_not_share_or_change_buffers():
    """A kept result keeps its beliefs and packed messages; a later call equals a fresh one bit for bit."""
    workspace.release_workspace()
    obs = RNG.uniform(0.0, 1.0, (1024, 1100))
    first = infer(obs, max_iter=5, tol=0.0, dtype=np.float64)
    kept_beliefs = first.beliefs.probability.copy()
    second = infer(obs[::-1].copy(), max_iter=5, tol=0.0, dtype=np.float64)  # first still held: new buffers
    assert not np.shares_memory(first.beliefs.probability, second.beliefs.probability)
    np.testing.assert_array_equal(first.beliefs.probability, kept_beliefs)
    plain = infer(obs, max_iter=5, tol=0.0, dtype=np.float64, schedule=Checkerboard(kernel="plain"))
    np.testing.assert_allclose(first.messages, plain.messages, atol=1e-9)  # unpacked after the second call
    del first, second
    again = infer(obs, max_iter=5, tol=0.0, dtype=np.float64)  # reuses the dropped buffers
    np.testing.assert_array_equal(again.beliefs.probability, kept_beliefs)
    np.testing.assert_allclose(again.beliefs.probability, plain.beliefs.probability, atol=1e-9)
    workspace.release_workspace()
