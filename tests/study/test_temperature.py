"""A preset's temperature fitted on a scan split: a known temperature of the preset recovered."""
import numpy as np
import pytest

from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import get_preset, temper
from crfmap.errors import InputError
from crfstudy.temperature import fit_split_temperature, tempered_preset


def test_split_temperature_recovers_a_known_temperature_of_the_preset():
    rng = np.random.default_rng(4)
    shape = (160, 160)
    first_hits, first_passes = rng.integers(0, 6, shape), rng.integers(0, 6, shape)
    p = get_preset("certainty").refine(hits=first_hits, passes=first_passes).beliefs.probability
    known = 0.8  # the world is sharper than the preset says: the preset is under-confident, T = 0.8 fixes it
    truth = temper(p, known)
    occupied = rng.uniform(0, 1, shape) < truth
    observed = rng.uniform(0, 1, shape) < 0.9  # the second half sees most cells, once
    sp = ScanSplit(first_hits, first_passes, (occupied & observed).astype(int), (~occupied & observed).astype(int))
    t = fit_split_temperature(sp, p)
    assert t == pytest.approx(known, rel=0.05)
    tempered = tempered_preset("certainty", t).refine(hits=first_hits, passes=first_passes).beliefs.probability
    np.testing.assert_allclose(tempered, temper(p, t), atol=1e-12)
    assert fit_split_temperature(sp, p, group="seen") == pytest.approx(known, rel=0.05)
    with pytest.raises(InputError, match="shape"):
        fit_split_temperature(sp, p[:10])
