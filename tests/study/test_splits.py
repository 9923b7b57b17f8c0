"""Harder scan splits: the masks, and split_by against scan_split."""
import numpy as np
import pytest

from crfmap.assess.scansplit import scan_split, score
from crfmap.errors import InputError
from crfstudy import splits

from box_scans import scans_in_a_box


@pytest.fixture
def corridor():
    """A laser walking along a 3 m x 1 m corridor: 12 scans of 60 beams."""
    n_scans = 12
    poses = np.column_stack([np.linspace(0.3, 2.7, n_scans), np.full(n_scans, 0.5), np.zeros(n_scans)])
    return scans_in_a_box(poses, (0.05, 0.05, 2.95, 0.95), 60)


def test_split_by_alternate_scans_is_scan_split(corridor):
    scans = corridor
    a = splits.split_by(scans, np.arange(len(scans)) % 2 == 0, 0.1)
    b = scan_split(scans, 0.1)
    for name in ("first_hits", "first_passes", "second_hits", "second_passes"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert a.bounds == b.bounds and len(a.first_scans) == len(b.first_scans)


def test_masks():
    assert splits.temporal_halves(4).tolist() == [True, True, False, False]
    assert splits.scan_blocks(7, 3).tolist() == [True] * 3 + [False] * 3 + [True]
    poses = np.array([[0.2, 0.2, 0], [2.2, 0.2, 0], [2.2, 2.2, 0], [-0.2, 0.2, 0]])
    assert splits.spatial_tiles(poses, 2.0).tolist() == [True, False, True, False]


def test_harder_splits_use_every_scan_once_and_score(corridor):
    scans = corridor
    out = splits.harder_splits(scans, 0.1, block=3, tile=1.0)
    whole = scan_split(scans, 0.1)
    for sp in out.values():
        assert np.array_equal(sp.first_hits + sp.second_hits, whole.first_hits + whole.second_hits)
        s = score(sp, {"raw": sp.raw_probability(), "half": np.full(sp.shape, 0.5)}, n_boot=20, reference="raw",
                  metrics=("brier",))
        h = splits.headline(s, "half")
        assert h["all"]["diff"] == pytest.approx(h["all"]["method"] - h["all"]["reference"])
    temporal = out["temporal halves"]
    assert len(temporal.first_scans) == 6 and temporal.first_scans.laser_poses[-1, 0] < 1.5


def test_block_sensitivity_gives_one_interval_per_block_and_group(corridor):
    sp = scan_split(corridor, 0.1)
    out = splits.block_sensitivity(sp, {"raw": sp.raw_probability(), "half": np.full(sp.shape, 0.5)}, (1, 4),
                                   n_boot=20)
    assert sorted(out) == [1, 4] and set(out[1]["half"]) == {"all", "seen", "unseen"}
    lo, hi = out[4]["half"]["all"]
    assert lo <= hi


@pytest.mark.parametrize("call", [lambda s: splits.split_by(s, np.ones(len(s), bool), 0.1),
                                  lambda s: splits.split_by(s, np.ones(3, bool), 0.1),
                                  lambda s: splits.scan_blocks(len(s), 0),
                                  lambda s: splits.spatial_tiles(s.laser_poses, -1.0),
                                  lambda s: splits.temporal_halves(1)])
def test_bad_input(call, corridor):
    with pytest.raises(InputError):
        call(corridor)
