"""Presets: the thesis's tables unchanged, the certainty preset's promises, maps vs counts."""
import numpy as np
import pytest

from crfmap.crf.inference.lbp import infer
from crfmap.crf.presets import CRITICAL_COUPLING, evidence_from_probability, get_preset, PRESETS
from crfmap.errors import InputError


def test_thesis_preset_is_the_thesis_default():
    p = np.array([[0.9, 0.5, 0.2], [0.1, 0.6, 0.5]])
    a = get_preset("thesis").refine(p, max_iter=200, tol=1e-9).beliefs.probability
    b = infer(p, [[10, 1], [1, 10]], [[1, 0], [0, 1]], max_iter=200, tol=1e-9).beliefs.probability
    assert np.allclose(a, b)


def test_certainty_is_subcritical_and_a_strong_wall_survives_four_free_neighbours():
    c = get_preset("certainty")
    assert c.coupling < CRITICAL_COUPLING
    hits = np.zeros((5, 5), int)
    passes = np.full((5, 5), 30)
    hits[2, 2], passes[2, 2] = 20, 0  # a wall seen 20 times, free all around
    b = c.refine(hits=hits, passes=passes).beliefs.probability
    assert b[2, 2] > 0.5
    hits[2, 2] = 1  # seen once: yields to its neighbours
    assert c.refine(hits=hits, passes=passes).beliefs.probability[2, 2] < 0.5


def test_never_seen_space_far_from_observations_stays_unknown():
    hits = np.zeros((30, 30), int)
    passes = np.zeros((30, 30), int)
    passes[:5, :5] = 3
    hits[5, :5] = 2
    r = get_preset("certainty").refine(hits=hits, passes=passes)
    b = r.beliefs.probability
    assert r.converged
    assert np.all(b[15:, 15:] == 0.5)  # more than `margin` cells from any observation
    assert b[6, 2] != 0.5  # next to observations: filled in


def test_a_map_file_gives_what_its_counts_give():
    rng = np.random.default_rng(0)
    hits, passes = rng.integers(0, 4, (10, 12)), rng.integers(0, 4, (10, 12))
    hits[:, :2] = passes[:, :2] = 0
    passes[(hits == passes) & (hits > 0)] += 1  # a map cannot tell "never seen" from "as many hits as passes"
    c = get_preset("certainty")
    prob = 0.5 + np.arctan(hits - passes) / np.pi  # the grid crfmap builds from these counts
    assert np.allclose(evidence_from_probability(prob), hits - passes)
    from_counts = c.refine(hits=hits, passes=passes).beliefs.probability
    from_map = c.refine(prob).beliefs.probability
    assert np.allclose(from_counts, from_map)


def test_trinary_map_values_are_the_strongest_observations():
    c = get_preset("certainty")
    u = c.observation(probability=np.array([0.0, 0.5, 1.0]))
    s = 1 / (1 + np.exp(-c.limit))
    assert np.allclose(u, [1 - s, 0.5, s])


def test_unknown_preset_is_named():
    with pytest.raises(InputError, match="preset"):
        get_preset("nope")
    assert set(PRESETS) == {"thesis", "certainty", "gated"}


def test_refine_within_bounds_the_senders_and_keeps_the_preset_region():
    """``within`` limits the cells that send messages (as infer's region); outside the preset's own region the
    beliefs stay the observation."""
    from crfmap.crf.presets import DEFAULT_PRESET, custom_preset
    from crfmap.grid import OccupancyGrid

    rng = np.random.default_rng(1)
    grid = OccupancyGrid(rng.uniform(0.1, 0.9, (12, 24)))
    within = np.zeros(grid.shape, bool)
    within[3:8, 3:8] = True
    crf = custom_preset([[4.0, 1.0], [1.0, 4.0]])
    got = crf.refine(grid, within=within, max_iter=5).beliefs.probability
    want = infer(grid, crf.hidden, crf.link, region=within, max_iter=5, tol=1e-5).beliefs.probability
    assert np.array_equal(got, want)
    with pytest.raises(InputError, match="within"):
        crf.refine(grid, within=within[:3])
    unseen = grid.probability.copy()
    unseen[:, 9:] = 0.5  # never observed: beyond the default preset's margin nothing is inferred
    default = get_preset(DEFAULT_PRESET)
    assert default.margin is not None and 9 + default.margin < grid.width
    beliefs = default.refine(unseen, within=np.ones(grid.shape, bool)).beliefs.probability
    far = beliefs[:, 9 + default.margin:]  # no LBP there: the observation, and the gate's prior if the preset has one
    np.testing.assert_allclose(far, 0.5 if default.gate is None else default.gate.unobserved_prior, rtol=1e-12)
    certainty = get_preset("certainty").refine(unseen).beliefs.probability
    assert np.all(certainty[:, 9 + get_preset("certainty").margin:] == 0.5)
    assert np.array_equal(beliefs, default.refine(unseen).beliefs.probability)


