"""The fast kernels (odds, red/black planes, temporal blocking, frozen tiles) against the plain ones."""
import numpy as np
import pytest

import crfmap.crf.engine.packed as F
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.regions import disc_region
from crfmap.crf.model.potentials import directional_tables

RNG = np.random.default_rng(2024)
TABLES = [
    ([[10.0, 1.0], [1.0, 10.0]], "receiver"),
    ([[3.0, 0.7], [1.3, 2.5]], "receiver"),  # non-symmetric, thesis pairing
    ([[3.0, 0.7], [1.3, 2.5]], "oriented"),  # non-symmetric, proper pairwise CRF
    ([[1.0, 0.0], [0.0, 1.0]], "receiver"),  # hard table: messages hit the floor
]
LINK = [[1.1, 0.1], [0.2, 1.3]]
PLAIN, FAST = Checkerboard(kernel="plain"), Checkerboard(kernel="fast")


def packed_run(obs, hidden, pairing, passes, threads=2, dtype=np.float64):
    """Run the fast kernel pass by pass; (beliefs, messages, changes: NaN but at pass ends)."""
    h, w = obs.shape
    block = F.PackedBlock(h, w, dtype, directional_tables(hidden, pairing), MESSAGE_FLOOR)
    block.set_unary(obs, np.asarray(LINK))
    changes = np.concatenate([[np.nan] * (n - 1) + [block.run_pass(n, threads)[0]] for n in passes])
    messages = block.messages(np.full((4, h, w), 0.5))
    return block.beliefs(), messages, changes


@pytest.mark.parametrize("shape", [(1, 9), (9, 1), (2, 2), (3, 4), (5, 7), (40, 41), (301, 96)])
@pytest.mark.parametrize("hidden, pairing", TABLES)
def test_fast_iterations_equal_plain_iterations(shape, hidden, pairing):
    """k fast iterations, however split into blocks, give the plain kernel's k iterations."""
    obs = RNG.uniform(0.0, 1.0, shape)
    obs[0, 0], obs[-1, -1] = 0.0, 1.0  # hard evidence too
    plain = infer(obs, hidden, LINK, pairing=pairing, max_iter=8, tol=0.0, schedule=PLAIN)
    for passes in ([1] * 8, [8], [3, 5]):
        beliefs, messages, changes = packed_run(obs, hidden, pairing, passes)
        np.testing.assert_allclose(beliefs, plain.beliefs.probability, atol=1e-9)
        np.testing.assert_allclose(messages, plain.messages, atol=1e-9)
        measured = np.isfinite(changes)
        assert measured.sum() == len(passes)
        np.testing.assert_allclose(changes[measured], plain.max_change[measured], atol=1e-9)


def test_blocked_pass_uses_several_bands_and_equals_plain():
    """A tall grid splits into bands (trapezoids, then the gaps between them): still exact."""
    obs = RNG.uniform(0.0, 1.0, (700, 300))
    block = F.PackedBlock(700, 300, np.float64, directional_tables([[4.0, 1.0], [1.0, 4.0]]), MESSAGE_FLOOR)
    edges = block.band_edges(6, threads=2)
    assert len(edges) >= 3
    assert np.all(edges[1:-1] % F.TILE_ROWS == 0)
    assert np.all(np.diff(edges) >= 4 * 6 + 2 * F.TILE_ROWS + 4)
    beliefs, messages, changes = packed_run(obs, [[4.0, 1.0], [1.0, 4.0]], "receiver", [6, 6])
    plain = infer(obs, [[4.0, 1.0], [1.0, 4.0]], LINK, max_iter=12, tol=0.0, schedule=PLAIN)
    np.testing.assert_allclose(beliefs, plain.beliefs.probability, atol=1e-10)
    np.testing.assert_allclose(changes[[5, 11]], plain.max_change[[5, 11]], atol=1e-10)


