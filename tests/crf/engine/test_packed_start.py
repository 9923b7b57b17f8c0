"""The fused whole-grid start of the fast path (packing, grid check and first half-sweep in one pass)."""
import numpy as np
import pytest

import crfmap.crf.engine.packed as F
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import directional_tables

RNG = np.random.default_rng(13)
TABLES = [
    ([[10.0, 1.0], [1.0, 10.0]], "receiver"),
    ([[3.0, 0.7], [1.3, 2.5]], "receiver"),
    ([[3.0, 0.7], [1.3, 2.5]], "oriented"),
    ([[1.0, 0.0], [0.0, 1.0]], "receiver"),  # messages clamped at the floor
    ([[1.0, 1e-7], [1e-7, 1.0]], "receiver"),  # near-hard: the clamp acts
]
LINK = np.array([[1.1, 0.1], [0.2, 1.3]])


def poisoned_block(shape, dtype, tables):
    """A block on NaN-filled planes: any entry the fused start forgets to write shows up."""
    h, w = shape
    wp = F.plane_width(w)
    arrays = (np.full((2, 4, h + 2, wp), np.nan, dtype), np.full((2, h + 2, wp), np.nan, dtype))
    return F.PackedBlock(h, w, dtype, tables, MESSAGE_FLOOR, arrays, fill=False)


@pytest.mark.parametrize("shape", [(1, 1), (1, 8), (7, 1), (2, 3), (5, 6), (33, 40), (130, 67)])
@pytest.mark.parametrize("hidden, pairing", TABLES)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_fused_start_equals_unary_then_full_iterations(shape, hidden, pairing, dtype):
    """start_uniform + k iterations = set_unary + k iterations: float32 bit for bit, float64 to rounding."""
    obs = RNG.uniform(0.0, 1.0, shape)
    obs[0, 0], obs[-1, -1] = 0.0, 1.0
    tables = directional_tables(np.array(hidden), pairing)
    plain = F.PackedBlock(*shape, dtype, tables, MESSAGE_FLOOR)
    plain.set_unary(obs, LINK)
    fused = poisoned_block(shape, dtype, tables)
    assert fused.start_uniform(obs, LINK, threads=2) == (0, 0)
    for n in (3, 2):
        c_plain, t_plain = plain.run_pass(n, 2)
        c_fused, t_fused = fused.run_pass(n, 2)
        tol = 0.0 if dtype == np.float32 else 1e-12
        assert abs(c_plain - c_fused) <= tol
        np.testing.assert_allclose(t_fused, t_plain, rtol=0, atol=tol)
    tol = 0.0 if dtype == np.float32 else 1e-12
    np.testing.assert_allclose(fused.beliefs(), plain.beliefs(), rtol=0, atol=tol)
    out = np.full((2, 4) + shape, 0.5)  # every real cell's slots (a NaN left unwritten fails here)
    np.testing.assert_allclose(fused.messages(out[0]), plain.messages(out[1]), rtol=0, atol=tol)


def test_the_pass_after_a_fused_start_must_do_two_whole_grid_iterations():
    block = F.PackedBlock(4, 4, np.float64, directional_tables(np.array(TABLES[0][0])), MESSAGE_FLOOR, fill=False)
    block.start_uniform(RNG.uniform(0, 1, (4, 4)), LINK)
    with pytest.raises(ValueError, match="two iterations"):
        block.run_pass(1, 1)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("hidden", [TABLES[0][0], TABLES[1][0], TABLES[3][0]])
def test_the_fused_start_equals_the_general_path(dtype, hidden):
    """A C-ordered float64 array (or grid) takes the fused start, a Fortran-ordered one the general path: same run."""
    obs = np.random.default_rng(66).uniform(0.0, 1.0, (150, 97))  # its own draw: xdist orders the module's RNG calls
    fused = infer(obs, hidden, LINK, max_iter=37, tol=0.0, dtype=dtype)
    general = infer(np.asfortranarray(obs), hidden, LINK, max_iter=37, tol=0.0, dtype=dtype)
    on_grid = infer(OccupancyGrid(obs, resolution=0.05), hidden, LINK, max_iter=37, tol=0.0, dtype=dtype)
    assert np.array_equal(on_grid.beliefs.probability, fused.beliefs.probability)
    assert on_grid.beliefs.resolution == 0.05
    assert fused.iterations == general.iterations == 37
    tol = 1e-6 if dtype == np.float32 else 1e-12
    np.testing.assert_allclose(fused.beliefs.probability, general.beliefs.probability, rtol=0, atol=tol)
    np.testing.assert_allclose(fused.messages, general.messages, rtol=0, atol=tol)
    assert set(fused.timings) == {"pack", "iterate", "unpack"}