def test_temperature_tempers_the_whole_refined_map_and_one_changes_nothing():
    from dataclasses import replace

    from crfmap.crf.presets import temper

    c = get_preset("certainty")
    assert c.temperature == 1.0 and get_preset("thesis").temperature == 1.0
    rng = np.random.default_rng(3)
    hits, passes = rng.integers(0, 3, (20, 20)), rng.integers(0, 3, (20, 20))
    hits[:, 12:] = passes[:, 12:] = 0  # a never-seen strip, partly beyond the margin
    base = c.refine(hits=hits, passes=passes).beliefs.probability
    assert np.array_equal(replace(c, temperature=1.0).refine(hits=hits, passes=passes).beliefs.probability, base)
    for t in (0.5, 2.0):
        got = replace(c, temperature=t).refine(hits=hits, passes=passes).beliefs.probability
        q = np.clip(base, 1e-6, 1 - 1e-6)
        np.testing.assert_allclose(np.log(got / (1 - got)), np.log(q / (1 - q)) / t, atol=1e-9)
        assert np.all(got[:, 19] == 0.5)  # unknown stays unknown
    np.testing.assert_allclose(temper(base, 2.0), replace(c, temperature=2.0).refine(hits=hits, passes=passes)
                               .beliefs.probability)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), float("inf"), "warm", True])
def test_bad_temperature_is_named(bad):
    from dataclasses import replace

    with pytest.raises(InputError, match="temperature"):
        replace(get_preset("certainty"), temperature=bad)


def _observation_reference(preset, x):
    """The certainty-scaled observation written out with NumPy, element by element as the module docstring says."""
    with np.errstate(invalid="ignore"):
        a = np.abs(x) - 1
        logit = np.where(x > 0, np.minimum(preset.occupied[0] + preset.occupied[1] * a, preset.limit),
                         -np.minimum(preset.free[0] + preset.free[1] * a, preset.limit))
    return 1.0 / (1.0 + np.exp(-np.where(x == 0, 0.0, logit)))


def test_the_observation_kernel_is_numpy_s_formula_to_the_last_places():
    # the same operations in the same order; only exp may differ by an ulp: NumPy has its own SIMD exp where the CPU
    # has AVX-512 (bit for bit elsewhere), and 1 / (1 + e) carries that to a few ulps of P
    preset = get_preset("certainty")
    rng = np.random.default_rng(3)
    hits, passes = rng.integers(0, 40, (130, 70)), rng.integers(0, 40, (130, 70))
    np.testing.assert_array_max_ulp(preset.observation(hits=hits, passes=passes),
                                    _observation_reference(preset, hits.astype(float) - passes), maxulp=4)
    p = rng.uniform(0.0, 1.0, (130, 70))
    p[::5], p[1, ::3], p[2, ::4] = 0.5, 0.0, 1.0  # unknown, trinary free and occupied
    np.testing.assert_array_max_ulp(preset.observation(probability=p),
                                    _observation_reference(preset, evidence_from_probability(p)), maxulp=4)
    assert preset.observation(probability=p[0]).shape == (70,)  # any shape: a row, a scalar
    np.testing.assert_array_max_ulp(preset.observation(hits=np.array(3), passes=np.array(1)),
                                    _observation_reference(preset, np.array(2.0)), maxulp=4)


def test_the_observation_keeps_nan_and_a_zero_slope_caps_infinite_evidence_at_its_first_hit():
    from dataclasses import replace

    preset = replace(get_preset("certainty"), occupied=(1.5, 0.0), free=(0.75, 0.0))
    u = preset.observation(probability=np.array([[np.nan, 1.0, 0.0, 0.5]]))
    assert np.isnan(u[0, 0])
    np.testing.assert_allclose(u[0, 1:], [1 / (1 + np.exp(-1.5)), 1 / (1 + np.exp(0.75)), 0.5], rtol=1e-15)
