"""The search that chose the gated preset's J and pi: the cached result is reproduced and is what the preset holds."""
import math

import pytest

from crfmap.crf.presets import get_preset, table_coupling
from crfmap.data import have_data
from crfstudy.analysis import gate_search as gs


def test_the_cache_records_a_grid_whose_choice_is_the_gated_preset():
    cached = gs.load_cached()
    assert len(cached["rows"]) == len(gs.COUPLINGS) * len(gs.PRIORS)
    chosen = gs.best(cached["rows"])
    assert cached["best"] == {"J": chosen["J"], "pi": chosen["pi"]}
    gated = get_preset("gated")
    assert math.isclose(table_coupling(gated.hidden), chosen["J"], abs_tol=1e-9)
    assert gated.gate.unobserved_prior == chosen["pi"]
    # the choice is interior in pi and not on the grid's largest J (the certainty preset's)
    assert min(gs.PRIORS) < chosen["pi"] < max(gs.PRIORS) and chosen["J"] < max(gs.COUPLINGS)


@pytest.mark.skipif(not all(have_data(f) for f in gs.RECORDINGS.values()), reason="Intel / ACES logs not downloaded")
def test_the_chosen_point_is_reproduced_on_intel_and_aces():
    rows = gs.search(gs.training_splits(), couplings=(0.30,), priors=(0.25, 0.5))
    cached = {(r["J"], r["pi"]): r for r in gs.load_cached()["rows"]}
    for row in rows:
        assert row["weighted_logloss"] == pytest.approx(cached[(row["J"], row["pi"])]["weighted_logloss"], abs=1e-9)
        assert row["brier"] == pytest.approx(cached[(row["J"], row["pi"])]["brier"], abs=1e-9)