def test_fused_start_is_deterministic_across_thread_counts():
    obs = RNG.uniform(0.0, 1.0, (700, 530))  # large enough for several bands and row blocks
    one = infer(obs, max_iter=20, tol=0.0, dtype=np.float32, threads=1)
    two = infer(obs, max_iter=20, tol=0.0, dtype=np.float32, threads=2)
    assert np.array_equal(one.beliefs.probability, two.beliefs.probability)
    assert np.array_equal(one.max_change, two.max_change, equal_nan=True)


@pytest.mark.parametrize("bad, word", [(np.nan, "NaN"), (np.inf, "infinite"), (1.5, "probabilities"),
                                       (-0.25, "probabilities")])
def test_a_bad_array_is_named_by_the_fused_check(bad, word):
    obs = RNG.uniform(0.0, 1.0, (40, 30))
    obs[17, 3] = bad
    with pytest.raises(InputError, match=word) as err:
        infer(obs, max_iter=5)
    assert "grid" in str(err.value)


def test_certain_cells_found_while_packing_are_clamped_as_on_the_general_path():
    """A link with a zero makes P = 0 / 1 cells certain: the fused start hands over to the clamps."""
    link = [[1.0, 0.3], [0.0, 1.0]]  # P = 1 is certainly occupied
    obs = RNG.uniform(0.05, 0.95, (60, 45))
    obs[10:13, 20:24] = 1.0
    fused = infer(obs, TABLES[0][0], link, max_iter=30, tol=0.0)
    general = infer(np.asfortranarray(obs), TABLES[0][0], link, max_iter=30, tol=0.0)
    np.testing.assert_allclose(fused.beliefs.probability, general.beliefs.probability, rtol=0, atol=1e-12)
    assert (fused.beliefs.probability[10:13, 20:24] == 1.0).all()


@pytest.mark.parametrize("link", [LINK, [[1.0, 0.3], [0.0, 1.0]], [[0.0, 1.0], [1.0, 0.0]], [[0.0, 0.0], [0.0, 0.0]],
                                  [[2.0, 0.0], [0.0, 0.0]]])
def test_observation_odds_are_the_floored_probability_as_odds(link):
    """One division (occ / emp) gives the odds of the floored P(occupied) = occ / (occ + emp) (the earlier form;
    at the floor that form loses digits in 1 - u, hence 1e-9)."""
    from crfmap.crf.engine._layout import unary_odds

    lk = np.asarray(link, np.float64).ravel()
    for p in np.concatenate([[0.0, 1.0, 0.5, 1e-9, 1 - 1e-9], RNG.uniform(0, 1, 200)]):
        occ, emp = lk[0] * p + lk[1] * (1 - p), lk[2] * p + lk[3] * (1 - p)
        u = occ / (occ + emp) if occ + emp > 0 else 0.5
        u = min(max(u, MESSAGE_FLOOR), 1 - MESSAGE_FLOOR)
        assert unary_odds(p, lk, MESSAGE_FLOOR) == pytest.approx(u / (1 - u), rel=1e-9)


def test_tile_dilation_is_scipys_binary_dilation():
    """The active tiles grow as scipy.ndimage.binary_dilation's cross would grow them (the slices stay: 3 to 40
    times faster on tile grids of 16^2 to 128^2, once per iteration of a sparse run)."""
    from scipy import ndimage

    for seed in range(40):
        rng = np.random.default_rng(seed)
        moving = rng.random(tuple(rng.integers(1, 20, 2))) < rng.uniform(0, 0.3)
        np.testing.assert_array_equal(F._dilate(moving), ndimage.binary_dilation(moving))
