"""Cross-validation of a map against itself: folds, the neighbour baseline, the fold loop, leave-one-out."""
import numpy as np
import pytest

from crfstudy.analysis.crossval import (
    NOT_IN_A_FOLD,
    block_folds,
    cross_validate,
    lbp_predictor,
    leave_one_out,
    neighbour_mean,
    neighbour_predictor,
    random_folds,
)
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.assess.metrics import confusion

RNG = np.random.default_rng(2024)


def random_map(shape=(12, 15), unknown=0.3, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.0, 1.0, shape)
    p[rng.uniform(size=shape) < unknown] = UNKNOWN
    return p


def naive_neighbour_mean(p, radius):
    h, w = p.shape
    out = np.full(p.shape, UNKNOWN)
    for y in range(h):
        for x in range(w):
            vals = [p[j, i] for j in range(max(0, y - radius), min(h, y + radius + 1))
                    for i in range(max(0, x - radius), min(w, x + radius + 1))
                    if (j, i) != (y, x) and p[j, i] != UNKNOWN]
            if vals:
                out[y, x] = sum(vals) / len(vals)
    return out


def rooms(shape=(24, 30)):
    """A map of thick (2-cell) walls around free rooms, crisp values, a few unknown cells outside."""
    p = np.full(shape, 0.05)
    p[:2, :] = p[-2:, :] = p[:, :2] = p[:, -2:] = 0.95
    p[:, 14:16] = 0.95
    p[10:14, 14:16] = 0.05  # a door
    p[0, :5] = UNKNOWN
    return p


# --- folds ---------------------------------------------------------------------------------
@pytest.mark.parametrize("k", [2, 3, 10])
def test_random_folds_partition_the_mask_evenly(k):
    mask = RNG.uniform(size=(17, 13)) < 0.6
    f = random_folds(mask, k, seed=1)
    assert np.all(f[~mask] == NOT_IN_A_FOLD)
    assert set(np.unique(f[mask])) == set(range(k))
    sizes = np.bincount(f[mask], minlength=k)
    assert sizes.max() - sizes.min() <= 1


def test_random_folds_are_seeded():
    mask = np.ones((9, 9), bool)
    np.testing.assert_array_equal(random_folds(mask, 4, seed=3), random_folds(mask, 4, seed=3))
    assert np.any(random_folds(mask, 4, seed=3) != random_folds(mask, 4, seed=4))