def test_float32_close_to_float64():
    obs = RNG.uniform(0.0, 1.0, (120, 130))
    b64, _, _ = packed_run(obs, [[10.0, 1.0], [1.0, 10.0]], "receiver", [4, 4])
    b32, _, _ = packed_run(obs, [[10.0, 1.0], [1.0, 10.0]], "receiver", [4, 4], dtype=np.float32)
    assert np.abs(b32 - b64).max() < 1e-4


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_infer_fast_equals_plain_bounded_with_warm_start(dtype):
    grid = OccupancyGrid(RNG.uniform(0.1, 0.9, (60, 80)), resolution=0.5)
    start = infer(grid, max_iter=3, tol=0.0, schedule=PLAIN).messages
    region = disc_region(grid, (17.0, 12.0), 6.0)
    plain = infer(grid, region=region, messages=start, max_iter=9, tol=0.0, schedule=PLAIN, dtype=dtype)
    fast = infer(grid, region=region, messages=start, max_iter=9, tol=0.0, schedule=FAST, dtype=dtype)
    assert fast.kernel == "fast" and plain.kernel == "plain"
    atol = 1e-10 if dtype == np.float64 else 1e-5
    np.testing.assert_allclose(fast.beliefs.probability, plain.beliefs.probability, atol=atol)
    np.testing.assert_allclose(fast.messages, plain.messages, atol=atol)
    # messages no active cell sends come back bit for bit
    senders = np.zeros((4,) + region.shape, bool)
    senders[0, :, 1:] = region[:, :-1]
    senders[1, :, :-1] = region[:, 1:]
    senders[2, 1:, :] = region[:-1, :]
    senders[3, :-1, :] = region[1:, :]
    np.testing.assert_array_equal(fast.messages[~senders], start.astype(dtype)[~senders])


def test_converged_beliefs_are_the_plain_fixed_point():
    obs = RNG.uniform(0.05, 0.95, (90, 70))
    plain = infer(obs, [[3.0, 1.0], [1.0, 3.0]], tol=1e-9, schedule=PLAIN)
    fast = infer(obs, [[3.0, 1.0], [1.0, 3.0]], tol=1e-9)
    assert fast.kernel == "fast" and fast.converged and plain.converged
    assert fast.iterations >= plain.iterations  # measured at block ends only
    assert np.isnan(fast.max_change).any() and fast.max_change[-1] < 1e-9
    np.testing.assert_allclose(fast.beliefs.probability, plain.beliefs.probability, atol=1e-7)


