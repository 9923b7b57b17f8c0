"""Evidence gating: the vectorised gate against a cell-by-cell reference, and the promises nav2 reads."""
import math

import numpy as np
import pytest

from crfmap.crf.model.gating import (
    OCCUPIED_THRESHOLD, FREE_THRESHOLD, UNKNOWN_CEILING, UNKNOWN_FLOOR, EvidenceGate, wall_line_gaps, wall_neighbours)
from crfmap.crf.presets import evidence_from_probability, get_preset
from crfmap.errors import InputError

OPPOSITE_PAIRS = (((0, 1), (0, -1)), ((1, 0), (-1, 0)), ((1, 1), (-1, -1)), ((1, -1), (-1, 1)))


def _at(mask, y, x):
    return 0 <= y < mask.shape[0] and 0 <= x < mask.shape[1] and bool(mask[y, x])


def slow_gate(p, hits, passes, free_evidence=2, lethal_evidence=2, line_hits=True, wall_lines=True,
              unobserved_prior=0.5):
    """The gate's rules, one cell at a time, written from the module docstring."""
    out = np.array(p, dtype=np.float64)
    x = hits.astype(float) - passes
    seen = hits + passes > 0
    walls = seen & (x >= 1)
    for y in range(p.shape[0]):
        for c in range(p.shape[1]):
            gap = any(_at(walls, y + a[0], c + a[1]) and _at(walls, y + b[0], c + b[1]) for a, b in OPPOSITE_PAIRS)
            off_line = not seen[y, c] and not (wall_lines and gap)
            if off_line:  # belief times the prior, in odds
                odds = out[y, c] / (1 - out[y, c]) * unobserved_prior / (1 - unobserved_prior)
                out[y, c] = odds / (1 + odds)
            if not x[y, c] <= -free_evidence and out[y, c] < UNKNOWN_FLOOR:
                out[y, c] = UNKNOWN_FLOOR
            on_line = any(_at(walls, y + dy, c + dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx)
            if x[y, c] >= lethal_evidence or (line_hits and walls[y, c] and on_line):
                out[y, c] = max(out[y, c], OCCUPIED_THRESHOLD)
            if off_line and out[y, c] > UNKNOWN_CEILING:
                out[y, c] = UNKNOWN_CEILING
    return out


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("options", [{}, {"free_evidence": 1, "lethal_evidence": 3},
                                     {"line_hits": False, "wall_lines": False},
                                     {"free_evidence": 4, "lethal_evidence": math.inf},
                                     {"unobserved_prior": 0.2}, {"unobserved_prior": 0.9, "wall_lines": False}])
def test_gate_matches_the_cell_by_cell_reference(seed, options):
    rng = np.random.default_rng(seed)
    shape = (7, 9)
    hits = rng.integers(0, 4, shape) * (rng.random(shape) < 0.5)
    passes = rng.integers(0, 5, shape) * (rng.random(shape) < 0.6)
    p = rng.uniform(0.01, 0.99, shape)
    got = EvidenceGate(**options).apply(p, hits, passes)
    assert np.allclose(got, slow_gate(p, hits, passes, **options), rtol=0, atol=1e-12)
    assert np.array_equal(p, np.asarray(p))  # the input is not changed in place


def test_free_cells_are_a_subset_of_the_raw_grids_free_cells():
    rng = np.random.default_rng(3)
    hits, passes = rng.integers(0, 3, (20, 20)), rng.integers(0, 6, (20, 20))
    raw_free = 0.5 + np.arctan(hits - passes.astype(float)) / np.pi <= FREE_THRESHOLD
    gated = EvidenceGate().apply(rng.random((20, 20)) * 0.3, hits, passes)  # a map that calls most cells free
    assert np.all(raw_free[gated <= FREE_THRESHOLD])
    assert (gated <= FREE_THRESHOLD).sum() > 0


def test_a_wall_stays_lethal_a_lone_hit_and_the_space_behind_do_not():
    # a corridor: free rows 0-2 passed 5 times, a wall on row 3 hit three times with one single-hit cell,
    # a lone single hit at (1, 6) in free space, and rows 4-5 behind the wall never observed
    hits, passes = np.zeros((6, 12), int), np.zeros((6, 12), int)
    passes[:3] = 5
    hits[3] = 3
    hits[3, 4] = 1
    hits[1, 6], passes[1, 6] = 1, 0
    r = get_preset("certainty").refine(hits=hits, passes=passes)
    gated = EvidenceGate().apply(r.beliefs.probability, hits, passes)
    assert np.all(gated[3] >= OCCUPIED_THRESHOLD)  # the wall, its single-hit cell included
    assert gated[1, 6] < OCCUPIED_THRESHOLD  # the lone hit (a ghost) is not lethal
    assert np.all(gated[4:] < OCCUPIED_THRESHOLD) and np.all(gated[4:] > FREE_THRESHOLD)  # behind: unknown
    assert r.beliefs.probability[4].max() > UNKNOWN_CEILING  # (the ungated CRF did grow the wall there)


def test_a_one_cell_gap_in_an_observed_wall_may_close():
    hits, passes = np.zeros((3, 5), int), np.zeros((3, 5), int)
    hits[1, [0, 1, 3, 4]] = 4
    p = np.full((3, 5), 0.9)
    gated = EvidenceGate().apply(p, hits, passes)
    assert gated[1, 2] == 0.9  # between two walls: may stay lethal
    assert gated[0, 2] == gated[2, 2] == UNKNOWN_CEILING  # beside the gap, on no line through two walls
    assert np.array_equal(gated, slow_gate(p, hits, passes))


def test_the_same_gate_from_a_map_files_probability():
    rng = np.random.default_rng(1)
    hits, passes = rng.integers(0, 3, (8, 8)), rng.integers(0, 3, (8, 8))
    raw = 0.5 + np.arctan(hits - passes.astype(float)) / np.pi
    p = rng.random((8, 8))
    from_counts = EvidenceGate().apply(p, hits, passes)
    from_map = EvidenceGate().apply(p, evidence=evidence_from_probability(raw), observed=hits + passes > 0)
    assert np.allclose(from_counts, from_map)


def test_the_prior_moves_only_never_observed_cells_and_keeps_them_unknown():
    hits, passes = np.zeros((1, 4), int), np.array([[0, 3, 0, 1]])
    p = np.array([[0.5, 0.1, 0.7, 0.3]])
    gated = EvidenceGate(unobserved_prior=0.2).apply(p, hits, passes)
    assert gated[0, 0] == UNKNOWN_FLOOR and gated[0, 2] == pytest.approx(0.7 * 0.2 / (0.7 * 0.2 + 0.3 * 0.8))
    assert gated[0, 1] == 0.1 and gated[0, 3] == 0.3  # observed cells keep their belief
    assert np.all(gated[0, [0, 2]] > FREE_THRESHOLD)
    hits = np.array([[2, 0, 2]])  # a never-observed cell between two walls keeps its belief
    assert EvidenceGate(unobserved_prior=0.2).apply(np.array([[0.9, 0.8, 0.9]]), hits, 0 * hits)[0, 1] == 0.8


def test_the_bounds_are_written_unknown_by_map_savers_rounding():
    from crfmap.grid import OccupancyGrid

    values = OccupancyGrid(np.array([[UNKNOWN_FLOOR, UNKNOWN_CEILING]])).to_int8()[0]
    assert round(100 * FREE_THRESHOLD) < values[0] and values[1] < round(100 * OCCUPIED_THRESHOLD)


def test_neighbour_masks():
    walls = np.zeros((5, 5), bool)
    walls[2, 2] = True
    assert wall_neighbours(walls).sum() == 8 and not wall_neighbours(walls)[2, 2]
    walls[2, 4] = True
    assert np.flatnonzero(wall_line_gaps(walls)).tolist() == [13]  # (2, 3), between the two


@pytest.mark.parametrize("bad", [{"free_evidence": 0}, {"free_evidence": float("nan")}, {"lethal_evidence": -1},
                                 {"free_evidence": True},
                                 {"unobserved_prior": 0.0}, {"unobserved_prior": 1.0}, {"unobserved_prior": "0.2"}])
def test_bad_settings_are_refused(bad):
    with pytest.raises(InputError):
        EvidenceGate(**bad)


def test_bad_input_is_refused():
    g = EvidenceGate()
    with pytest.raises(InputError, match="hits"):
        g.apply(np.zeros((2, 2)), np.zeros((2, 3), int), np.zeros((2, 3), int))
    with pytest.raises(InputError, match="gate"):
        g.apply(np.zeros((2, 2)))
    with pytest.raises(InputError, match="probability"):
        g.apply(np.zeros(4), evidence=np.zeros(4))