def test_block_folds_keep_blocks_together():
    mask = RNG.uniform(size=(20, 23)) < 0.7
    block = 4
    f = block_folds(mask, 5, block=block, seed=0)
    assert np.all(f[~mask] == NOT_IN_A_FOLD)
    assert np.all(f[mask] >= 0)
    for by in range(0, 20, block):
        for bx in range(0, 23, block):
            ids = np.unique(f[by:by + block, bx:bx + block][mask[by:by + block, bx:bx + block]])
            assert ids.size <= 1
    blocks_per_fold = [len({(y // block, x // block) for y, x in zip(*np.nonzero(f == k))}) for k in range(5)]
    assert max(blocks_per_fold) - min(blocks_per_fold) <= 1


@pytest.mark.parametrize("bad", [1, 0, 2.5, True])
def test_bad_fold_count_is_refused(bad):
    with pytest.raises(InputError, match="^k: "):
        random_folds(np.ones((3, 3), bool), bad)


def test_more_folds_than_cells_is_refused():
    with pytest.raises(InputError, match="^k: .*only 4 cells"):
        random_folds(np.ones((2, 2), bool), 5)


def test_mask_must_be_boolean():
    with pytest.raises(InputError, match="^mask: .*boolean"):
        random_folds(np.ones((3, 3)), 2)


# --- the neighbour baseline ------------------------------------------------------------------
@pytest.mark.parametrize("radius", [1, 2, 4])
def test_neighbour_mean_matches_naive_loops(radius):
    p = random_map()
    np.testing.assert_allclose(neighbour_mean(p, radius).probability, naive_neighbour_mean(p, radius), atol=1e-12)


def test_neighbour_mean_keeps_grid_metadata():
    g = OccupancyGrid(random_map(), resolution=0.05, origin=(1.0, -2.0, 0.0), frame_id="odom")
    out = neighbour_mean(g, 1)
    assert (out.resolution, out.origin, out.frame_id) == (0.05, (1.0, -2.0, 0.0), "odom")


def test_neighbour_mean_refuses_bad_radius():
    with pytest.raises(InputError, match="^radius: "):
        neighbour_mean(random_map(), 0)
    with pytest.raises(InputError, match="^radius: "):
        neighbour_predictor(1.5)


# --- the fold loop ---------------------------------------------------------------------------
def test_predictor_sees_the_fold_hidden_and_everything_else_unchanged():
    p = random_map(seed=5)
    folds = random_folds(p != UNKNOWN, 4, seed=0)
    seen = []

    def spy(masked, held_out):
        q = masked.probability
        assert np.all(q[held_out] == UNKNOWN)
        np.testing.assert_array_equal(q[~held_out], p[~held_out])
        k = np.unique(folds[held_out])
        assert k.size == 1
        seen.append(int(k[0]))
        return np.full(p.shape, 0.1 + 0.2 * k[0])  # a fold-specific value, to check where it lands

    cv = cross_validate(p, folds, spy, progress=False)
    assert sorted(seen) == [0, 1, 2, 3]
    np.testing.assert_array_equal(cv.held_out, p != UNKNOWN)
    np.testing.assert_allclose(cv.predicted.probability[cv.held_out], 0.1 + 0.2 * folds[cv.held_out])
    assert np.all(cv.predicted.probability[~cv.held_out] == UNKNOWN)
    assert [f["cells"] for f in cv.per_fold] == [int((folds == k).sum()) for k in range(4)]


def test_only_the_requested_folds_run():
    p = random_map(seed=6)
    folds = random_folds(p != UNKNOWN, 5, seed=0)
    cv = cross_validate(p, folds, neighbour_predictor(1), run=[1, 3], progress=False)
    np.testing.assert_array_equal(cv.held_out, np.isin(folds, [1, 3]))
    with pytest.raises(InputError, match="^run: .*\\[7\\]"):
        cross_validate(p, folds, neighbour_predictor(1), run=[1, 7], progress=False)


def test_report_counts_agree_with_metrics_on_the_held_out_cells():
    p = random_map(seed=7)
    cv = cross_validate(p, random_folds(p != UNKNOWN, 3, seed=0), neighbour_predictor(1), progress=False)
    r = cv.report()
    c = confusion(cv.predicted.probability[cv.held_out][None], p[cv.held_out][None])
    assert (r.tp, r.fp, r.fn, r.tn, r.unknown) == (c.tp, c.fp, c.fn, c.tn, c.unknown)
    assert r.tp + r.fp + r.fn + r.tn + r.unknown == int(cv.held_out.sum())
    assert cv.coverage == pytest.approx(1 - r.unknown / cv.held_out.sum())
    fpr, tpr, _ = cv.roc()
    assert fpr[0] == tpr[0] == 0 and fpr[-1] == tpr[-1] == 1


def test_lbp_recovers_held_out_cells_of_a_crisp_map():
    p = rooms()
    cv = cross_validate(p, random_folds(p != UNKNOWN, 10, seed=0), lbp_predictor(margin=2), progress=False)
    r = cv.report()
    assert cv.coverage == 1.0
    assert all(f["converged"] for f in cv.per_fold)
    assert r.accuracy > 0.95 and r.precision > 0.9 and r.recall > 0.9  # majority class alone: 0.68
    # the mistakes are all on label boundaries (room corners, door jambs), never inside a wall or a room
    label = p > 0.5
    padded = np.pad(label, 1, mode="edge")
    boundary = ((padded[1:-1, :-2] != label) | (padded[1:-1, 2:] != label)
                | (padded[:-2, 1:-1] != label) | (padded[2:, 1:-1] != label))
    wrong = cv.held_out & ((cv.predicted.probability > 0.5) != label)
    assert not (wrong & ~boundary).any()


def test_block_holdout_is_harder_than_random_holdout_for_the_baseline():
    """Whole blocks hidden leave block cells with no known neighbour: the 3x3 baseline loses coverage."""
    p = rooms()
    known = p != UNKNOWN
    scattered = cross_validate(p, random_folds(known, 10, seed=0), neighbour_predictor(1), progress=False)
    blocks = cross_validate(p, block_folds(known, 10, block=4, seed=0), neighbour_predictor(1), progress=False)
    assert blocks.coverage < scattered.coverage


def test_folds_on_unknown_cells_are_refused():
    p = random_map(seed=8)
    folds = random_folds(np.ones(p.shape, bool), 3, seed=0)
    with pytest.raises(InputError, match="^folds: .*unknown"):
        cross_validate(p, folds, neighbour_predictor(1), progress=False)


def test_folds_of_the_wrong_shape_are_refused():
    with pytest.raises(InputError, match="^folds: "):
        cross_validate(random_map(), np.zeros((3, 3), int), neighbour_predictor(1), progress=False)


def test_a_predictor_returning_the_wrong_shape_is_named():
    p = random_map(seed=9)
    with pytest.raises(InputError, match="^prediction: "):
        cross_validate(p, random_folds(p != UNKNOWN, 2), lambda m, h: np.zeros((2, 2)), progress=False)


# --- leave one out ---------------------------------------------------------------------------
def test_leave_one_out_equals_single_cell_folds_when_the_window_holds_the_grid():
    p = rooms((10, 12))
    known = np.argwhere(p != UNKNOWN)[:: 7]  # (y, x) of some known cells
    folds = np.full(p.shape, NOT_IN_A_FOLD)
    folds[known[:, 0], known[:, 1]] = np.arange(len(known))
    predict = lbp_predictor(margin=None, tol=1e-10, max_iter=2000)
    cv = cross_validate(p, folds, predict, progress=False)
    loo = leave_one_out(p, known[:, ::-1], predict, window=20)
    np.testing.assert_allclose(loo, cv.predicted.probability[known[:, 0], known[:, 1]], atol=1e-7)


def test_leave_one_out_window_is_centred_on_the_cell():
    p = random_map((15, 15), unknown=0.0, seed=3)
    cells = np.array([[0, 0], [7, 7], [14, 3]])
    got = leave_one_out(p, cells, neighbour_predictor(1), window=1)
    want = naive_neighbour_mean(p, 1)[cells[:, 1], cells[:, 0]]
    np.testing.assert_allclose(got, want)


def test_leave_one_out_refuses_unknown_and_outside_cells():
    p = random_map(seed=4)
    unknown = np.argwhere(p == UNKNOWN)[0][::-1]
    with pytest.raises(InputError, match="^cells: .*unknown"):
        leave_one_out(p, unknown[None], neighbour_predictor(1))
    with pytest.raises(InputError, match="^cells: .*outside"):
        leave_one_out(p, np.array([[99, 0]]), neighbour_predictor(1))


def test_neighbour_mean_is_scipys_window_correlation_to_rounding():
    """scipy.ndimage.correlate sums each window directly; the summed-area table of neighbour_mean rounds differently
    (a mean that is exactly 0.5 can come out a hair off it), so the library would change the cross-validation's
    numbers and the table stays: the two agree to rounding."""
    from scipy import ndimage

    rng = np.random.default_rng(7)
    p = rng.choice([0.05, 0.1, 0.3, 0.5, 0.5, 0.7, 0.9, 0.95], size=(31, 37))
    for radius in (1, 2, 3):
        ring = np.ones((2 * radius + 1,) * 2)
        ring[radius, radius] = 0.0  # the cell itself is left out
        known = (p != 0.5).astype(float)
        total = ndimage.correlate(p * known, ring, mode="constant", cval=0.0)
        count = ndimage.correlate(known, ring, mode="constant", cval=0.0)
        want = np.where(count > 0, total / np.maximum(count, 1), 0.5)
        np.testing.assert_allclose(neighbour_mean(p, radius).probability, want, rtol=0, atol=1e-12)
