"""The search that chooses the certainty preset: the algorithm on small splits, and its cached Intel result."""
import itertools

import numpy as np
import pytest

from crfmap.data import data_file, have_data
from crfstudy.analysis import preset_search as ps
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import get_preset
from crfmap.errors import InputError


def _split(seed=0, shape=(20, 20)):
    rng = np.random.default_rng(seed)
    walls = rng.random(shape) < 0.2
    h1, e1 = rng.poisson(np.where(walls, 2.0, 0.2)), rng.poisson(np.where(walls, 0.3, 1.5))
    h2, e2 = rng.poisson(np.where(walls, 2.0, 0.2)), rng.poisson(np.where(walls, 0.3, 1.5))
    return ScanSplit(h1, e1, h2, e2)


SMALL_GRID = {"coupling": (0.0, 0.2, 0.35), "occupied_first": (0.5, 1.5), "free_further": (0.1, 0.3), "margin": (1, 3)}
SMALL_START = dict(ps.START, coupling=0.2, occupied_first=0.5, free_further=0.1, margin=1)


def test_search_ends_where_no_single_coordinate_move_helps_and_its_trace_is_honest():
    sp = _split()
    r = ps.coordinate_search(sp, grid=SMALL_GRID, start=SMALL_START, dtype=np.float64)
    for entry in r.trace:  # every traced score is that configuration's score
        config = {k: entry[k] for k in ps.GRID if k in entry}
        assert entry["brier"] == pytest.approx(ps.search_brier(sp, config, dtype=np.float64), abs=1e-12)
    assert len({tuple(sorted((k, e[k]) for k in ps.GRID)) for e in r.trace}) == r.configurations
    assert r.converged and r.best_brier == pytest.approx(ps.search_brier(sp, r.best, dtype=np.float64))
    for name, values in SMALL_GRID.items():  # coordinate-wise minimum, by brute force
        for v in values:
            assert ps.search_brier(sp, dict(r.best, **{name: v}), dtype=np.float64) >= r.best_brier - 1e-12
    # and no worse than the start; the full grid's optimum is at most as good
    full = min(ps.search_brier(sp, dict(SMALL_START, **dict(zip(SMALL_GRID, combo))), dtype=np.float64)
               for combo in itertools.product(*SMALL_GRID.values()))
    assert full <= r.best_brier <= r.trace[0]["brier"]


def test_preset_from_round_trips_the_preset_constants():
    p = get_preset("certainty")
    q = ps.preset_from(ps.preset_constants(p))
    assert np.allclose(q.hidden, p.hidden) and (q.occupied, q.free, q.limit, q.margin) == \
        (p.occupied, p.free, p.limit, p.margin)


@pytest.mark.parametrize("grid,start", [({"nope": (1,)}, None), ({"coupling": ()}, None),
                                        ({"coupling": (0.1, 0.2)}, dict(ps.START, coupling=0.3))])
def test_bad_search_input_is_refused(grid, start):
    with pytest.raises(InputError):
        ps.coordinate_search(_split(), grid=grid, start=start)


def test_cache_is_this_search_on_intel():
    cached = ps.load_cached()
    assert cached["grid"] == {k: list(v) for k, v in ps.GRID.items()} and cached["start"] == ps.START
    assert cached["order"] == list(ps.ORDER) and cached["recording"] == ps.TRAINING
    assert cached["configurations"] == len(cached["trace"]) and cached["converged"]
    # its best is the lowest score of its trace, and every one-coordinate move from it was scored
    assert cached["best_brier"] == min(e["brier"] for e in cached["trace"])
    scored = {tuple(e[k] for k in ps.ORDER): e["brier"] for e in cached["trace"]}
    for name, values in ps.GRID.items():
        for v in values:
            assert scored[tuple(dict(cached["best"], **{name: v})[k] for k in ps.ORDER)] >= cached["best_brier"]


def test_preset_constants_are_what_the_search_returns():
    assert ps.preset_constants(get_preset("certainty")) == ps.load_cached()["best"]


@pytest.mark.skipif(not have_data(ps.TRAINING), reason="Intel log not downloaded")
def test_cached_scores_are_reproduced_on_intel():
    from crfmap.assess.scansplit import scan_split
    from crfmap.io.recordings import load_recording

    cached = ps.load_cached()
    sp = scan_split(load_recording(data_file(ps.TRAINING)).scans, ps.TRAINING_RESOLUTION)
    assert ps.search_brier(sp, cached["best"]) == pytest.approx(cached["best_brier"], abs=1e-9)


def test_command_refuses_bad_arguments_and_missing_data(tmp_path, monkeypatch, capsys):
    assert ps.main(["--nope"]) == 2
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))
    assert ps.main([]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and err[1].startswith("crfmap preset search:") and "intel" in err[1].lower()