def settling_grid(h=128, w=256, rng=RNG):
    """Blocks of strong evidence (they settle early) and one noisy, weakly observed patch."""
    yy, xx = np.mgrid[0:h, 0:w]
    obs = np.where(((yy // 32) + (xx // 32)) % 2 == 0, 0.05, 0.95)
    obs[50:70, 150:190] = rng.uniform(0.4, 0.6, (20, 40))
    return obs


@pytest.fixture
def small_tiles(monkeypatch):
    monkeypatch.setattr(F, "TILE_ROWS", 8)
    monkeypatch.setattr(F, "TILE_COLS", 32)
    monkeypatch.setattr(F, "SPARSE_CELLS", 0)


def test_freezing_exactly_settled_tiles_changes_nothing(small_tiles):
    """freeze=0 skips only tiles whose messages did not move at all: the plain iterations."""
    obs = settling_grid()
    h, w = obs.shape
    n = 120
    plain = infer(obs, max_iter=n, tol=0.0, schedule=PLAIN)
    block = F.PackedBlock(h, w, np.float64, directional_tables([[10.0, 1.0], [1.0, 10.0]]), MESSAGE_FLOOR)
    block.set_unary(obs, np.eye(2))
    changes = block.run(n, 0.0, threads=2, block=8, freeze=0.0)
    assert len(changes) == n
    assert block.cell_updates < 0.8 * n * h * w  # tiles were frozen
    np.testing.assert_allclose(block.beliefs(), plain.beliefs.probability, atol=1e-12)


def test_freezing_converges_to_the_plain_fixed_point(small_tiles):
    obs = settling_grid()
    plain = infer(obs, tol=1e-6, schedule=PLAIN, max_iter=3000)
    fast = infer(obs, tol=1e-6, schedule=Checkerboard(freeze=1e-8), max_iter=3000)
    exact = infer(obs, tol=1e-6, schedule=Checkerboard(freeze=0.0), max_iter=3000)
    assert plain.converged and fast.converged and exact.converged
    assert fast.max_change[-1] < 1e-6  # decided by an iteration of every cell
    assert np.abs(fast.beliefs.probability - plain.beliefs.probability).max() < 1e-5
    assert np.abs(exact.beliefs.probability - plain.beliefs.probability).max() < 1e-5


@pytest.mark.parametrize("seed", [0, 1])
def test_a_settled_run_is_always_confirmed_by_a_whole_grid_iteration(small_tiles, seed):
    """Wherever max_iter cuts the run, a last change below tol was measured on every cell,
    never on the moving tiles only (the others frozen): else it is reported unmeasured (NaN)."""
    obs = settling_grid(rng=np.random.default_rng(seed))
    h, w = obs.shape
    tol = 1e-6
    tables = directional_tables([[10.0, 1.0], [1.0, 10.0]])
    cut_in_a_frozen_phase = 0
    for max_iter in range(41, 400, 2):  # the settled frozen pass ends where the rate predicts: cut often
        block = F.PackedBlock(h, w, np.float64, tables, MESSAGE_FLOOR)
        block.set_unary(obs, np.eye(2))
        passes = []  # (whole grid?, the pass's measured change), one per pass block.run makes
        plan, measured = block._pass_arguments, block._pass_change

        def planned(n, threads, measure, active):
            passes.append([active is None, None])  # noqa: B023 (this iteration's list)
            return plan(n, threads, measure, active)  # noqa: B023

        def logged(cb, measure, per_tile):
            out = measured(cb, measure, per_tile)  # noqa: B023
            passes[-1][1] = out[0]  # noqa: B023
            return out

        block._pass_arguments, block._pass_change = planned, logged
        changes = block.run(max_iter, tol, threads=1, block=8, freeze=1e-8)
        whole_grid, last = passes[-1]
        if not whole_grid and last < tol:
            cut_in_a_frozen_phase += 1
        if changes[-1] < tol:
            assert whole_grid and changes[-1] == last, max_iter
    assert cut_in_a_frozen_phase > 0  # the case this test is about did occur


def test_warm_start_from_converged_stops_at_once():
    # its own draw (xdist orders the module's RNG calls): with the default tables some draws need more than
    # max_iter to reach tol, and a warm start from an unconverged run rightly goes on
    obs = np.random.default_rng(1).uniform(0.1, 0.9, (64, 300))
    r = infer(obs, tol=1e-8)
    assert r.converged
    r2 = infer(obs, tol=1e-8, messages=r.messages)
    assert r2.iterations == 1 and r2.converged


def test_blocks_measure_their_last_iteration_and_grow_after_a_warm_start():
    obs = RNG.uniform(0.1, 0.9, (50, 60))
    r = infer(obs, max_iter=20, tol=0.0, schedule=Checkerboard(block=8))
    assert r.iterations == 20 and r.max_change.shape == (20,)
    # from uniform messages, tol 0 (no stop to predict): blocks of 8, 8 and the 4 left
    assert np.flatnonzero(np.isfinite(r.max_change)).tolist() == [7, 15, 19]
    # with a tol: two half blocks first (their changes give the rate), then blocks of 8 and the 4 left
    t = infer(obs, max_iter=20, tol=1e-300, schedule=Checkerboard(block=8))
    assert np.flatnonzero(np.isfinite(t.max_change)).tolist() == [3, 7, 15, 19]
    # warm start: blocks of 1, 2, 4, 8 and the 5 left, measured at iterations 1, 3, 7, 15, 20
    w = infer(obs, max_iter=20, tol=0.0, schedule=Checkerboard(block=8), messages=r.messages)
    assert np.flatnonzero(np.isfinite(w.max_change)).tolist() == [0, 2, 6, 14, 19]


@pytest.mark.parametrize("settings, word", [
    ({"kernel": "gpu"}, "kernel"),
    ({"kernel": "fast", "damping": 0.5}, "damping"),
    ({"block": 0}, "block"),
    ({"kernel": "plain", "block": 4}, "block"),
    ({"damping": 0.5, "freeze": 1e-9}, "freeze"),
])
def test_bad_fast_settings_are_named(settings, word):
    with pytest.raises(InputError, match=word):
        infer(np.full((3, 3), 0.5), schedule=Checkerboard(**settings))


@pytest.mark.parametrize("kwargs, word", [
    ({"schedule": Checkerboard(freeze=1.0)}, "freeze"),  # must be below tol
    ({"threads": 0}, "threads"),
])
def test_bad_fast_arguments_are_named(kwargs, word):
    with pytest.raises(InputError, match=word):
        infer(np.full((3, 3), 0.5), **kwargs)


def test_flooding_and_damping_still_run_on_the_plain_kernels():
    obs = RNG.uniform(0.1, 0.9, (8, 9))
    assert infer(obs, schedule="flooding", max_iter=3).kernel == "plain"
    assert infer(obs, schedule=Checkerboard(damping=0.3), max_iter=3).kernel == "plain"
    assert infer(obs, max_iter=3).kernel == "fast"


def test_timings_and_messages_unpacked_on_first_read():
    obs = np.random.default_rng(5).uniform(0.1, 0.9, (33, 47))
    fast = infer(obs, max_iter=12, tol=0.0, schedule=FAST)
    plain = infer(obs, max_iter=12, tol=0.0, schedule=PLAIN)
    assert set(fast.timings) == {"pack", "iterate", "unpack"} and all(v >= 0 for v in fast.timings.values())
    assert plain.timings == {}
    assert callable(fast.__dict__["_messages"])  # not unpacked yet
    np.testing.assert_allclose(fast.messages, plain.messages, atol=1e-12)
    assert fast.messages is fast.messages  # unpacked once


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_region_from_uniform_messages_matches_the_general_path(dtype):
    # the lean bounded path (no warm start, no hard evidence) against the general one, which a warm start
    # with uniform messages takes: the same messages bit for bit over the same iterations (tol 0: both run
    # max_iter, in passes cut differently), the same beliefs to rounding, and outside the senders' box (plus its
    # one-cell halo) the floored observation
    from crfmap.crf.model.potentials import link_unary

    p = np.random.default_rng(5).uniform(0.05, 0.95, (60, 70))  # its own draw: xdist orders the module's RNG calls
    region = np.zeros(p.shape, bool)
    region[10:30, 15:40] = True
    lean = infer(p, [[3.0, 1.0], [1.0, 3.0]], LINK, region=region, max_iter=150, tol=0.0, dtype=dtype)
    general = infer(p, [[3.0, 1.0], [1.0, 3.0]], LINK, region=region, max_iter=150, tol=0.0, dtype=dtype,
                    messages=np.full((4,) + p.shape, 0.5))
    assert lean.iterations == general.iterations == 150
    np.testing.assert_array_equal(lean.messages, general.messages)
    rounding = 1e-14 if dtype == np.float64 else 1e-6  # odds against probability formula of the same messages
    np.testing.assert_allclose(lean.beliefs.probability, general.beliefs.probability, rtol=0, atol=rounding)
    outside = np.ones(p.shape, bool)
    outside[9:31, 14:41] = False
    floored = np.clip(link_unary(p, LINK), MESSAGE_FLOOR, 1 - MESSAGE_FLOOR)
    np.testing.assert_array_equal(lean.beliefs.probability[outside], floored[outside])
    again = infer(p, [[3.0, 1.0], [1.0, 3.0]], LINK, region=region, max_iter=400, tol=1e-5, dtype=dtype,
                  messages=lean.messages)  # the lazily unpacked messages warm-start a settled run
    assert again.converged and again.iterations == 1


def test_a_float64_region_iterates_in_float32_first_then_confirms_in_float64():
    """The lean bounded path in float64 with tol >= MIXED_MIN_TOL: float32 passes, then float64 iterations from
    their messages until one moves no message by tol. Converged by the same rule, within about tol of the
    float64-only run, and its messages a float64 fixed point to tol (a warm start settles at once)."""
    from crfmap.crf.engine.solve import MIXED_MIN_TOL

    p = np.random.default_rng(6).uniform(0.05, 0.95, (80, 90))
    region = np.zeros(p.shape, bool)
    region[5:70, 10:80] = True
    hidden, tol = [[3.0, 1.0], [1.0, 3.0]], 1e-5
    assert tol >= MIXED_MIN_TOL
    mixed = infer(p, hidden, LINK, region=region, max_iter=400, tol=tol)
    narrow = infer(p, hidden, LINK, region=region, max_iter=400, tol=tol, dtype=np.float32)
    tight = infer(p, hidden, LINK, region=region, max_iter=2000, tol=MIXED_MIN_TOL / 100)  # float64 only
    assert mixed.converged and mixed.max_change[-1] < tol and mixed.messages.dtype == np.float64
    assert mixed.iterations > narrow.iterations  # the float32 run, then at least one float64 iteration
    assert np.abs(mixed.beliefs.probability - tight.beliefs.probability).max() < 20 * tol
    assert np.abs(mixed.beliefs.probability - narrow.beliefs.probability).max() > 0  # not the float32 beliefs
    again = infer(p, hidden, LINK, region=region, max_iter=400, tol=tol, messages=mixed.messages)
    assert again.converged and again.iterations == 1
    # below MIXED_MIN_TOL, float64 only: the tight run is the general path's, iteration for iteration
    general = infer(p, hidden, LINK, region=region, max_iter=2000, tol=MIXED_MIN_TOL / 100,
                    messages=np.full((4,) + p.shape, 0.5))
    np.testing.assert_allclose(tight.beliefs.probability, general.beliefs.probability, rtol=0, atol=1e-7)


def test_segments_of_active_tiles_match_a_loop_over_their_runs():
    def by_loop(block, active):  # the obvious reference: one run of active tiles at a time
        n_ty, n_tx = block.tile_shape()
        segs, nseg, cells = np.zeros((n_ty, (n_tx + 1) // 2, 2), np.int64), np.zeros(n_ty, np.int64), 0
        for ty in range(n_ty):
            tx = 0
            while tx < n_tx:
                if not active[ty, tx]:
                    tx += 1
                    continue
                t1 = tx
                while t1 + 1 < n_tx and active[ty, t1 + 1]:
                    t1 += 1
                x0, x1 = tx * F.TILE_COLS, min((t1 + 1) * F.TILE_COLS, block.w)
                segs[ty, nseg[ty]] = (x0, x1)
                nseg[ty] += 1
                cells += (min((ty + 1) * F.TILE_ROWS, block.h) - ty * F.TILE_ROWS) * (x1 - x0)
                tx = t1 + 1
        return segs, nseg, cells

    rng = np.random.default_rng(7)
    for _ in range(60):
        h, w = rng.integers(1, 200, 2)
        block = F.PackedBlock(h, w, np.float32, np.ones((4, 2, 2)), MESSAGE_FLOOR)
        active = rng.random(block.tile_shape()) < rng.random()
        want, got = by_loop(block, active), block._segments(active)
        assert np.array_equal(want[0], got[0]) and np.array_equal(want[1], got[1]) and want[2] == got[2]


def test_iterations_to_tol_follows_the_measured_rate():
    # halving every iteration: from 1e-3 at iteration 10 to below 1e-5 takes 7 more (2^-7 < 1e-2 < 2^-6)
    assert F._iterations_to_tol((9, 2e-3), (10, 1e-3), 1e-5) == 7
    assert F._iterations_to_tol((0, 0.5), (10, 0.5 * 0.5 ** 10), 0.5 * 0.5 ** 10) == 1  # already below: one more
    assert F._iterations_to_tol((0, 1e-3), (8, 2e-3), 1e-5) > 10 ** 6  # growing: no prediction
    assert F._iterations_to_tol((0, 1e-3), (8, 1e-3), 1e-5) > 10 ** 6  # flat
    assert F._iterations_to_tol((0, 1e-3), (8, 1e-4), 0.0) > 10 ** 6  # tol 0: run to max_iter


@pytest.mark.parametrize("region", [False, True])
def test_the_last_pass_stops_near_where_the_plain_kernel_first_meets_tol(region):
    """Passes grow 1, 2, 4, ... up to block, but the one predicted to reach tol is cut to the measured rate:
    the run stops a few iterations after the plain kernel's first iteration below tol, not up to block - 1."""
    obs = np.clip(RNG.normal(0.5, 0.2, (96, 128)), 0.0, 1.0)
    hidden, tol, block = [[2.0, 1.0], [1.0, 2.0]], 1e-7, 32
    yy, xx = np.mgrid[0:96, 0:128]
    mask = (yy - 48) ** 2 + (xx - 64) ** 2 < 40 ** 2 if region else None
    plain = infer(obs, hidden, max_iter=500, tol=0.0, schedule=PLAIN, region=mask)
    first_below = int(np.argmax(plain.max_change < tol)) + 1  # iterations the plain kernel needs
    fast = infer(obs, hidden, max_iter=500, tol=tol, schedule=Checkerboard(block=block), region=mask)
    assert fast.converged and fast.max_change[-1] < tol
    assert first_below <= fast.iterations <= first_below + 3, (first_below, fast.iterations)
    assert np.abs(fast.beliefs.probability - plain.beliefs.probability).max() < 1e-6


@pytest.mark.parametrize("shape, threads", [((1, 7), 1), ((6, 5), 1), ((97, 61), 1), ((450, 131), 2), ((900, 40), 2)])
@pytest.mark.parametrize("max_iter, block", [(1, 16), (2, 16), (5, 16), (16, 16), (40, 16), (23, 4)])
def test_the_last_pass_writes_the_beliefs_of_every_row_bit_for_bit(shape, threads, max_iter, block):
    """Fused into the last pass (row by row, bands and the gaps between them), the beliefs are the beliefs pass's
    after it: every cell written (NaN before), bit for bit; also after the fused first half-sweep."""
    rng = np.random.default_rng(max_iter * 1000 + shape[0])
    obs = rng.uniform(0.02, 0.98, shape)
    tables = directional_tables([[3.0, 1.0], [1.0, 3.0]])
    for start_uniform in (False, True):
        if start_uniform and max_iter < 2:
            continue  # the pass after start_uniform runs at least two iterations
        block_ = F.PackedBlock(*shape, np.float64, tables, MESSAGE_FLOOR)
        if start_uniform:
            block_.start_uniform(obs, np.eye(2).ravel(), threads)
        else:
            block_.set_unary(obs, np.eye(2))
        out = np.full(shape, np.nan)
        changes = block_.run(max_iter, 0.0, threads, block=block, first=block if start_uniform else 1, beliefs=out)
        assert len(changes) == max_iter and block_.beliefs_written
        np.testing.assert_array_equal(out, block_.beliefs())
    if shape[0] >= 450:  # several bands on two threads, so the gaps wrote rows too
        assert len(block_.band_edges(block, threads)) > 2


def test_beliefs_are_fused_only_into_a_whole_grid_pass_that_ends_the_run():
    obs = np.random.default_rng(8).uniform(0.02, 0.98, (700, 700))  # big enough to freeze tiles
    tables = directional_tables([[3.0, 1.0], [1.0, 3.0]])
    block_ = F.PackedBlock(700, 700, np.float64, tables, MESSAGE_FLOOR)
    block_.set_unary(obs, np.eye(2))
    out = np.full(obs.shape, np.nan)
    changes = block_.run(1000, 1e-6, 2, beliefs=out)
    assert changes[-1] < 1e-6  # converged: its last pass (whole grid) wrote them
    assert block_.beliefs_written
    np.testing.assert_array_equal(out, block_.beliefs())
    masked = F.PackedBlock(700, 700, np.float64, tables, MESSAGE_FLOOR)
    masked.set_unary(obs, np.eye(2))
    masked.set_mask(obs > 0.3)
    untouched = np.full(obs.shape, np.nan)
    masked.run(20, 0.0, 2, beliefs=untouched)
    assert not masked.beliefs_written and np.isnan(untouched).all()  # a mask: the beliefs pass does it
    r = infer(obs, [[3.0, 1.0], [1.0, 3.0]], np.eye(2), max_iter=30, tol=0.0)  # infer's whole grid: fused
    np.testing.assert_allclose(r.beliefs.probability, infer(obs, [[3.0, 1.0], [1.0, 3.0]], np.eye(2), max_iter=30,
                                                            tol=0.0, schedule=PLAIN).beliefs.probability, atol=1e-12)
