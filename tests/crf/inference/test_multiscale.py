"""The coarse-to-fine start (crfmap.crf.inference.multiscale, infer(init="coarse")) against the uniform start."""
import numpy as np
import pytest

from crfstudy.bench.common import bench_grid
from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.inference import multiscale
from crfmap.crf.inference.lbp import infer
from crfmap.crf.presets import coupling_table
from crfmap.errors import InputError

RNG = np.random.default_rng(7)


def test_downsample_combines_block_log_odds_and_upsample_repeats():
    p = RNG.uniform(0.05, 0.95, (5, 7))
    coarse = multiscale.downsample(p)
    assert coarse.shape == (3, 4)
    logit = np.log(p / (1 - p))
    assert np.isclose(coarse[1, 2], 1 / (1 + np.exp(-logit[2:4, 4:6].sum())))
    assert np.isclose(coarse[2, 3], 1 / (1 + np.exp(-4 * logit[4, 6])))  # odd corner: counted four times
    m = RNG.uniform(size=(4, 3, 4))
    up = multiscale.upsample_messages(m, (5, 7))
    assert up.shape == (4, 5, 7)
    assert up[1, 4, 5] == m[1, 2, 2] and up[3, 0, 1] == m[3, 0, 0]
    assert multiscale.levels((127, 500)) == 0 and multiscale.levels((128, 500)) == 1 and multiscale.levels((512, 512)) == 3


@pytest.mark.parametrize("hidden", [[[2.0, 1.0], [1.0, 2.0]], coupling_table(0.35)])
@pytest.mark.parametrize("shape, kind", [((256, 300), "office"), ((129, 200), "noise"), ((300, 131), "office")])
def test_single_fixed_point_coarse_start_gives_the_uniform_start_beliefs(hidden, shape, kind):
    if kind == "office":
        obs = bench_grid(max(shape), kind="office")[: shape[0], : shape[1]]
    else:
        obs = RNG.uniform(0.0, 1.0, shape)
    plain = infer(obs, hidden, tol=1e-7, max_iter=5000)
    coarse = infer(obs, hidden, tol=1e-7, max_iter=5000, init="coarse")
    assert plain.converged and coarse.converged
    assert "coarse" in coarse.timings and coarse.seconds >= coarse.timings["coarse"]
    np.testing.assert_allclose(coarse.beliefs.probability, plain.beliefs.probability, atol=1e-4)
    # and the plain kernels agree (the option is a warm start, whatever the kernel)
    plain_kernel = infer(obs, hidden, tol=1e-7, max_iter=5000, init="coarse", schedule=Checkerboard(kernel="plain"))
    np.testing.assert_allclose(plain_kernel.beliefs.probability, plain.beliefs.probability, atol=1e-4)


def test_ordered_phase_coarse_start_runs_and_mostly_agrees():
    """[[10, 1], [1, 10]]: several fixed points; the coarse start's keeps most cells on the same side."""
    obs = bench_grid(256, kind="office")
    plain = infer(obs, tol=1e-5, max_iter=5000)
    coarse = infer(obs, tol=1e-5, max_iter=5000, init="coarse")
    assert plain.converged and coarse.converged
    same = np.mean((plain.beliefs.probability > 0.5) == (coarse.beliefs.probability > 0.5))
    assert same > 0.95


def test_small_grids_start_uniform_and_bad_init_is_named():
    obs = RNG.uniform(0.0, 1.0, (100, 300))  # too small to halve: exactly the uniform start
    a, b = infer(obs, max_iter=7, tol=0.0), infer(obs, max_iter=7, tol=0.0, init="coarse")
    np.testing.assert_array_equal(a.beliefs.probability, b.beliefs.probability)
    with pytest.raises(InputError, match="init"):
        infer(obs, init="fine")
    with pytest.raises(InputError, match="init"):
        infer(obs, init="coarse", messages=a.messages)
